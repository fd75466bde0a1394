/* chair_core.c - see chair_core.h. One call of core_step() is one pass of
 * the sketch's loop(): read the host's frames, decide the pot bytes, and
 * queue HELLO / TELEMETRY frames. */
#include "chair_core.h"

#include "encoder.h"

void core_init(chair_core_t *c, uint8_t reset_flags)
{
    proto_parser_init(&c->parser);
    watchdog_init(&c->watchdog, 0);
    c->host_active = 0;
    c->host_fb = POT_NEUTRAL;
    c->host_lr = POT_NEUTRAL;
    c->cap_fb = POT_MAX_OFFSET;
    c->cap_lr = POT_MAX_OFFSET;
    c->telemetry_period_ms = CORE_TELEMETRY_PERIOD_MS;
    c->watchdog_tripped = 0;
    c->heard_host = 0;
    c->hello_pending = 1;
    c->hello_reason = HELLO_BOOT;
    c->reset_flags = reset_flags;
    c->last_cmd_seq = 0;
    c->tx_seq = 0;
    c->started = 0;
    c->loops = 0;
    c->last_telemetry_ms = 0;
    c->last_hello_ms = 0;
}

/* Act on one valid host frame. `joystick_busy` is set while the joystick is
 * deflected or faulty: drive commands are then acknowledged but not held. */
static void handle_message(chair_core_t *c, const proto_msg_t *m, uint32_t now_ms,
                           uint8_t joystick_busy)
{
    uint8_t period;

    if (m->type >= 0x80u) {
        /* A chair -> host message sent to the chair (a loop-back cable, or a
         * confused host). Valid CRC, but not a command: count and ignore. */
        c->parser.bad_frames = (uint16_t)(c->parser.bad_frames + 1u);
        return;
    }
    watchdog_feed(&c->watchdog, now_ms);
    c->heard_host = 1;
    c->last_cmd_seq = m->seq;

    switch (m->type) {
    case MSG_SET_POTS:
        if (!joystick_busy) {
            c->host_fb = m->u.pots.fb;
            c->host_lr = m->u.pots.lr;
            c->host_active = 1;
            c->watchdog_tripped = 0;
        }
        break;
    case MSG_SET_TWIST:
        if (!joystick_busy) {
            twist_to_pots(m->u.twist.v_mm_s, m->u.twist.w_mrad_s, &c->host_fb,
                          &c->host_lr);
            c->host_active = 1;
            c->watchdog_tripped = 0;
        }
        break;
    case MSG_STOP:
        c->host_fb = POT_NEUTRAL;
        c->host_lr = POT_NEUTRAL;
        c->host_active = 0;
        break;
    case MSG_CONFIGURE:
        c->cap_fb = m->u.config.cap_fb > POT_MAX_OFFSET ? (uint8_t)POT_MAX_OFFSET
                                                        : m->u.config.cap_fb;
        c->cap_lr = m->u.config.cap_lr > POT_MAX_OFFSET ? (uint8_t)POT_MAX_OFFSET
                                                        : m->u.config.cap_lr;
        period = m->u.config.telemetry_period_ms;
        if (period == 0u) {
            period = CORE_TELEMETRY_PERIOD_MS;
        } else if (period < CORE_TELEMETRY_MIN_MS) {
            period = CORE_TELEMETRY_MIN_MS;
        }
        c->telemetry_period_ms = period;
        break;
    case MSG_HELLO_REQUEST:
        c->hello_pending = 1;
        c->hello_reason = HELLO_REQUEST;
        break;
    default: /* MSG_HEARTBEAT: feeding the watchdog is all it does */
        break;
    }
}

static void queue(core_outputs_t *out, const proto_msg_t *m)
{
    size_t n = proto_encode(m, out->tx + out->tx_len,
                            (size_t)(CORE_TX_MAX - out->tx_len));
    out->tx_len = (uint8_t)(out->tx_len + n);
}

