/* abcwc_firmware.ino - the Arduino Mega 2560 sketch of the abcwc chair.
 *
 * Thin glue: every pass of loop() reads the world (joystick ADC, encoder
 * counts, gyro, sonar, bytes from the host), hands it to core_step() in
 * firmware/core/chair_core.c, which decides everything, then writes the
 * pot bytes it returns and sends its frames to the host. The wire protocol
 * is described in firmware/PROTOCOL.md. */
#include <Arduino.h>
#include <avr/wdt.h>

#include "board.h"
#include "chair_core.h"

#define SERIAL_BAUD 115200ul
#define GYRO_PERIOD_MS 20u        /* 50 Hz */
#define GYRO_RETRY_MS 1000u       /* re-initialise a missing IMU */
#define SONAR_STALE_MS 300u       /* no pulse for this long: report 0 */
#define POT_REFRESH_MS 100u       /* re-send unchanged pot bytes */

/* Reset cause, saved before main() (and the hardware watchdog switched off,
 * since it stays on across a watchdog reset). */
static uint8_t saved_mcusr __attribute__((section(".noinit")));
void save_mcusr(void) __attribute__((naked, used, section(".init3")));
void save_mcusr(void)
{
    saved_mcusr = MCUSR;
    MCUSR = 0;
    wdt_disable();
}

static chair_core_t core;
static core_inputs_t inputs;
static core_outputs_t outputs;

static uint8_t pot_fb_sent;
static uint8_t pot_lr_sent;
static uint32_t pot_sent_ms;

static uint8_t imu_ok;
static int16_t gyro_z;
static uint32_t gyro_ms;
static uint32_t gyro_retry_ms;

void setup()
{
    /* Neutral first: the pots keep their last wiper value across a reset. */
    spi_board_begin();
    pot_write(POT_CMD_BOTH, POT_NEUTRAL);
    pot_fb_sent = POT_NEUTRAL;
    pot_lr_sent = POT_NEUTRAL;

    Serial.begin(SERIAL_BAUD);
    sensors_begin();
    imu_ok = gyro_begin();
    core_init(&core, saved_mcusr);

    /* The loop takes about 1 ms; 250 ms without one resets the MCU. */
    wdt_enable(WDTO_250MS);
}

static void read_gyro(uint32_t now)
{
    if (imu_ok) {
        if ((uint32_t)(now - gyro_ms) >= GYRO_PERIOD_MS) {
            gyro_ms = now;
            imu_ok = gyro_read_z(&gyro_z);
            if (!imu_ok) {
                gyro_retry_ms = now;
            }
        }
    } else if ((uint32_t)(now - gyro_retry_ms) >= GYRO_RETRY_MS) {
        gyro_retry_ms = now;
        imu_ok = gyro_begin();
    }
}

static uint16_t read_sonar(uint32_t now)
{
    uint16_t mm;
    uint32_t at;
    if (!sonar_read(&mm, &at) || (uint32_t)(now - at) > SONAR_STALE_MS) {
        return 0;
    }
    return mm;
}

static void write_pots(uint32_t now)
{
    uint8_t refresh = (uint8_t)((uint32_t)(now - pot_sent_ms) >= POT_REFRESH_MS);
    if (refresh || outputs.pot_fb != pot_fb_sent) {
        pot_write(POT_CMD_FB, outputs.pot_fb);
        pot_fb_sent = outputs.pot_fb;
    }
    if (refresh || outputs.pot_lr != pot_lr_sent) {
        pot_write(POT_CMD_LR, outputs.pot_lr);
        pot_lr_sent = outputs.pot_lr;
    }
    if (refresh) {
        pot_sent_ms = now;
    }
}

void loop()
{
    static uint8_t rx[64];
    uint8_t n = 0;
    uint32_t now;

    wdt_reset();
    inputs.joy_lr = adc_read(ADC_CH_LR);
    inputs.joy_fb = adc_read(ADC_CH_FB);
    encoders_read(&inputs.enc_left, &inputs.enc_right);
    now = millis();
    read_gyro(now);
    inputs.gyro_z_raw = gyro_z;
    inputs.imu_ok = imu_ok;
    inputs.sonar_mm = read_sonar(now);
    while (n < sizeof rx && Serial.available() > 0) {
        rx[n++] = (uint8_t)Serial.read();
    }
    inputs.rx = rx;
    inputs.rx_len = n;

    core_step(&core, now, &inputs, &outputs);

    write_pots(now);
    /* Never block on a full transmit buffer: a frame that does not fit is
     * dropped (telemetry comes again in 20 ms, HELLO in 500 ms). */
    if (outputs.tx_len > 0u && Serial.availableForWrite() >= (int)outputs.tx_len) {
        Serial.write(outputs.tx, outputs.tx_len);
    }
}
