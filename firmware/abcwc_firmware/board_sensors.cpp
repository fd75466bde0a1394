/* board_sensors.cpp - encoder interrupts and the sonar pulse timer.
 *
 * Encoders: x1 decoding. On each rising edge of phase A the ISR reads phase
 * B and steps the count by the sign convention in core/encoder.h.
 *
 * Sonar: pin 9 has neither an external nor a pin-change interrupt on the
 * Mega, and pulseIn() would block the loop for up to a sensor cycle (100 ms).
 * Instead Timer2 samples the pin every 25 us; the pulse width is measured to
 * +-25 us, i.e. +-25 mm, without ever blocking the loop. */
#include <Arduino.h>
#include <avr/interrupt.h>
#include <util/atomic.h>

#include "board.h"
#include "encoder.h"

#define SONAR_TICK_US 25u

static volatile uint32_t enc_left;
static volatile uint32_t enc_right;

static volatile uint16_t sonar_width_ticks;
static volatile uint8_t sonar_fresh;

static void left_a_rising(void)
{
    uint8_t b_high = (uint8_t)((PIND & _BV(PD2)) != 0); /* pin 19 */
    enc_left = encoder_apply(enc_left, encoder_step(b_high, ENC_LEFT_B_HIGH_STEP));
}

static void right_a_rising(void)
{
    uint8_t b_high = (uint8_t)((PINE & _BV(PE5)) != 0); /* pin 3 */
    enc_right = encoder_apply(enc_right, encoder_step(b_high, ENC_RIGHT_B_HIGH_STEP));
}

/* 40 kHz sampler of the sonar pin (PH6). */
ISR(TIMER2_COMPA_vect)
{
    static uint16_t ticks;
    static uint16_t rise;
    static uint8_t prev;
    uint8_t level = (uint8_t)(PINH & _BV(PH6));
    ticks++;
    if (level && !prev) {
        rise = ticks;
    } else if (!level && prev) {
        sonar_width_ticks = (uint16_t)(ticks - rise);
        sonar_fresh = 1;
    }
    prev = level;
}

void sensors_begin(void)
{
    pinMode(PIN_ENC_LEFT_A, INPUT);
    pinMode(PIN_ENC_LEFT_B, INPUT);
    pinMode(PIN_ENC_RIGHT_A, INPUT);
    pinMode(PIN_ENC_RIGHT_B, INPUT);
    pinMode(PIN_SONAR, INPUT);
    attachInterrupt(digitalPinToInterrupt(PIN_ENC_LEFT_A), left_a_rising, RISING);
    attachInterrupt(digitalPinToInterrupt(PIN_ENC_RIGHT_A), right_a_rising, RISING);

    /* Timer2: CTC, prescaler 8 (2 MHz), 50 counts = 25 us. */
    TCCR2A = _BV(WGM21);
    TCCR2B = _BV(CS21);
    OCR2A = (uint8_t)(F_CPU / 8u / 1000000u * SONAR_TICK_US - 1u);
    TCNT2 = 0;
    TIMSK2 = _BV(OCIE2A);
}

void encoders_read(uint32_t *left, uint32_t *right)
{
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        *left = enc_left;
        *right = enc_right;
    }
}

uint8_t sonar_read(uint16_t *mm, uint32_t *at_ms)
{
    static uint16_t last_mm;
    static uint32_t last_ms;
    static uint8_t have;
    uint16_t width = 0;
    uint8_t fresh;
    ATOMIC_BLOCK(ATOMIC_RESTORESTATE)
    {
        fresh = sonar_fresh;
        width = sonar_width_ticks;
        sonar_fresh = 0;
    }
    /* Widths above 60 ms are not a sonar echo (the MB1013 tops out near
     * 5 m = 5 ms); ignore them. */
    if (fresh && width <= 60000u / SONAR_TICK_US) {
        last_mm = (uint16_t)(width * SONAR_TICK_US);
        last_ms = millis();
        have = 1;
    }
    *mm = last_mm;
    *at_ms = last_ms;
    return have;
}
