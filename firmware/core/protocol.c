/* protocol.c - frame encode/decode and the streaming parser (PROTOCOL.md). */
#include "protocol.h"

#include "cobs.h"
#include "crc16.h"

void put_u16le(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}

void put_u32le(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)((v >> 8) & 0xFFu);
    p[2] = (uint8_t)((v >> 16) & 0xFFu);
    p[3] = (uint8_t)(v >> 24);
}

uint16_t get_u16le(const uint8_t *p)
{
    return (uint16_t)((uint16_t)p[0] | (uint16_t)((uint16_t)p[1] << 8));
}

uint32_t get_u32le(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

/* Two's complement reinterpretation without implementation-defined casts. */
int16_t i16_from_u16(uint16_t u)
{
    if (u & 0x8000u) {
        return (int16_t)(-(int16_t)(uint16_t)(~u) - 1);
    }
    return (int16_t)u;
}

int32_t i32_from_u32(uint32_t u)
{
    if (u & 0x80000000ul) {
        return -(int32_t)(uint32_t)(~u) - 1;
    }
    return (int32_t)u;
}

int16_t proto_payload_len(uint8_t type)
{
    switch (type) {
    case MSG_HEARTBEAT:     return LEN_HEARTBEAT;
    case MSG_SET_POTS:      return LEN_SET_POTS;
    case MSG_SET_TWIST:     return LEN_SET_TWIST;
    case MSG_STOP:          return LEN_STOP;
    case MSG_CONFIGURE:     return LEN_CONFIGURE;
    case MSG_HELLO_REQUEST: return LEN_HELLO_REQUEST;
    case MSG_HELLO:         return LEN_HELLO;
    case MSG_TELEMETRY:     return LEN_TELEMETRY;
    default:                return -1;
    }
}

static void pack_payload(const proto_msg_t *m, uint8_t *p)
{
    const proto_telemetry_t *t = &m->u.tel;
    switch (m->type) {
    case MSG_SET_POTS:
        p[0] = m->u.pots.fb;
        p[1] = m->u.pots.lr;
        break;
    case MSG_SET_TWIST:
        put_u16le(p, (uint16_t)m->u.twist.v_mm_s);
        put_u16le(p + 2, (uint16_t)m->u.twist.w_mrad_s);
        break;
    case MSG_CONFIGURE:
        p[0] = m->u.config.cap_fb;
        p[1] = m->u.config.cap_lr;
        p[2] = m->u.config.telemetry_period_ms;
        break;
    case MSG_HELLO:
        p[0] = m->u.hello.protocol_version;
        p[1] = m->u.hello.fw_major;
        p[2] = m->u.hello.fw_minor;
        p[3] = m->u.hello.fw_patch;
        p[4] = m->u.hello.reason;
        p[5] = m->u.hello.reset_flags;
        break;
    case MSG_TELEMETRY:
        put_u32le(p, t->time_ms);
        put_u32le(p + 4, (uint32_t)t->enc_left);
        put_u32le(p + 8, (uint32_t)t->enc_right);
        put_u16le(p + 12, (uint16_t)t->gyro_z_raw);
        put_u16le(p + 14, t->sonar_mm);
        put_u16le(p + 16, t->joy_fb);
        put_u16le(p + 18, t->joy_lr);
        p[20] = t->pot_fb;
        p[21] = t->pot_lr;
        p[22] = t->flags;
        put_u16le(p + 23, t->bad_frames);
        p[25] = t->last_cmd_seq;
        put_u16le(p + 26, t->loops);
        p[28] = t->cap_fb;
        p[29] = t->cap_lr;
        break;
    default: /* no payload */
        break;
    }
}

static void unpack_payload(proto_msg_t *m, const uint8_t *p)
{
    proto_telemetry_t *t = &m->u.tel;
    switch (m->type) {
    case MSG_SET_POTS:
        m->u.pots.fb = p[0];
        m->u.pots.lr = p[1];
        break;
    case MSG_SET_TWIST:
        m->u.twist.v_mm_s = i16_from_u16(get_u16le(p));
        m->u.twist.w_mrad_s = i16_from_u16(get_u16le(p + 2));
        break;
    case MSG_CONFIGURE:
        m->u.config.cap_fb = p[0];
        m->u.config.cap_lr = p[1];
        m->u.config.telemetry_period_ms = p[2];
        break;
    case MSG_HELLO:
        m->u.hello.protocol_version = p[0];
        m->u.hello.fw_major = p[1];
        m->u.hello.fw_minor = p[2];
        m->u.hello.fw_patch = p[3];
        m->u.hello.reason = p[4];
        m->u.hello.reset_flags = p[5];
        break;
    case MSG_TELEMETRY:
        t->time_ms = get_u32le(p);
        t->enc_left = i32_from_u32(get_u32le(p + 4));
        t->enc_right = i32_from_u32(get_u32le(p + 8));
        t->gyro_z_raw = i16_from_u16(get_u16le(p + 12));
        t->sonar_mm = get_u16le(p + 14);
        t->joy_fb = get_u16le(p + 16);
        t->joy_lr = get_u16le(p + 18);
        t->pot_fb = p[20];
        t->pot_lr = p[21];
        t->flags = p[22];
        t->bad_frames = get_u16le(p + 23);
        t->last_cmd_seq = p[25];
        t->loops = get_u16le(p + 26);
        t->cap_fb = p[28];
        t->cap_lr = p[29];
        break;
    default:
        break;
    }
}

size_t proto_encode(const proto_msg_t *m, uint8_t *out, size_t cap)
{
    uint8_t raw[PROTO_MAX_RAW];
    int16_t plen = proto_payload_len(m->type);
    size_t n;
    size_t enc;
    uint16_t crc;

    if (plen < 0) {
        return 0;
    }
    raw[0] = PROTO_VERSION;
    raw[1] = m->type;
    raw[2] = m->seq;
    pack_payload(m, raw + PROTO_HEADER_LEN);
    n = PROTO_HEADER_LEN + (size_t)plen;
    crc = crc16(raw, n);
    put_u16le(raw + n, crc);
    n += PROTO_CRC_LEN;

    if (cap < 2u) {
        return 0;
    }
    enc = cobs_encode(raw, n, out, cap - 1u);
    if (enc == 0u) {
        return 0;
    }
    out[enc] = 0u;
    return enc + 1u;
}

uint8_t proto_decode_raw(const uint8_t *raw, size_t len, proto_msg_t *m)
{
    int16_t plen;
    size_t body;

    if (len < PROTO_HEADER_LEN + PROTO_CRC_LEN) {
        return 0;
    }
    body = len - PROTO_CRC_LEN;
    if (crc16(raw, body) != get_u16le(raw + body)) {
        return 0;
    }
    if (raw[0] != PROTO_VERSION) {
        return 0;
    }
    plen = proto_payload_len(raw[1]);
    if (plen < 0 || (size_t)plen != body - PROTO_HEADER_LEN) {
        return 0;
    }
    m->type = raw[1];
    m->seq = raw[2];
    unpack_payload(m, raw + PROTO_HEADER_LEN);
    return 1;
}

void proto_parser_init(proto_parser_t *p)
{
    p->len = 0;
    p->overflow = 0;
    p->bad_frames = 0;
}

uint8_t proto_parser_feed(proto_parser_t *p, uint8_t byte, proto_msg_t *m)
{
    uint8_t raw[PROTO_MAX_RAW];
    size_t raw_len = 0;
    uint8_t ok;

    if (byte != 0u) {
        if (p->len < sizeof p->buf) {
            p->buf[p->len++] = byte;
        } else {
            p->overflow = 1;
        }
        return 0;
    }
    /* A delimiter: judge the frame collected so far. */
    if (p->len == 0u && !p->overflow) {
        return 0;
    }
    ok = !p->overflow &&
         cobs_decode(p->buf, p->len, raw, sizeof raw, &raw_len) &&
         proto_decode_raw(raw, raw_len, m);
    p->len = 0;
    p->overflow = 0;
    if (!ok) {
        p->bad_frames = (uint16_t)(p->bad_frames + 1u);
    }
    return ok;
}
