/* pots.h - joystick and pot scales, the thesis maps, and the velocity
 * controller. Pure integer maths; the Python twins live in
 * abcwc/hw/protocol.py (twist_to_pot_bytes_int, joystick_to_pot_byte).
 *
 * Scales:
 *   joystick ADC, "pot scale": what the firmware reads from the MCP3004 with
 *       a 16-clock transfer (the 10-bit conversion shifted right by one).
 *       Centre 254, full deflection 110..398 (thesis 4.1.5).
 *   pot byte: what is written to the MCP42010 wiper, 0..255, neutral 128.
 *       FB above 128 drives forward; LR below 128 turns left
 *       (counter-clockwise). Only POT_MIN..POT_MAX is ever written. */
#ifndef ABCWC_POTS_H
#define ABCWC_POTS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define POT_NEUTRAL 128u
#define POT_MIN 8u     /* eqn 1 of JOY_MIN */
#define POT_MAX 253u   /* eqn 1 of JOY_MAX */

#define JOY_CENTRE 254u
#define JOY_MIN 110u
#define JOY_MAX 398u
/* Dead band: a channel reading inside 248..260 (inclusive) is neutral. */
#define JOY_DEAD_LO 248u
#define JOY_DEAD_HI 260u
/* Plausible joystick readings. Outside 60..450 the joystick is taken to be
 * disconnected or shorted (a floating or grounded wiper reads near 0 or the
 * rail): 50 counts of margin beyond the full-deflection range. */
#define JOY_FAULT_LO 60u
#define JOY_FAULT_HI 450u

/* Velocity controller constants (thesis table 2, eqn 2 and appendix A.14,
 * recalibrated to integer mm/s and mrad/s). */
#define V_MAX_MM_S 1667      /* 6 km/h */
#define W_MAX_MRAD_S 1571    /* 90 deg/s */
#define MOTOR_DEAD_BAND 2    /* |byte - 128| <= 2 is neutral for the motor controller */
#define POT_SPAN 123         /* offsets 3..125 cover 0..full speed */
#define POT_MAX_OFFSET 125u  /* POT_MAX - POT_NEUTRAL */

typedef enum {
    JOY_NEUTRAL = 0,   /* both channels inside the dead band */
    JOY_DEFLECTED = 1, /* at least one channel outside the dead band */
    JOY_FAULT = 2      /* at least one channel implausible */
} joy_state_t;

/* Clamp any integer into the safe pot range POT_MIN..POT_MAX. */
uint8_t pot_clamp(int32_t value);

/* Thesis eqn 1: pot = (adc - 100) * 0.85, here (adc - 100) * 85 / 100 with
 * truncation, after clamping adc into JOY_MIN..JOY_MAX.
 * 110 -> 8, 254 -> 130, 398 -> 253. */
uint8_t joystick_to_pot(uint16_t adc);

/* Classify a pair of joystick readings. Fault beats deflected. */
joy_state_t joystick_state(uint16_t fb_adc, uint16_t lr_adc);

/* Offset (0 or 3..125, may exceed 125 for |value| > max) for one axis. */
int32_t axis_offset(int32_t value, int32_t max_value);

/* The calibrated velocity controller: twist -> pot bytes, both clamped
 * into POT_MIN..POT_MAX. Positive v drives forward (FB up), positive w
 * turns left, counter-clockwise (LR down), as in ROS REP 103. */
void twist_to_pots(int16_t v_mm_s, int16_t w_mrad_s, uint8_t *fb, uint8_t *lr);

/* Apply a speed cap: |byte - 128| is limited to cap (cap above 125 means
 * 125), then the byte is clamped into POT_MIN..POT_MAX. Sets *capped to 1
 * if the result differs from byte, by the cap or by the safe range (leaves
 * it alone otherwise). */
uint8_t pot_apply_cap(uint8_t byte, uint8_t cap, uint8_t *capped);

#ifdef __cplusplus
}
#endif

#endif
