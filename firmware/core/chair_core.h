/* chair_core.h - the firmware's decision making, free of any hardware.
 *
 * The sketch gathers the world into a core_inputs_t every loop, calls
 * core_step(), writes the pot bytes it gets back to the MCP42010 and sends
 * the bytes in out->tx to the host. Everything that keeps the rider safe is
 * decided here, whatever the host sends:
 *   1. the pots never leave POT_MIN..POT_MAX;
 *   2. a deflected joystick drives the pots (eqn 1) in the same step;
 *   3. an implausible joystick reading puts both pots to neutral;
 *   4. no valid frame for 250 ms drops the host command (pots neutral);
 *   5. host commands are limited by the configured speed cap.
 * After the joystick has taken over, or after a fault or the watchdog, the
 * pots stay neutral until the host sends a new SET_POTS or SET_TWIST. */
#ifndef ABCWC_CHAIR_CORE_H
#define ABCWC_CHAIR_CORE_H

#include <stdint.h>

#include "pots.h"
#include "protocol.h"
#include "watchdog.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CORE_TELEMETRY_PERIOD_MS 20u  /* 50 Hz */
#define CORE_TELEMETRY_MIN_MS 10u
#define CORE_HELLO_PERIOD_MS 500u     /* until the first host frame */
#define CORE_TX_MAX (2u * PROTO_MAX_WIRE)

typedef struct {
    uint16_t joy_fb;      /* MCP3004 channel 1, pot scale */
    uint16_t joy_lr;      /* MCP3004 channel 0, pot scale */
    uint32_t enc_left;    /* raw wrapping counts from the encoder interrupts */
    uint32_t enc_right;
    int16_t gyro_z_raw;
    uint8_t imu_ok;       /* 0 if the last gyro read failed */
    uint16_t sonar_mm;    /* 0 = no recent reading */
    const uint8_t *rx;    /* bytes received from the host since the last step */
    uint8_t rx_len;
} core_inputs_t;

typedef struct {
    uint8_t pot_fb;
    uint8_t pot_lr;
    uint8_t flags;                /* FLAG_* as in telemetry */
    uint8_t tx[CORE_TX_MAX];      /* bytes to send to the host */
    uint8_t tx_len;
} core_outputs_t;

typedef struct {
    proto_parser_t parser;
    watchdog_t watchdog;
    uint8_t host_active;     /* a host command holds the pots */
    uint8_t host_fb;         /* the held command, before the cap */
    uint8_t host_lr;
    uint8_t cap_fb;
    uint8_t cap_lr;
    uint8_t telemetry_period_ms;
    uint8_t watchdog_tripped;
    uint8_t heard_host;      /* any valid frame since boot */
    uint8_t hello_pending;   /* send HELLO with hello_reason next step */
    uint8_t hello_reason;
    uint8_t reset_flags;
    uint8_t last_cmd_seq;
    uint8_t tx_seq;
    uint8_t started;
    uint16_t loops;
    uint32_t last_telemetry_ms;
    uint32_t last_hello_ms;
} chair_core_t;

void core_init(chair_core_t *c, uint8_t reset_flags);
void core_step(chair_core_t *c, uint32_t now_ms, const core_inputs_t *in,
               core_outputs_t *out);

#ifdef __cplusplus
}
#endif

#endif
