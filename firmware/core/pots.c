/* pots.c - see pots.h. */
#include "pots.h"

uint8_t pot_clamp(int32_t value)
{
    if (value < (int32_t)POT_MIN) {
        return (uint8_t)POT_MIN;
    }
    if (value > (int32_t)POT_MAX) {
        return (uint8_t)POT_MAX;
    }
    return (uint8_t)value;
}

uint8_t joystick_to_pot(uint16_t adc)
{
    int32_t a = (int32_t)adc;
    if (a < (int32_t)JOY_MIN) {
        a = JOY_MIN;
    }
    if (a > (int32_t)JOY_MAX) {
        a = JOY_MAX;
    }
    /* eqn 1, in integers; (398 - 100) * 85 = 25330 also fits a 16-bit int,
     * but int32_t keeps it obviously safe. */
    return pot_clamp((a - 100) * 85 / 100);
}

static uint8_t channel_deflected(uint16_t adc)
{
    return (uint8_t)(adc < JOY_DEAD_LO || adc > JOY_DEAD_HI);
}

static uint8_t channel_implausible(uint16_t adc)
{
    return (uint8_t)(adc < JOY_FAULT_LO || adc > JOY_FAULT_HI);
}

joy_state_t joystick_state(uint16_t fb_adc, uint16_t lr_adc)
{
    /* The thesis's checkjoystick() mixes && and || without brackets; the
     * intent, and what we do, is "either axis outside the dead band". */
    if (channel_implausible(fb_adc) || channel_implausible(lr_adc)) {
        return JOY_FAULT;
    }
    if (channel_deflected(fb_adc) || channel_deflected(lr_adc)) {
        return JOY_DEFLECTED;
    }
    return JOY_NEUTRAL;
}

int32_t axis_offset(int32_t value, int32_t max_value)
{
    int32_t mag;
    if (value == 0 || max_value <= 0) {
        return 0;
    }
    /* Saturate first so that -value and value * POT_SPAN cannot overflow;
     * anything this large maps to full scale anyway. */
    if (value > 1000000) {
        value = 1000000;
    } else if (value < -1000000) {
        value = -1000000;
    }
    if (value < 0) {
        value = -value;
    }
    mag = (value * POT_SPAN + max_value / 2) / max_value; /* rounded */
    if (mag == 0) {
        return 0;
    }
    return MOTOR_DEAD_BAND + mag;
}

void twist_to_pots(int16_t v_mm_s, int16_t w_mrad_s, uint8_t *fb, uint8_t *lr)
{
    int32_t v = v_mm_s;
    int32_t w = w_mrad_s;
    int32_t fb_off = axis_offset(v, V_MAX_MM_S);
    int32_t lr_off = axis_offset(w, W_MAX_MRAD_S);
    if (v < 0) {
        fb_off = -fb_off;
    }
    if (w < 0) {
        lr_off = -lr_off;
    }
    *fb = pot_clamp((int32_t)POT_NEUTRAL + fb_off);
    *lr = pot_clamp((int32_t)POT_NEUTRAL - lr_off); /* left (w > 0) lowers LR */
}

uint8_t pot_apply_cap(uint8_t byte, uint8_t cap, uint8_t *capped)
{
    int32_t off = (int32_t)byte - (int32_t)POT_NEUTRAL;
    int32_t c = cap > POT_MAX_OFFSET ? (int32_t)POT_MAX_OFFSET : (int32_t)cap;
    uint8_t result;
    if (off > c) {
        off = c;
    } else if (off < -c) {
        off = -c;
    }
    result = pot_clamp((int32_t)POT_NEUTRAL + off);
    if (result != byte) {
        *capped = 1;
    }
    return result;
}
