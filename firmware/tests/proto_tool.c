/* proto_tool.c - a line-oriented front end to firmware/core for the Python
 * cross-checks in tests/firmware. One command per stdin line, one answer
 * line on stdout:
 *   twist V W              -> "FB LR"          (velocity controller)
 *   joy ADC                -> "POT"            (eqn 1)
 *   cap BYTE CAP           -> "POT"            (speed cap)
 *   enc TYPE SEQ F1 F2 ... -> hex of the wire frame, delimiter included
 *   dec HEX                -> "msg TYPE SEQ F1 F2 ..." for each frame the
 *                             parser accepts, then "bad N" (fresh parser)
 * Field order is the Python dataclass order (abcwc/hw/protocol.py). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../core/pots.h"
#include "../core/protocol.h"

#define MAX_FIELDS 16

static void print_msg(const proto_msg_t *m)
{
    const proto_telemetry_t *t = &m->u.tel;
    printf("msg %u %u", m->type, m->seq);
    switch (m->type) {
    case MSG_SET_POTS:
        printf(" %u %u", m->u.pots.fb, m->u.pots.lr);
        break;
    case MSG_SET_TWIST:
        printf(" %d %d", m->u.twist.v_mm_s, m->u.twist.w_mrad_s);
        break;
    case MSG_CONFIGURE:
        printf(" %u %u %u", m->u.config.cap_fb, m->u.config.cap_lr,
               m->u.config.telemetry_period_ms);
        break;
    case MSG_HELLO:
        printf(" %u %u %u %u %u %u", m->u.hello.protocol_version, m->u.hello.fw_major,
               m->u.hello.fw_minor, m->u.hello.fw_patch, m->u.hello.reason,
               m->u.hello.reset_flags);
        break;
    case MSG_TELEMETRY:
        printf(" %lu %ld %ld %d %u %u %u %u %u %u %u %u %u %u %u", (unsigned long)t->time_ms,
               (long)t->enc_left, (long)t->enc_right, t->gyro_z_raw, t->sonar_mm, t->joy_fb,
               t->joy_lr, t->pot_fb, t->pot_lr, t->flags, t->bad_frames, t->last_cmd_seq,
               t->loops, t->cap_fb, t->cap_lr);
        break;
    default:
        break;
    }
    printf("\n");
}

static void fill_msg(proto_msg_t *m, const long long *f)
{
    proto_telemetry_t *t = &m->u.tel;
    switch (m->type) {
    case MSG_SET_POTS:
        m->u.pots.fb = (uint8_t)f[0];
        m->u.pots.lr = (uint8_t)f[1];
        break;
    case MSG_SET_TWIST:
        m->u.twist.v_mm_s = (int16_t)f[0];
        m->u.twist.w_mrad_s = (int16_t)f[1];
        break;
    case MSG_CONFIGURE:
        m->u.config.cap_fb = (uint8_t)f[0];
        m->u.config.cap_lr = (uint8_t)f[1];
        m->u.config.telemetry_period_ms = (uint8_t)f[2];
        break;
    case MSG_HELLO:
        m->u.hello.protocol_version = (uint8_t)f[0];
        m->u.hello.fw_major = (uint8_t)f[1];
        m->u.hello.fw_minor = (uint8_t)f[2];
        m->u.hello.fw_patch = (uint8_t)f[3];
        m->u.hello.reason = (uint8_t)f[4];
        m->u.hello.reset_flags = (uint8_t)f[5];
        break;
    case MSG_TELEMETRY:
        t->time_ms = (uint32_t)f[0];
        t->enc_left = (int32_t)f[1];
        t->enc_right = (int32_t)f[2];
        t->gyro_z_raw = (int16_t)f[3];
        t->sonar_mm = (uint16_t)f[4];
        t->joy_fb = (uint16_t)f[5];
        t->joy_lr = (uint16_t)f[6];
        t->pot_fb = (uint8_t)f[7];
        t->pot_lr = (uint8_t)f[8];
        t->flags = (uint8_t)f[9];
        t->bad_frames = (uint16_t)f[10];
        t->last_cmd_seq = (uint8_t)f[11];
        t->loops = (uint16_t)f[12];
        t->cap_fb = (uint8_t)f[13];
        t->cap_lr = (uint8_t)f[14];
        break;
    default:
        break;
    }
}

int main(void)
{
    static char line[8192];
    while (fgets(line, sizeof line, stdin)) {
        char *tok = strtok(line, " \t\r\n");
        if (!tok) {
            continue;
        }
        if (strcmp(tok, "twist") == 0) {
            long v = strtol(strtok(NULL, " \t\r\n"), NULL, 10);
            long w = strtol(strtok(NULL, " \t\r\n"), NULL, 10);
            uint8_t fb, lr;
            twist_to_pots((int16_t)v, (int16_t)w, &fb, &lr);
            printf("%u %u\n", fb, lr);
        } else if (strcmp(tok, "joy") == 0) {
            long a = strtol(strtok(NULL, " \t\r\n"), NULL, 10);
            printf("%u\n", joystick_to_pot((uint16_t)a));
        } else if (strcmp(tok, "cap") == 0) {
            long b = strtol(strtok(NULL, " \t\r\n"), NULL, 10);
            long c = strtol(strtok(NULL, " \t\r\n"), NULL, 10);
            uint8_t capped = 0;
            printf("%u\n", pot_apply_cap((uint8_t)b, (uint8_t)c, &capped));
        } else if (strcmp(tok, "enc") == 0) {
            proto_msg_t m;
            long long f[MAX_FIELDS] = {0};
            uint8_t out[PROTO_MAX_WIRE];
            size_t n, i;
            int k = 0;
            char *x;
            memset(&m, 0, sizeof m);
            m.type = (uint8_t)strtol(strtok(NULL, " \t\r\n"), NULL, 10);
            m.seq = (uint8_t)strtol(strtok(NULL, " \t\r\n"), NULL, 10);
            while ((x = strtok(NULL, " \t\r\n")) != NULL && k < MAX_FIELDS) {
                f[k++] = strtoll(x, NULL, 10);
            }
            fill_msg(&m, f);
            n = proto_encode(&m, out, sizeof out);
            for (i = 0; i < n; i++) {
                printf("%02x", out[i]);
            }
            printf("\n");
        } else if (strcmp(tok, "dec") == 0) {
            proto_parser_t p;
            proto_msg_t m;
            char *hex = strtok(NULL, " \t\r\n");
            size_t i, len = hex ? strlen(hex) : 0;
            proto_parser_init(&p);
            for (i = 0; i + 1 < len; i += 2) {
                unsigned b;
                sscanf(hex + i, "%2x", &b);
                if (proto_parser_feed(&p, (uint8_t)b, &m)) {
                    print_msg(&m);
                }
            }
            printf("bad %u\n", p.bad_frames);
        } else {
            printf("error unknown command %s\n", tok);
        }
        fflush(stdout);
    }
    return 0;
}