void core_step(chair_core_t *c, uint32_t now_ms, const core_inputs_t *in,
               core_outputs_t *out)
{
    proto_msg_t m;
    joy_state_t joy;
    uint8_t i;
    uint8_t flags = 0;
    uint8_t capped = 0;

    out->tx_len = 0;
    if (!c->started) {
        /* First step: start the clocks here, not at the boot time 0. */
        c->started = 1;
        watchdog_init(&c->watchdog, now_ms);
        c->last_telemetry_ms = now_ms - c->telemetry_period_ms;
        c->last_hello_ms = now_ms;
    }
    c->loops = (uint16_t)(c->loops + 1u);

    /* 1. The joystick is read before the host: it must win this very step. */
    joy = joystick_state(in->joy_fb, in->joy_lr);
    if (joy != JOY_NEUTRAL) {
        c->host_active = 0; /* never resume an old command after an override */
    }

    /* 2. Host frames. */
    for (i = 0; i < in->rx_len; i++) {
        if (proto_parser_feed(&c->parser, in->rx[i], &m)) {
            handle_message(c, &m, now_ms, (uint8_t)(joy != JOY_NEUTRAL));
        }
    }

    /* 3. Watchdog: a held command goes stale after 250 ms of silence. */
    if (c->host_active && watchdog_expired(&c->watchdog, now_ms)) {
        c->host_active = 0;
        c->watchdog_tripped = 1;
    }

    /* 4. Decide the pots. */
    if (joy == JOY_FAULT) {
        out->pot_fb = POT_NEUTRAL;
        out->pot_lr = POT_NEUTRAL;
        flags |= FLAG_JOYSTICK_FAULT;
    } else if (joy == JOY_DEFLECTED) {
        out->pot_fb = joystick_to_pot(in->joy_fb); /* eqn 1, no speed cap */
        out->pot_lr = joystick_to_pot(in->joy_lr);
        flags |= FLAG_JOYSTICK_OVERRIDE;
    } else if (c->host_active) {
        out->pot_fb = pot_apply_cap(c->host_fb, c->cap_fb, &capped);
        out->pot_lr = pot_apply_cap(c->host_lr, c->cap_lr, &capped);
        flags |= FLAG_HOST_ACTIVE;
        if (capped) {
            flags |= FLAG_SPEED_CAPPED;
        }
    } else {
        out->pot_fb = POT_NEUTRAL;
        out->pot_lr = POT_NEUTRAL;
    }
    /* Belt and braces: whatever path got here, stay in the safe range. */
    out->pot_fb = pot_clamp(out->pot_fb);
    out->pot_lr = pot_clamp(out->pot_lr);
    if (c->watchdog_tripped) {
        flags |= FLAG_WATCHDOG_TRIPPED;
    }
    if (!in->imu_ok) {
        flags |= FLAG_IMU_FAULT;
    }
    out->flags = flags;

    /* 5. HELLO: at boot, on request, and every 500 ms until the host talks. */
    if (!c->heard_host && !c->hello_pending &&
        (uint32_t)(now_ms - c->last_hello_ms) >= CORE_HELLO_PERIOD_MS) {
        c->hello_pending = 1;
        c->hello_reason = HELLO_PERIODIC;
    }
    if (c->hello_pending) {
        m.type = MSG_HELLO;
        m.seq = c->tx_seq++;
        m.u.hello.protocol_version = PROTO_VERSION;
        m.u.hello.fw_major = FW_VERSION_MAJOR;
        m.u.hello.fw_minor = FW_VERSION_MINOR;
        m.u.hello.fw_patch = FW_VERSION_PATCH;
        m.u.hello.reason = c->hello_reason;
        m.u.hello.reset_flags = c->reset_flags;
        queue(out, &m);
        c->hello_pending = 0;
        c->last_hello_ms = now_ms;
    }

    /* 6. TELEMETRY at the configured period (50 Hz by default). */
    if ((uint32_t)(now_ms - c->last_telemetry_ms) >= c->telemetry_period_ms) {
        proto_telemetry_t *t = &m.u.tel;
        m.type = MSG_TELEMETRY;
        m.seq = c->tx_seq++;
        t->time_ms = now_ms;
        t->enc_left = encoder_delta(in->enc_left, 0);
        t->enc_right = encoder_delta(in->enc_right, 0);
        t->gyro_z_raw = in->imu_ok ? in->gyro_z_raw : 0;
        t->sonar_mm = in->sonar_mm;
        t->joy_fb = in->joy_fb;
        t->joy_lr = in->joy_lr;
        t->pot_fb = out->pot_fb;
        t->pot_lr = out->pot_lr;
        t->flags = flags;
        t->bad_frames = c->parser.bad_frames;
        t->last_cmd_seq = c->last_cmd_seq;
        t->loops = c->loops;
        t->cap_fb = c->cap_fb;
        t->cap_lr = c->cap_lr;
        queue(out, &m);
        c->loops = 0;
        /* Keep the cadence, but do not try to catch up after a long stall. */
        if ((uint32_t)(now_ms - c->last_telemetry_ms) >= 2u * c->telemetry_period_ms) {
            c->last_telemetry_ms = now_ms;
        } else {
            c->last_telemetry_ms += c->telemetry_period_ms;
        }
    }
}
