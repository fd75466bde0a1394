/* protocol.h - the abcwc serial protocol (see firmware/PROTOCOL.md).
 *
 * A frame before stuffing is
 *     version(1) type(1) seq(1) payload(n) crc16(2, little-endian)
 * with the CRC-16/CCITT-FALSE taken over version..payload. On the wire it is
 * COBS-encoded and followed by one 0x00. All multi-byte fields are
 * little-endian. The Python twin is abcwc/hw/protocol.py; both must agree. */
#ifndef ABCWC_PROTOCOL_H
#define ABCWC_PROTOCOL_H

#include <stddef.h>
#include <stdint.h>

#include "cobs.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PROTO_VERSION 1u

#define FW_VERSION_MAJOR 0u
#define FW_VERSION_MINOR 1u
#define FW_VERSION_PATCH 0u

/* Message types. Host -> chair are 0x01..0x7F, chair -> host 0x80..0xFF. */
#define MSG_HEARTBEAT     0x01u /* no payload */
#define MSG_SET_POTS      0x02u /* fb u8, lr u8 */
#define MSG_SET_TWIST     0x03u /* v_mm_s i16, w_mrad_s i16 */
#define MSG_STOP          0x04u /* no payload */
#define MSG_CONFIGURE     0x05u /* cap_fb u8, cap_lr u8, telemetry_period_ms u8 */
#define MSG_HELLO_REQUEST 0x06u /* no payload */
#define MSG_HELLO         0x81u /* see proto_hello_t */
#define MSG_TELEMETRY     0x82u /* see proto_telemetry_t */

/* Payload sizes (bytes). A frame whose payload size differs is bad. */
#define LEN_HEARTBEAT     0u
#define LEN_SET_POTS      2u
#define LEN_SET_TWIST     4u
#define LEN_STOP          0u
#define LEN_CONFIGURE     3u
#define LEN_HELLO_REQUEST 0u
#define LEN_HELLO         6u
#define LEN_TELEMETRY     30u

#define PROTO_HEADER_LEN  3u
#define PROTO_CRC_LEN     2u
#define PROTO_MAX_PAYLOAD 30u
#define PROTO_MAX_RAW     (PROTO_HEADER_LEN + PROTO_MAX_PAYLOAD + PROTO_CRC_LEN)
/* Encoded bytes on the wire for the largest frame, delimiter included. */
#define PROTO_MAX_WIRE    (COBS_MAX_ENCODED(PROTO_MAX_RAW) + 1u)

/* Telemetry flags (proto_telemetry_t.flags). */
#define FLAG_JOYSTICK_OVERRIDE 0x01u /* joystick deflected: it drives the pots */
#define FLAG_WATCHDOG_TRIPPED  0x02u /* host went quiet for 250 ms: pots neutral */
#define FLAG_JOYSTICK_FAULT    0x04u /* joystick ADC implausible: pots neutral */
#define FLAG_IMU_FAULT         0x08u /* gyro not answering: gyro_z_raw is 0 */
#define FLAG_SPEED_CAPPED      0x10u /* the host command was limited (speed cap or safe range) */
#define FLAG_HOST_ACTIVE       0x20u /* pots follow a host command */

/* HELLO reasons. */
#define HELLO_BOOT     0u
#define HELLO_REQUEST  1u
#define HELLO_PERIODIC 2u

typedef struct {
    uint8_t protocol_version;
    uint8_t fw_major;
    uint8_t fw_minor;
    uint8_t fw_patch;
    uint8_t reason;      /* HELLO_BOOT, HELLO_REQUEST or HELLO_PERIODIC */
    uint8_t reset_flags; /* AVR MCUSR at boot: 1 power-on, 2 external, 4 brown-out, 8 watchdog */
} proto_hello_t;

typedef struct {
    uint32_t time_ms;      /* chair clock, ms since boot (wraps) */
    int32_t enc_left;      /* encoder counts, + when that wheel drives forward (wraps) */
    int32_t enc_right;
    int16_t gyro_z_raw;    /* MPU9250 gyro z, 65.5 LSB per deg/s, + counter-clockwise */
    uint16_t sonar_mm;     /* MB1013 range, mm; 0 = no reading */
    uint16_t joy_fb;       /* joystick ADC, pot scale (centre 254, 110..398) */
    uint16_t joy_lr;
    uint8_t pot_fb;        /* pot bytes the chair is driving (8..253, 128 neutral) */
    uint8_t pot_lr;
    uint8_t flags;         /* FLAG_* */
    uint16_t bad_frames;   /* frames dropped since boot (wraps) */
    uint8_t last_cmd_seq;  /* seq of the last accepted host frame */
    uint16_t loops;        /* main-loop iterations since the previous telemetry */
    uint8_t cap_fb;        /* current speed caps (|byte - 128| allowed) */
    uint8_t cap_lr;
} proto_telemetry_t;

typedef struct {
    uint8_t type;
    uint8_t seq;
    union {
        struct { uint8_t fb; uint8_t lr; } pots;
        struct { int16_t v_mm_s; int16_t w_mrad_s; } twist;
        struct { uint8_t cap_fb; uint8_t cap_lr; uint8_t telemetry_period_ms; } config;
        proto_hello_t hello;
        proto_telemetry_t tel;
    } u;
} proto_msg_t;

/* Payload length of a known type, or -1 for an unknown type. */
int16_t proto_payload_len(uint8_t type);

/* Encode m as a complete wire frame (COBS + trailing 0x00) into out.
 * Returns the number of bytes written, or 0 if m->type is unknown or out is
 * too small (PROTO_MAX_WIRE always suffices). */
size_t proto_encode(const proto_msg_t *m, uint8_t *out, size_t cap);

/* Decode one raw (already un-stuffed) frame. Returns 1 and fills *m if the
 * CRC, version, type and payload length are all right, else 0. */
uint8_t proto_decode_raw(const uint8_t *raw, size_t len, proto_msg_t *m);

/* Streaming frame parser: feed it bytes one at a time. */
typedef struct {
    uint8_t buf[PROTO_MAX_WIRE];
    uint8_t len;
    uint8_t overflow;      /* current frame is longer than any valid frame */
    uint16_t bad_frames;   /* wraps at 65536 */
} proto_parser_t;

void proto_parser_init(proto_parser_t *p);

/* Feed one byte. Returns 1 when it completes a valid frame (then *m is
 * filled), 0 otherwise. A bad frame (bad COBS, CRC, version, type, length
 * or too long) increments bad_frames. Empty frames (0x00 0x00) are ignored
 * and not counted, so a host may send 0x00 to resynchronise. */
uint8_t proto_parser_feed(proto_parser_t *p, uint8_t byte, proto_msg_t *m);

/* Little-endian helpers (also used by the tests). */
void put_u16le(uint8_t *p, uint16_t v);
void put_u32le(uint8_t *p, uint32_t v);
uint16_t get_u16le(const uint8_t *p);
uint32_t get_u32le(const uint8_t *p);
int16_t i16_from_u16(uint16_t u);
int32_t i32_from_u32(uint32_t u);

#ifdef __cplusplus
}
#endif

#endif
