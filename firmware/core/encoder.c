/* encoder.c - see encoder.h. */
#include "encoder.h"

#include "protocol.h" /* i32_from_u32 */

int8_t encoder_step(uint8_t b_high, int8_t b_high_step)
{
    return b_high ? b_high_step : (int8_t)(-b_high_step);
}

uint32_t encoder_apply(uint32_t count, int8_t step)
{
    if (step >= 0) {
        return count + (uint32_t)(uint8_t)step;
    }
    return count - (uint32_t)(uint8_t)(-step);
}

int32_t encoder_delta(uint32_t now, uint32_t before)
{
    return i32_from_u32(now - before);
}
