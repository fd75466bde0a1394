/* fuzz_parser.c - libFuzzer target for the frame parser and the core.
 *
 * 1. Every byte string is fed to the streaming parser; every frame it
 *    accepts must re-encode to a frame that decodes to the same message.
 * 2. The same bytes drive chair_core as host input, chopped into steps,
 *    with joystick readings taken from the input: the pots must always stay
 *    in the safe range and obey the joystick rules. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../core/chair_core.h"
#include "../core/protocol.h"

static void require(int cond)
{
    if (!cond) {
        abort();
    }
}

static void check_parser(const uint8_t *data, size_t size)
{
    proto_parser_t p, q;
    proto_msg_t m, r;
    uint8_t wire[PROTO_MAX_WIRE];
    size_t i, j, n;
    uint8_t got;

    proto_parser_init(&p);
    for (i = 0; i < size; i++) {
        if (!proto_parser_feed(&p, data[i], &m)) {
            continue;
        }
        n = proto_encode(&m, wire, sizeof wire);
        require(n > 1u && n <= PROTO_MAX_WIRE && wire[n - 1u] == 0u);
        require(memchr(wire, 0, n - 1u) == NULL);
        proto_parser_init(&q);
        got = 0;
        memset(&r, 0, sizeof r);
        for (j = 0; j < n; j++) {
            got = (uint8_t)(got + proto_parser_feed(&q, wire[j], &r));
        }
        require(got == 1u && q.bad_frames == 0u);
        require(r.type == m.type && r.seq == m.seq);
        n = proto_encode(&r, wire, sizeof wire);
        {
            uint8_t wire2[PROTO_MAX_WIRE];
            require(proto_encode(&m, wire2, sizeof wire2) == n);
            require(memcmp(wire, wire2, n) == 0);
        }
    }
}

static void check_core(const uint8_t *data, size_t size)
{
    static chair_core_t c;
    core_inputs_t in;
    core_outputs_t out;
    uint32_t now = 0;
    size_t pos = 0;

    if (size < 2u) {
        return;
    }
    core_init(&c, data[0]);
    now = (uint32_t)data[1] << 24; /* exercise millis() wrap-around */
    memset(&in, 0, sizeof in);
    while (pos < size) {
        uint8_t ctl = data[pos++];
        size_t chunk = (size_t)(ctl & 0x1Fu);
        joy_state_t joy;
        if (chunk > size - pos) {
            chunk = size - pos;
        }
        /* Joystick: mostly centred, sometimes anywhere in 0..1023. */
        in.joy_fb = (ctl & 0x20u) ? (uint16_t)(((uint16_t)ctl << 2) | 3u) : 254u;
        in.joy_lr = (ctl & 0x40u) ? (uint16_t)(1023u - ((uint16_t)ctl << 2)) : 254u;
        in.imu_ok = (uint8_t)(ctl >> 7);
        in.rx = data + pos;
        in.rx_len = (uint8_t)chunk;
        pos += chunk;
        now += (uint32_t)(ctl & 0x0Fu) * 17u;
        core_step(&c, now, &in, &out);
        require(out.pot_fb >= POT_MIN && out.pot_fb <= POT_MAX);
        require(out.pot_lr >= POT_MIN && out.pot_lr <= POT_MAX);
        require(out.tx_len <= CORE_TX_MAX);
        joy = joystick_state(in.joy_fb, in.joy_lr);
        if (joy == JOY_FAULT) {
            require(out.pot_fb == POT_NEUTRAL && out.pot_lr == POT_NEUTRAL);
        } else if (joy == JOY_DEFLECTED) {
            require(out.pot_fb == joystick_to_pot(in.joy_fb));
            require(out.pot_lr == joystick_to_pot(in.joy_lr));
        } else if (!(out.flags & FLAG_HOST_ACTIVE)) {
            require(out.pot_fb == POT_NEUTRAL && out.pot_lr == POT_NEUTRAL);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    check_parser(data, size);
    check_core(data, size);
    return 0;
}
