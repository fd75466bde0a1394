/* encoder.h - encoder sign conventions and wrap-safe tick accounting.
 *
 * Each wheel's encoder is decoded x1: the count changes by one on every
 * rising edge of phase A, in the direction given by phase B at that moment
 * (400 counts per turn of the encoder wheel). With the thesis's wiring
 * (appendix A.18) the two encoders are mirror images, so the same B level
 * means opposite directions on the two sides. The constants below give the
 * count change for "B high"; "B low" is the opposite. They are chosen so that
 * both counts increase when the chair drives forward. If a rebuilt chair
 * counts backwards on one side, flip that side's constant here. */
#ifndef ABCWC_ENCODER_H
#define ABCWC_ENCODER_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define ENC_LEFT_B_HIGH_STEP  (-1) /* left: B high at A's rising edge -> count down */
#define ENC_RIGHT_B_HIGH_STEP (+1) /* right: B high at A's rising edge -> count up */

#define ENC_COUNTS_PER_ENCODER_TURN 400

/* Counts are kept as uint32_t so that incrementing past the top wraps
 * (well defined for unsigned types; signed overflow would be undefined). */

/* The step (+1 or -1) for one rising edge of A, given B's level. */
int8_t encoder_step(uint8_t b_high, int8_t b_high_step);

/* Apply one step to a wrapping count. */
uint32_t encoder_apply(uint32_t count, int8_t step);

/* Signed change from `before` to `now`, correct across a wrap as long as the
 * true change is within +-2^31 counts. */
int32_t encoder_delta(uint32_t now, uint32_t before);

#ifdef __cplusplus
}
#endif

#endif
