/* test_core.c - unit tests of firmware/core. Built twice: for the host with
 * the address and undefined-behaviour sanitizers (make test), and for the
 * ATmega2560, run under simavr (make avr-test), where int is 16 bits wide.
 * Also the source of truth for the known-answer values quoted in
 * PROTOCOL.md. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "../core/chair_core.h"
#include "../core/cobs.h"
#include "../core/crc16.h"
#include "../core/encoder.h"
#include "../core/pots.h"
#include "../core/protocol.h"
#include "../core/watchdog.h"
#include "check.h"

#ifdef __AVR__
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#endif

uint32_t check_count;
uint32_t check_failures;

void check_fail(unsigned line, long got, long want)
{
    printf("FAIL line %u: got %ld want %ld\n", line, got, want);
}

static uint32_t rng_state = 12345u;
static uint32_t rng(void)
{
    rng_state = (uint32_t)(rng_state * 1664525ul + 1013904223ul);
    return rng_state >> 8;
}

/* ---------------------------------------------------------------- crc16 */
static void test_crc16(void)
{
    static const uint8_t check_str[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    CHECK_EQ(crc16(check_str, 9), 0x29B1u);
    CHECK_EQ(crc16(check_str, 0), 0xFFFFu);
}

/* ----------------------------------------------------------------- cobs */
static uint8_t cobs_case(const uint8_t *src, size_t n, const uint8_t *want, size_t wn)
{
    uint8_t enc[16];
    uint8_t dec[16];
    size_t dn = 0;
    size_t en = cobs_encode(src, n, enc, sizeof enc);
    if (en != wn || memcmp(enc, want, wn) != 0) {
        return 0;
    }
    if (!cobs_decode(enc, en, dec, sizeof dec, &dn)) {
        return 0;
    }
    return (uint8_t)(dn == n && memcmp(dec, src, n) == 0);
}

static void test_cobs_vectors(void)
{
    static const uint8_t a[] = {0x00}, ae[] = {0x01, 0x01};
    static const uint8_t b[] = {0x00, 0x00}, be[] = {0x01, 0x01, 0x01};
    static const uint8_t c[] = {0x11, 0x22, 0x00, 0x33}, ce[] = {0x03, 0x11, 0x22, 0x02, 0x33};
    static const uint8_t d[] = {0x11, 0x22, 0x33, 0x44}, de[] = {0x05, 0x11, 0x22, 0x33, 0x44};
    static const uint8_t e[] = {0x11, 0x00, 0x00, 0x00}, ee[] = {0x02, 0x11, 0x01, 0x01, 0x01};
    static const uint8_t ze[] = {0x01};
    CHECK(cobs_case(a, 0, ze, 1));
    CHECK(cobs_case(a, 1, ae, 2));
    CHECK(cobs_case(b, 2, be, 3));
    CHECK(cobs_case(c, 4, ce, 5));
    CHECK(cobs_case(d, 4, de, 5));
    CHECK(cobs_case(e, 4, ee, 5));
}

static uint8_t big_src[300];
static uint8_t big_enc[310];
static uint8_t big_dec[300];

static void test_cobs_long(void)
{
    size_t i, n, en, dn;
    /* 254 non-zero bytes: one full group, no trailing code byte. */
    for (i = 0; i < 254u; i++) {
        big_src[i] = (uint8_t)(i + 1u);
    }
    en = cobs_encode(big_src, 254, big_enc, sizeof big_enc);
    CHECK_EQ(en, 255);
    CHECK_EQ(big_enc[0], 0xFF);
    /* 255 non-zero bytes: FF, 254 bytes, 02, 1 byte. */
    big_src[254] = 0xFFu;
    en = cobs_encode(big_src, 255, big_enc, sizeof big_enc);
    CHECK_EQ(en, 257);
    CHECK_EQ(big_enc[255], 0x02);
    /* Random round trips, including runs of zeros and long non-zero runs. */
    for (n = 0; n < 300u; n += 1u + (n / 16u)) {
        for (i = 0; i < n; i++) {
            uint32_t r = rng();
            big_src[i] = (r & 0x300u) == 0u ? 0u : (uint8_t)(r | 1u);
        }
        en = cobs_encode(big_src, n, big_enc, sizeof big_enc);
        CHECK(en >= n + 1u && en <= COBS_MAX_ENCODED(n));
        CHECK(memchr(big_enc, 0, en) == NULL);
        dn = 0;
        CHECK(cobs_decode(big_enc, en, big_dec, sizeof big_dec, &dn));
        CHECK_EQ(dn, n);
        CHECK(memcmp(big_src, big_dec, n) == 0);
    }
}

static void test_cobs_errors(void)
{
    static const uint8_t zero_inside[] = {0x03, 0x11, 0x00};
    static const uint8_t past_end[] = {0x05, 0x11, 0x22};
    static const uint8_t ok[] = {0x05, 0x11, 0x22, 0x33, 0x44};
    uint8_t out[8];
    size_t n = 0;
    CHECK_EQ(cobs_decode(zero_inside, 3, out, sizeof out, &n), 0);
    CHECK_EQ(cobs_decode(past_end, 3, out, sizeof out, &n), 0);
    CHECK_EQ(cobs_decode(ok, 5, out, 3, &n), 0);      /* too small */
    CHECK_EQ(cobs_decode(ok, 5, out, 4, &n), 1);
    CHECK_EQ(n, 4);
    CHECK_EQ(cobs_encode(ok, 5, out, 5), 0);          /* needs 6 */
    CHECK_EQ(cobs_encode(ok, 5, out, 6), 6);
}

/* ------------------------------------------------------------- protocol */
static void test_int_helpers(void)
{
    CHECK_EQ(i16_from_u16(0x8000u), -32768L);
    CHECK_EQ(i16_from_u16(0xFFFFu), -1);
    CHECK_EQ(i16_from_u16(0x7FFFu), 32767);
    CHECK_EQ(i32_from_u32(0xFFFFFFFFul), -1);
    CHECK_EQ(i32_from_u32(0x80000000ul), -2147483647L - 1L);
    CHECK_EQ(i32_from_u32(0x7FFFFFFFul), 2147483647L);
}

static uint8_t feed_all(proto_parser_t *p, const uint8_t *b, size_t n, proto_msg_t *m)
{
    size_t i;
    uint8_t got = 0;
    for (i = 0; i < n; i++) {
        got = (uint8_t)(got + proto_parser_feed(p, b[i], m));
    }
    return got;
}

static void test_known_frames(void)
{
    /* Known answers, also checked by tests/firmware (Python) and quoted in
     * PROTOCOL.md: HEARTBEAT seq 0 and SET_TWIST(500, -300) seq 7. */
    static const uint8_t hb[] = {0x03, 0x01, 0x01, 0x03, 0x9D, 0xC8, 0x00};
    static const uint8_t tw[] = {0x0A, 0x01, 0x03, 0x07, 0xF4, 0x01, 0xD4, 0xFE, 0x25, 0x55,
                                 0x00};
    uint8_t out[PROTO_MAX_WIRE];
    proto_msg_t m;
    size_t n;
    memset(&m, 0, sizeof m);
    m.type = MSG_HEARTBEAT;
    m.seq = 0;
    n = proto_encode(&m, out, sizeof out);
    CHECK_EQ(n, sizeof hb);
    CHECK(memcmp(out, hb, sizeof hb) == 0);
    m.type = MSG_SET_TWIST;
    m.seq = 7;
    m.u.twist.v_mm_s = 500;
    m.u.twist.w_mrad_s = -300;
    n = proto_encode(&m, out, sizeof out);
    CHECK_EQ(n, sizeof tw);
    CHECK(memcmp(out, tw, sizeof tw) == 0);
}

static void test_roundtrip(void)
{
    uint8_t out[PROTO_MAX_WIRE];
    proto_parser_t p;
    proto_msg_t m, r;
    size_t n;

    proto_parser_init(&p);
    memset(&m, 0, sizeof m);
    m.type = MSG_TELEMETRY;
    m.seq = 200;
    m.u.tel.time_ms = 0xFEDCBA98ul;
    m.u.tel.enc_left = -123456789L;
    m.u.tel.enc_right = 2147483647L;
    m.u.tel.gyro_z_raw = -32768;
    m.u.tel.sonar_mm = 5000;
    m.u.tel.joy_fb = 398;
    m.u.tel.joy_lr = 110;
    m.u.tel.pot_fb = 253;
    m.u.tel.pot_lr = 8;
    m.u.tel.flags = 0x3F;
    m.u.tel.bad_frames = 65535u;
    m.u.tel.last_cmd_seq = 255;
    m.u.tel.loops = 1234;
    m.u.tel.cap_fb = 60;
    m.u.tel.cap_lr = 125;
    n = proto_encode(&m, out, sizeof out);
    CHECK(n > 0u && n <= PROTO_MAX_WIRE);
    memset(&r, 0, sizeof r);
    CHECK_EQ(feed_all(&p, out, n, &r), 1);
    CHECK_EQ(r.type, MSG_TELEMETRY);
    CHECK_EQ(r.seq, 200);
    CHECK_EQ(r.u.tel.time_ms, 0xFEDCBA98ul);
    CHECK_EQ(r.u.tel.enc_left, -123456789L);
    CHECK_EQ(r.u.tel.enc_right, 2147483647L);
    CHECK_EQ(r.u.tel.gyro_z_raw, -32768L);
    CHECK_EQ(r.u.tel.sonar_mm, 5000);
    CHECK_EQ(r.u.tel.joy_fb, 398);
    CHECK_EQ(r.u.tel.joy_lr, 110);
    CHECK_EQ(r.u.tel.pot_fb, 253);
    CHECK_EQ(r.u.tel.pot_lr, 8);
    CHECK_EQ(r.u.tel.flags, 0x3F);
    CHECK_EQ(r.u.tel.bad_frames, 65535L);
    CHECK_EQ(r.u.tel.last_cmd_seq, 255);
    CHECK_EQ(r.u.tel.loops, 1234);
    CHECK_EQ(r.u.tel.cap_fb, 60);
    CHECK_EQ(r.u.tel.cap_lr, 125);

    m.type = MSG_SET_TWIST;
    m.seq = 1;
    m.u.twist.v_mm_s = -32768;
    m.u.twist.w_mrad_s = 32767;
    n = proto_encode(&m, out, sizeof out);
    CHECK_EQ(feed_all(&p, out, n, &r), 1);
    CHECK_EQ(r.u.twist.v_mm_s, -32768L);
    CHECK_EQ(r.u.twist.w_mrad_s, 32767);

    m.type = MSG_CONFIGURE;
    m.u.config.cap_fb = 40;
    m.u.config.cap_lr = 30;
    m.u.config.telemetry_period_ms = 50;
    n = proto_encode(&m, out, sizeof out);
    CHECK_EQ(feed_all(&p, out, n, &r), 1);
    CHECK_EQ(r.u.config.cap_fb, 40);
    CHECK_EQ(r.u.config.cap_lr, 30);
    CHECK_EQ(r.u.config.telemetry_period_ms, 50);

    m.type = MSG_HELLO;
    m.u.hello.protocol_version = PROTO_VERSION;
    m.u.hello.fw_major = 1;
    m.u.hello.fw_minor = 2;
    m.u.hello.fw_patch = 3;
    m.u.hello.reason = HELLO_PERIODIC;
    m.u.hello.reset_flags = 0x08;
    n = proto_encode(&m, out, sizeof out);
    CHECK_EQ(feed_all(&p, out, n, &r), 1);
    CHECK_EQ(r.u.hello.fw_patch, 3);
    CHECK_EQ(r.u.hello.reason, HELLO_PERIODIC);
    CHECK_EQ(r.u.hello.reset_flags, 0x08);
    CHECK_EQ(p.bad_frames, 0);

    m.type = 0x42; /* unknown types cannot be encoded */
    CHECK_EQ(proto_encode(&m, out, sizeof out), 0);
    m.type = MSG_STOP;
    CHECK_EQ(proto_encode(&m, out, 4), 0); /* too small */
}

/* Build a raw frame with arbitrary header and payload, stuff and send. */
static size_t raw_frame(uint8_t version, uint8_t type, const uint8_t *payload,
                        uint8_t plen, uint8_t corrupt_crc, uint8_t *wire)
{
    uint8_t raw[64];
    uint16_t crc;
    size_t n;
    raw[0] = version;
    raw[1] = type;
    raw[2] = 9;
    memcpy(raw + 3, payload, plen);
    crc = crc16(raw, (size_t)3u + plen);
    if (corrupt_crc) {
        crc ^= 0x0100u;
    }
    put_u16le(raw + 3 + plen, crc);
    n = cobs_encode(raw, (size_t)5u + plen, wire, 62);
    wire[n] = 0;
    return n + 1u;
}

static void test_bad_frames(void)
{
    static const uint8_t pl[4] = {1, 2, 3, 4};
    uint8_t wire[70];
    proto_parser_t p;
    proto_msg_t m;
    size_t n, i;

    proto_parser_init(&p);
    n = raw_frame(PROTO_VERSION, MSG_SET_POTS, pl, 2, 0, wire);
    CHECK_EQ(feed_all(&p, wire, n, &m), 1);                 /* baseline ok */
    n = raw_frame(PROTO_VERSION, MSG_SET_POTS, pl, 2, 1, wire);
    CHECK_EQ(feed_all(&p, wire, n, &m), 0);                 /* bad CRC */
    CHECK_EQ(p.bad_frames, 1);
    n = raw_frame(2, MSG_SET_POTS, pl, 2, 0, wire);
    CHECK_EQ(feed_all(&p, wire, n, &m), 0);                 /* wrong version */
    CHECK_EQ(p.bad_frames, 2);
    n = raw_frame(PROTO_VERSION, 0x42, pl, 2, 0, wire);
    CHECK_EQ(feed_all(&p, wire, n, &m), 0);                 /* unknown type */
    CHECK_EQ(p.bad_frames, 3);
    n = raw_frame(PROTO_VERSION, MSG_SET_POTS, pl, 3, 0, wire);
    CHECK_EQ(feed_all(&p, wire, n, &m), 0);                 /* wrong length */
    CHECK_EQ(p.bad_frames, 4);
    n = raw_frame(PROTO_VERSION, MSG_SET_POTS, pl, 2, 0, wire);
    wire[n - 3u] = 0;                                        /* truncated */
    CHECK_EQ(feed_all(&p, wire, n - 2u, &m), 0);
    CHECK_EQ(p.bad_frames, 5);
    /* Too long: 100 non-zero bytes then a delimiter is one bad frame. */
    for (i = 0; i < 100u; i++) {
        CHECK_EQ(proto_parser_feed(&p, 0x55, &m), 0);
    }
    CHECK_EQ(proto_parser_feed(&p, 0, &m), 0);
    CHECK_EQ(p.bad_frames, 6);
    /* Empty frames are ignored, and the next good frame still decodes. */
    CHECK_EQ(proto_parser_feed(&p, 0, &m), 0);
    CHECK_EQ(proto_parser_feed(&p, 0, &m), 0);
    CHECK_EQ(p.bad_frames, 6);
    n = raw_frame(PROTO_VERSION, MSG_SET_TWIST, pl, 4, 0, wire);
    CHECK_EQ(feed_all(&p, wire, n, &m), 1);
    CHECK_EQ(m.type, MSG_SET_TWIST);
    CHECK_EQ(m.seq, 9);
    CHECK_EQ(m.u.twist.v_mm_s, 0x0201);
    /* Counter wraps instead of overflowing. */
    p.bad_frames = 65535u;
    CHECK_EQ(proto_parser_feed(&p, 0x07, &m), 0);
    CHECK_EQ(proto_parser_feed(&p, 0x00, &m), 0);
    CHECK_EQ(p.bad_frames, 0);
}

/* ----------------------------------------------------------------- pots */
static void test_eqn1(void)
{
    CHECK_EQ(joystick_to_pot(110), 8);
    CHECK_EQ(joystick_to_pot(254), 130);
    CHECK_EQ(joystick_to_pot(398), 253);
    CHECK_EQ(joystick_to_pot(255), 131);
    CHECK_EQ(joystick_to_pot(0), 8);
    CHECK_EQ(joystick_to_pot(1023), 253);
    CHECK_EQ(joystick_to_pot(65535u), 253);
    CHECK_EQ(pot_clamp(-100000L), POT_MIN);
    CHECK_EQ(pot_clamp(100000L), POT_MAX);
    CHECK_EQ(pot_clamp(128), 128);
}

static void test_joystick_state(void)
{
    CHECK_EQ(joystick_state(254, 254), JOY_NEUTRAL);
    CHECK_EQ(joystick_state(248, 260), JOY_NEUTRAL);
    CHECK_EQ(joystick_state(260, 248), JOY_NEUTRAL);
    CHECK_EQ(joystick_state(247, 254), JOY_DEFLECTED);
    CHECK_EQ(joystick_state(254, 261), JOY_DEFLECTED);
    CHECK_EQ(joystick_state(398, 110), JOY_DEFLECTED);
    CHECK_EQ(joystick_state(60, 450), JOY_DEFLECTED);
    CHECK_EQ(joystick_state(59, 254), JOY_FAULT);
    CHECK_EQ(joystick_state(254, 451), JOY_FAULT);
    CHECK_EQ(joystick_state(0, 0), JOY_FAULT);
    CHECK_EQ(joystick_state(1023, 254), JOY_FAULT);
}

static void twist_case(int16_t v, int16_t w, uint8_t fb, uint8_t lr)
{
    uint8_t f = 0, l = 0;
    twist_to_pots(v, w, &f, &l);
    CHECK_EQ(f, fb);
    CHECK_EQ(l, lr);
}

static void test_velocity_controller(void)
{
    twist_case(0, 0, 128, 128);
    twist_case(1667, 0, 253, 128);
    twist_case(-1667, 0, 8, 128);      /* 128 - 125 = 3, clamped to 8 */
    twist_case(0, 1571, 128, 8);       /* left lowers LR */
    twist_case(0, -1571, 128, 253);
    twist_case(6, 0, 128, 128);        /* rounds to 0: neutral */
    twist_case(7, 0, 131, 128);        /* first step jumps the dead band */
    twist_case(-7, 0, 125, 128);
    twist_case(833, 785, 191, 65);     /* about half: 2 + 61 */
    twist_case(32767, -32768, 253, 253);
    twist_case(-32768, 32767, 8, 8);
    CHECK_EQ(axis_offset(0, 1667), 0);
    CHECK_EQ(axis_offset(1667, 1667), 125);
    CHECK_EQ(axis_offset(-1667, 1667), 125);
    CHECK_EQ(axis_offset(32767, 1667), 2 + 2418);
    CHECK_EQ(axis_offset(2147483647L, 1), 2 + 123000000L);
    CHECK_EQ(axis_offset(-2147483647L - 1L, 1), 2 + 123000000L);
    CHECK_EQ(axis_offset(5, 0), 0);
}

static void test_cap(void)
{
    uint8_t capped = 0;
    CHECK_EQ(pot_apply_cap(253, 50, &capped), 178);
    CHECK_EQ(capped, 1);
    capped = 0;
    CHECK_EQ(pot_apply_cap(8, 50, &capped), 78);
    CHECK_EQ(capped, 1);
    capped = 0;
    CHECK_EQ(pot_apply_cap(130, 125, &capped), 130);
    CHECK_EQ(capped, 0);
    CHECK_EQ(pot_apply_cap(255, 200, &capped), 253);  /* cap > 125 is 125 */
    CHECK_EQ(capped, 1);
    capped = 0;
    CHECK_EQ(pot_apply_cap(0, 125, &capped), 8);      /* safe range */
    CHECK_EQ(capped, 1);
    CHECK_EQ(pot_apply_cap(200, 0, &capped), 128);    /* cap 0: stand still */
}

/* -------------------------------------------------------------- encoder */
static void test_encoder(void)
{
    CHECK_EQ(encoder_step(1, ENC_LEFT_B_HIGH_STEP), -1);
    CHECK_EQ(encoder_step(0, ENC_LEFT_B_HIGH_STEP), 1);
    CHECK_EQ(encoder_step(1, ENC_RIGHT_B_HIGH_STEP), 1);
    CHECK_EQ(encoder_step(0, ENC_RIGHT_B_HIGH_STEP), -1);
    CHECK_EQ(encoder_apply(0xFFFFFFFFul, 1), 0);
    CHECK(encoder_apply(0, -1) == 0xFFFFFFFFul);
    CHECK_EQ(encoder_delta(5, 0xFFFFFFFEul), 7);
    CHECK_EQ(encoder_delta(0xFFFFFFFEul, 5), -7);
    CHECK_EQ(encoder_delta(0x80000000ul, 0), -2147483647L - 1L);
    CHECK_EQ(encoder_delta(0x7FFFFFFFul, 0), 2147483647L);
    CHECK_EQ(encoder_delta(1000, 1000), 0);
}

/* ------------------------------------------------------------- watchdog */
static void test_watchdog(void)
{
    watchdog_t w;
    watchdog_init(&w, 1000);
    CHECK_EQ(watchdog_expired(&w, 1249), 0);
    CHECK_EQ(watchdog_expired(&w, 1250), 1);
    watchdog_feed(&w, 0xFFFFFF00ul);
    CHECK_EQ(watchdog_expired(&w, 0xFFFFFFF0ul), 0);
    CHECK_EQ(watchdog_expired(&w, 0x00000010ul), 1);   /* 272 ms across the wrap */
    watchdog_feed(&w, 0xFFFFFFC0ul);
    CHECK_EQ(watchdog_expired(&w, 0x00000010ul), 0);   /* 80 ms across the wrap */
}

/* ----------------------------------------------------------- chair_core */
typedef struct {
    chair_core_t core;
    core_inputs_t in;
    core_outputs_t out;
    uint8_t rx[80];
    uint8_t seq;
    uint16_t hello;       /* HELLO frames seen */
    uint16_t telemetry;   /* TELEMETRY frames seen */
    uint8_t last_hello_reason;
    proto_telemetry_t tel; /* last telemetry */
    proto_parser_t host;   /* host-side parser of out.tx */
} rig_t;

static rig_t rig;

static void rig_init(uint32_t t0)
{
    memset(&rig, 0, sizeof rig);
    core_init(&rig.core, 0x01);
    proto_parser_init(&rig.host);
    rig.in.joy_fb = 254;
    rig.in.joy_lr = 254;
    rig.in.imu_ok = 1;
    (void)t0;
}

static void rig_send(uint8_t type, int16_t a, int16_t b, uint8_t c)
{
    proto_msg_t m;
    size_t n;
    memset(&m, 0, sizeof m);
    m.type = type;
    m.seq = rig.seq++;
    if (type == MSG_SET_POTS) {
        m.u.pots.fb = (uint8_t)a;
        m.u.pots.lr = (uint8_t)b;
    } else if (type == MSG_SET_TWIST) {
        m.u.twist.v_mm_s = a;
        m.u.twist.w_mrad_s = b;
    } else if (type == MSG_CONFIGURE) {
        m.u.config.cap_fb = (uint8_t)a;
        m.u.config.cap_lr = (uint8_t)b;
        m.u.config.telemetry_period_ms = c;
    }
    n = proto_encode(&m, rig.rx + rig.in.rx_len, sizeof rig.rx - rig.in.rx_len);
    rig.in.rx_len = (uint8_t)(rig.in.rx_len + n);
}

static void rig_step(uint32_t now)
{
    proto_msg_t m;
    uint8_t i;
    rig.in.rx = rig.rx;
    core_step(&rig.core, now, &rig.in, &rig.out);
    rig.in.rx_len = 0;
    CHECK(rig.out.pot_fb >= POT_MIN && rig.out.pot_fb <= POT_MAX);
    CHECK(rig.out.pot_lr >= POT_MIN && rig.out.pot_lr <= POT_MAX);
    for (i = 0; i < rig.out.tx_len; i++) {
        if (proto_parser_feed(&rig.host, rig.out.tx[i], &m)) {
            if (m.type == MSG_HELLO) {
                rig.hello++;
                rig.last_hello_reason = m.u.hello.reason;
            } else if (m.type == MSG_TELEMETRY) {
                rig.telemetry++;
                rig.tel = m.u.tel;
            }
        }
    }
}

static void test_core_boot_and_telemetry(void)
{
    uint32_t t;
    rig_init(0);
    rig_step(5);
    CHECK_EQ(rig.hello, 1);
    CHECK_EQ(rig.last_hello_reason, HELLO_BOOT);
    CHECK_EQ(rig.telemetry, 1);
    CHECK_EQ(rig.out.pot_fb, 128);
    CHECK_EQ(rig.out.pot_lr, 128);
    CHECK_EQ(rig.tel.flags, 0);
    CHECK_EQ(rig.host.bad_frames, 0);
    for (t = 6; t <= 1005u; t++) {
        rig_step(t);
    }
    CHECK_EQ(rig.telemetry, 51);           /* 50 Hz */
    CHECK_EQ(rig.hello, 3);                /* boot, +500 ms, +1000 ms */
    CHECK_EQ(rig.last_hello_reason, HELLO_PERIODIC);
    CHECK_EQ(rig.tel.loops, 20);
    rig_send(MSG_HEARTBEAT, 0, 0, 0);      /* the host speaks: no more HELLOs */
    for (t = 1006; t <= 3000u; t++) {
        rig_step(t);
    }
    CHECK_EQ(rig.hello, 3);
    rig_send(MSG_HELLO_REQUEST, 0, 0, 0);
    rig_step(3001);
    CHECK_EQ(rig.hello, 4);
    CHECK_EQ(rig.last_hello_reason, HELLO_REQUEST);
    CHECK_EQ(rig.tel.last_cmd_seq, 0);     /* telemetry of t=3000 */
    rig_step(3020);
    CHECK_EQ(rig.tel.last_cmd_seq, 1);
}

static void test_core_twist_and_watchdog(void)
{
    uint32_t t;
    rig_init(0);
    rig_step(100);
    rig_send(MSG_SET_TWIST, 1667, 0, 0);
    rig_step(101);
    CHECK_EQ(rig.out.pot_fb, 253);
    CHECK_EQ(rig.out.pot_lr, 128);
    CHECK_EQ(rig.out.flags, FLAG_HOST_ACTIVE);
    /* Heartbeats every 100 ms keep the command alive. */
    for (t = 102; t <= 1101u; t++) {
        if (t % 100u == 0u) {
            rig_send(MSG_HEARTBEAT, 0, 0, 0);
        }
        rig_step(t);
        CHECK_EQ(rig.out.pot_fb, 253);
    }
    /* Last frame at t=1100: still driving at 1349, neutral at 1350. */
    for (t = 1102; t < 1350u; t++) {
        rig_step(t);
    }
    CHECK_EQ(rig.out.pot_fb, 253);
    rig_step(1350);
    CHECK_EQ(rig.out.pot_fb, 128);
    CHECK_EQ(rig.out.pot_lr, 128);
    CHECK_EQ(rig.out.flags, FLAG_WATCHDOG_TRIPPED);
    /* A heartbeat does not bring the command back, nor clear the flag. */
    rig_send(MSG_HEARTBEAT, 0, 0, 0);
    rig_step(1400);
    CHECK_EQ(rig.out.pot_fb, 128);
    CHECK_EQ(rig.out.flags, FLAG_WATCHDOG_TRIPPED);
    /* A fresh twist does. */
    rig_send(MSG_SET_TWIST, -500, 400, 0);
    rig_step(1401);
    CHECK_EQ(rig.out.flags, FLAG_HOST_ACTIVE);
    {
        uint8_t fb, lr;
        twist_to_pots(-500, 400, &fb, &lr);
        CHECK_EQ(rig.out.pot_fb, fb);
        CHECK_EQ(rig.out.pot_lr, lr);
    }
    rig_send(MSG_STOP, 0, 0, 0);
    rig_step(1402);
    CHECK_EQ(rig.out.pot_fb, 128);
    CHECK_EQ(rig.out.pot_lr, 128);
    CHECK_EQ(rig.out.flags, 0);
}

static void test_core_watchdog_wrap(void)
{
    uint32_t t = 0xFFFFFF00ul;
    uint16_t i;
    rig_init(0);
    rig_step(t);
    rig_send(MSG_SET_POTS, 200, 100, 0);
    rig_step(t + 1u);
    CHECK_EQ(rig.out.pot_fb, 200);
    for (i = 2; i < 251u; i++) {
        rig_step(t + i);
    }
    CHECK_EQ(rig.out.pot_fb, 200);         /* 249 ms, across the wrap */
    rig_step(t + 251u);
    CHECK_EQ(rig.out.pot_fb, 128);
}

static void test_core_joystick(void)
{
    rig_init(0);
    rig_step(10);
    rig_send(MSG_SET_POTS, 200, 60, 0);
    rig_step(11);
    CHECK_EQ(rig.out.pot_fb, 200);
    CHECK_EQ(rig.out.pot_lr, 60);
    /* Deflection wins in the very step it is seen, even against a command
     * arriving in the same step. */
    rig.in.joy_fb = 300;
    rig.in.joy_lr = 254;
    rig_send(MSG_SET_POTS, 250, 250, 0);
    rig_step(12);
    CHECK_EQ(rig.out.pot_fb, joystick_to_pot(300));
    CHECK_EQ(rig.out.pot_lr, joystick_to_pot(254));
    CHECK_EQ(rig.out.flags, FLAG_JOYSTICK_OVERRIDE);
    /* The joystick is not speed-capped. */
    rig_send(MSG_CONFIGURE, 10, 10, 0);
    rig.in.joy_fb = 398;
    rig_step(13);
    CHECK_EQ(rig.out.pot_fb, 253);
    /* Release: neutral, the old command does not come back. */
    rig.in.joy_fb = 254;
    rig_step(14);
    CHECK_EQ(rig.out.pot_fb, 128);
    CHECK_EQ(rig.out.pot_lr, 128);
    CHECK_EQ(rig.out.flags, 0);
    /* A new command is capped. */
    rig_send(MSG_SET_POTS, 253, 8, 0);
    rig_step(15);
    CHECK_EQ(rig.out.pot_fb, 138);
    CHECK_EQ(rig.out.pot_lr, 118);
    CHECK_EQ(rig.out.flags, FLAG_HOST_ACTIVE | FLAG_SPEED_CAPPED);
    /* A faulty joystick reading: neutral, whatever the host says. */
    rig.in.joy_lr = 20;
    rig_send(MSG_SET_TWIST, 1000, 0, 0);
    rig_step(16);
    CHECK_EQ(rig.out.pot_fb, 128);
    CHECK_EQ(rig.out.pot_lr, 128);
    CHECK_EQ(rig.out.flags, FLAG_JOYSTICK_FAULT);
    rig.in.joy_lr = 254;
    rig.in.imu_ok = 0;
    rig_step(17);
    CHECK_EQ(rig.out.pot_fb, 128);
    CHECK_EQ(rig.out.flags, FLAG_IMU_FAULT);
}

static void test_core_config_and_counters(void)
{
    uint32_t t;
    uint16_t before;
    static const uint8_t junk[] = {0x12, 0x34, 0x00, 0x03, 0x01, 0x00};
    rig_init(0);
    rig_send(MSG_CONFIGURE, 200, 3, 0);    /* caps clamp to 125; period 0 -> 20 */
    rig_step(0);
    CHECK_EQ(rig.core.cap_fb, 125);
    CHECK_EQ(rig.core.cap_lr, 3);
    CHECK_EQ(rig.core.telemetry_period_ms, 20);
    rig_send(MSG_CONFIGURE, 125, 125, 5); /* period 5 -> 10 */
    rig_step(1);
    CHECK_EQ(rig.core.telemetry_period_ms, 10);
    before = rig.telemetry;
    for (t = 2; t <= 101u; t++) {
        rig_step(t);
    }
    CHECK_EQ(rig.telemetry - before, 10);
    /* Garbage is counted, and shows in telemetry. */
    memcpy(rig.rx, junk, sizeof junk);
    rig.in.rx_len = sizeof junk;
    rig_step(102);
    CHECK_EQ(rig.core.parser.bad_frames, 2);
    rig_step(120);
    CHECK_EQ(rig.tel.bad_frames, 2);
    /* A chair -> host message sent to the chair is counted, not obeyed. */
    {
        proto_msg_t m;
        memset(&m, 0, sizeof m);
        m.type = MSG_HELLO;
        rig.in.rx_len = (uint8_t)proto_encode(&m, rig.rx, sizeof rig.rx);
        rig_step(121);
        CHECK_EQ(rig.core.parser.bad_frames, 3);
    }
    /* SET_POTS outside the safe range is clamped. */
    rig_send(MSG_SET_POTS, 0, 255, 0);
    rig_step(122);
    CHECK_EQ(rig.out.pot_fb, 8);
    CHECK_EQ(rig.out.pot_lr, 253);
    CHECK_EQ(rig.out.flags, FLAG_HOST_ACTIVE | FLAG_SPEED_CAPPED);
}

/* Random frames, garbage and joystick readings: the safety rules hold. */
static void test_core_random(void)
{
    uint16_t i;
    uint32_t t = 0;
    rig_init(0);
    for (i = 0; i < 3000u; i++) {
        uint32_t r = rng();
        uint8_t kind = (uint8_t)(r % 8u);
        t += 1u + (rng() % 40u);
        if (kind == 0u) {
            rig_send(MSG_SET_POTS, (int16_t)(rng() & 0xFFu), (int16_t)(rng() & 0xFFu), 0);
        } else if (kind == 1u) {
            rig_send(MSG_SET_TWIST, (int16_t)(uint16_t)rng(), (int16_t)(uint16_t)rng(), 0);
        } else if (kind == 2u) {
            rig_send(MSG_CONFIGURE, (int16_t)(rng() & 0xFFu), (int16_t)(rng() & 0xFFu),
                     (uint8_t)rng());
        } else if (kind == 3u) {
            uint8_t k, n = (uint8_t)(rng() % 30u);
            for (k = 0; k < n; k++) {
                rig.rx[rig.in.rx_len++] = (uint8_t)rng();
            }
        }
        rig.in.joy_fb = (rng() % 4u == 0u) ? (uint16_t)(rng() % 1024u) : 254u;
        rig.in.joy_lr = (rng() % 4u == 0u) ? (uint16_t)(rng() % 1024u) : 254u;
        rig_step(t);
        switch (joystick_state(rig.in.joy_fb, rig.in.joy_lr)) {
        case JOY_FAULT:
            CHECK_EQ(rig.out.pot_fb, 128);
            CHECK_EQ(rig.out.pot_lr, 128);
            break;
        case JOY_DEFLECTED:
            CHECK_EQ(rig.out.pot_fb, joystick_to_pot(rig.in.joy_fb));
            CHECK_EQ(rig.out.pot_lr, joystick_to_pot(rig.in.joy_lr));
            break;
        default:
            if (!(rig.out.flags & FLAG_HOST_ACTIVE)) {
                CHECK_EQ(rig.out.pot_fb, 128);
                CHECK_EQ(rig.out.pot_lr, 128);
            } else {
                CHECK(rig.out.pot_fb >= 128u - rig.core.cap_fb &&
                      rig.out.pot_fb <= 128u + rig.core.cap_fb);
                CHECK(rig.out.pot_lr >= 128u - rig.core.cap_lr &&
                      rig.out.pot_lr <= 128u + rig.core.cap_lr);
            }
            break;
        }
    }
}

/* ----------------------------------------------------------------- main */
#ifdef __AVR__
static int uart_putchar(char c, FILE *stream)
{
    (void)stream;
    loop_until_bit_is_set(UCSR0A, UDRE0);
    UDR0 = (uint8_t)c;
    return 0;
}
static FILE uart_out = FDEV_SETUP_STREAM(uart_putchar, NULL, _FDEV_SETUP_WRITE);
#endif

int main(void)
{
#ifdef __AVR__
    UBRR0 = 8; /* 115200 baud at 16 MHz (the simulator does not care) */
    UCSR0B = (uint8_t)(1u << TXEN0);
    stdout = &uart_out;
#endif
    test_crc16();
    test_cobs_vectors();
    test_cobs_long();
    test_cobs_errors();
    test_int_helpers();
    test_known_frames();
    test_roundtrip();
    test_bad_frames();
    test_eqn1();
    test_joystick_state();
    test_velocity_controller();
    test_cap();
    test_encoder();
    test_watchdog();
    test_core_boot_and_telemetry();
    test_core_twist_and_watchdog();
    test_core_watchdog_wrap();
    test_core_joystick();
    test_core_config_and_counters();
    test_core_random();
    printf("core tests: %lu checks, %lu failures\n", (unsigned long)check_count,
           (unsigned long)check_failures);
    printf(check_failures == 0u ? "RESULT PASS\n" : "RESULT FAIL\n");
#ifdef __AVR__
    /* Interrupts off + sleep: simavr stops the simulation. */
    cli();
    sleep_enable();
    sleep_cpu();
    for (;;) {
    }
#endif
    return check_failures == 0u ? 0 : 1;
}
