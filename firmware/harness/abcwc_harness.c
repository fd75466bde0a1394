/* abcwc_harness.c - firmware-in-the-loop simulator for the abcwc chair.
 *
 * Runs the real firmware ELF on a simulated ATmega2560 (libsimavr) and plays
 * the chair's electronics around it:
 *   UART0      <-> a pseudo-terminal; its slave path is the first stdout line
 *   SPI        MCP3004 joystick ADC (answers with the joystick values) and
 *              MCP42010 digital pot (records every write, with sim time)
 *   INT3/INT4  encoder quadrature pulses (x1: B level, then A rising)
 *   TWI        an MPU9250 at 0x68 answering WHO_AM_I and gyro z
 *   pin 9      MB1013 sonar: a pulse of 1 us per mm every 100 ms
 * The world is set, and results read, over a line protocol on stdin/stdout
 * described in firmware/harness/README.md. Three clock modes: realtime
 * (paced to the wall clock, times --speed), fast (as fast as it goes) and
 * lockstep (simulated time only moves on "A <ms>", for co-simulation).
 *
 * Build: cc -I/usr/include/simavr abcwc_harness.c -lsimavr -lelf */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <avr_extint.h>
#include <avr_ioport.h>
#include <avr_spi.h>
#include <avr_twi.h>
#include <avr_uart.h>
#include <sim_avr.h>
#include <sim_elf.h>
#include <sim_irq.h>
#include <sim_time.h>

#define F_CPU 16000000u
#define CHUNK_US 1000u          /* simulated time between I/O services */
#define ENC_PHASE_US 20u        /* one encoder count = 3 phases = 60 us */
#define SONAR_PERIOD_US 100000u /* MB1013: 10 readings a second */
#define POT_LOG_MAX 20000u
#define HOST_Q_MAX 65536u
#define MPU_ADDR 0x68u

enum { MODE_REALTIME, MODE_FAST, MODE_LOCKSTEP };

/* ------------------------------------------------------------ the world */
static avr_t *avr;
static FILE *ctl; /* the control channel: our real stdout */
static int mode = MODE_REALTIME;
static double speed = 1.0;

static uint16_t joy_fb = 254, joy_lr = 254;    /* pot scale, as read */
static int16_t gyro_raw;
static int imu_present = 1;
static uint16_t sonar_mm;

typedef struct {
    const char *name;
    char port;               /* both phases are on this port */
    int a_bit;
    int b_bit;
    int b_high_forward;      /* B level that makes the firmware count up */
    int64_t pending;         /* counts still to play (signed) */
    int64_t played;          /* counts played since start (signed) */
    int phase;
    int dir;
    int timer_on;
} wheel_t;
static wheel_t wheels[2];

/* SPI devices. */
static int adc_cs = 1, pot_cs = 1;
static int adc_idx, pot_idx;
static uint16_t adc_value;
static uint8_t pot_cmd, pot_data;
static uint8_t pot_fb = 128, pot_lr = 128;   /* MCP42010 power-on: mid-scale */
static uint64_t pot_writes;
typedef struct {
    uint64_t t_us;
    char ch;
    uint8_t value;
} pot_event_t;
static pot_event_t pot_log[POT_LOG_MAX];
static size_t pot_log_len;
static uint64_t pot_log_dropped;

/* MPU9250 register file. */
static uint8_t mpu_regs[128];
static int mpu_selected, mpu_index;
static uint8_t mpu_ptr;
static avr_irq_t *twi_in;

/* UART <-> pty. */
static int pty_master = -1, pty_slave = -1;
static uint8_t host_q[HOST_Q_MAX];
static size_t host_q_head, host_q_len;
static uint64_t host_rx_total, avr_tx_total, avr_tx_dropped, pty_written;
static int uart_xoff;
static avr_irq_t *uart_in;
static uint8_t out_buf[4096];
static size_t out_len;

static avr_irq_t *spi_in;

/* Time accounting for the speed report. */
static double wall_running_s;
static uint64_t cycles_running;

static uint64_t sim_us(void)
{
    return avr->cycle / (F_CPU / 1000000u);
}

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void reply(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfprintf(ctl, fmt, ap);
    va_end(ap);
    fputc('\n', ctl);
    fflush(ctl);
}

/* ---------------------------------------------------------------- SPI */
static void pot_record(char ch, uint8_t v)
{
    uint8_t *cur = ch == 'F' ? &pot_fb : &pot_lr;
    if (*cur == v) {
        return;
    }
    *cur = v;
    if (pot_log_len < POT_LOG_MAX) {
        pot_log[pot_log_len].t_us = sim_us();
        pot_log[pot_log_len].ch = ch;
        pot_log[pot_log_len].value = v;
        pot_log_len++;
    } else {
        pot_log_dropped++;
    }
}

static void spi_out_hook(avr_irq_t *irq, uint32_t value, void *param)
{
    uint8_t b = (uint8_t)value;
    uint8_t answer = 0xFF;
    (void)irq;
    (void)param;
    if (!adc_cs) {
        /* MCP3004: first byte start/single/channel (bits 4..3 select the
         * channel on a 4-channel part); reply so that the firmware's 16-bit
         * read, masked to 10 bits, is the joystick value. */
        if (adc_idx == 0) {
            unsigned ch = (b >> 3) & 0x3u;
            adc_value = ch == 0 ? joy_lr : ch == 1 ? joy_fb : 0;
            answer = (uint8_t)((adc_value >> 8) & 0x03u);
        } else if (adc_idx == 1) {
            answer = (uint8_t)(adc_value & 0xFFu);
        }
        adc_idx++;
    } else if (!pot_cs) {
        if (pot_idx == 0) {
            pot_cmd = b;
        } else if (pot_idx == 1) {
            pot_data = b;
        }
        pot_idx++;
    }
    avr_raise_irq(spi_in, answer);
}

static void adc_cs_hook(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (adc_cs && !value) {
        adc_idx = 0;
    }
    adc_cs = value != 0;
}

static void pot_cs_hook(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (pot_cs && !value) {
        pot_idx = 0;
    } else if (!pot_cs && value && pot_idx >= 2) {
        /* MCP42010 command byte: xxC1C0xxP1P0; C = 01 writes data. */
        if ((pot_cmd & 0x30u) == 0x10u) {
            pot_writes++;
            if (pot_cmd & 0x02u) {
                pot_record('F', pot_data); /* pot 1: forward/back */
            }
            if (pot_cmd & 0x01u) {
                pot_record('L', pot_data); /* pot 0: left/right */
            }
        }
    }
    pot_cs = value != 0;
}

/* ---------------------------------------------------------------- TWI */
static void twi_hook(avr_irq_t *irq, uint32_t value, void *param)
{
    avr_twi_msg_irq_t v;
    (void)irq;
    (void)param;
    v.u.v = value;
    if (v.u.twi.msg & TWI_COND_STOP) {
        mpu_selected = 0;
    }
    if (v.u.twi.msg & TWI_COND_START) {
        mpu_selected = 0;
        mpu_index = 0;
        if (imu_present && (v.u.twi.addr >> 1) == MPU_ADDR) {
            mpu_selected = 1;
            avr_raise_irq(twi_in, avr_twi_irq_msg(TWI_COND_ACK, v.u.twi.addr, 1));
        }
    }
    if (!mpu_selected) {
        return;
    }
    if (v.u.twi.msg & TWI_COND_WRITE) {
        avr_raise_irq(twi_in, avr_twi_irq_msg(TWI_COND_ACK, v.u.twi.addr, 1));
        if (mpu_index == 0) {
            mpu_ptr = v.u.twi.data & 0x7Fu;
        } else {
            mpu_regs[mpu_ptr] = v.u.twi.data;
            mpu_ptr = (uint8_t)((mpu_ptr + 1u) & 0x7Fu);
        }
        mpu_index++;
    }
    if (v.u.twi.msg & TWI_COND_READ) {
        uint8_t data;
        uint16_t g = (uint16_t)gyro_raw;
        mpu_regs[0x47] = (uint8_t)(g >> 8);
        mpu_regs[0x48] = (uint8_t)(g & 0xFFu);
        mpu_regs[0x75] = 0x71; /* WHO_AM_I of an MPU9250 */
        data = mpu_regs[mpu_ptr];
        mpu_ptr = (uint8_t)((mpu_ptr + 1u) & 0x7Fu);
        avr_raise_irq(twi_in, avr_twi_irq_msg(TWI_COND_READ, v.u.twi.addr, data));
    }
}

/* ----------------------------------------------------------- encoders */
static void drive_pin(char port, int bit, int level);

static avr_cycle_count_t wheel_timer(avr_t *a, avr_cycle_count_t when, void *param)
{
    wheel_t *w = (wheel_t *)param;
    (void)a;
    switch (w->phase) {
    case 0:
        if (w->pending == 0) {
            w->timer_on = 0;
            return 0;
        }
        w->dir = w->pending > 0 ? 1 : -1;
        drive_pin(w->port, w->b_bit, (w->dir > 0) == w->b_high_forward);
        w->phase = 1;
        break;
    case 1:
        drive_pin(w->port, w->a_bit, 1);
        w->phase = 2;
        break;
    default:
        drive_pin(w->port, w->a_bit, 0);
        w->pending -= w->dir;
        w->played += w->dir;
        w->phase = 0;
        break;
    }
    return when + avr_usec_to_cycles(avr, ENC_PHASE_US);
}

static void wheel_add(wheel_t *w, int64_t counts)
{
    w->pending += counts;
    if (!w->timer_on && w->pending != 0) {
        w->timer_on = 1;
        avr_cycle_timer_register_usec(avr, ENC_PHASE_US, wheel_timer, w);
    }
}

/* -------------------------------------------------------------- sonar */
static avr_cycle_count_t sonar_fall(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)a;
    (void)when;
    (void)param;
    drive_pin('H', 6, 0);
    return 0;
}

static avr_cycle_count_t sonar_timer(avr_t *a, avr_cycle_count_t when, void *param)
{
    (void)a;
    (void)param;
    if (sonar_mm > 0) {
        drive_pin('H', 6, 1);
        avr_cycle_timer_register_usec(avr, sonar_mm, sonar_fall, NULL);
    }
    return when + avr_usec_to_cycles(avr, SONAR_PERIOD_US);
}

/* --------------------------------------------------------------- UART */
static void uart_out_hook(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    avr_tx_total++;
    if (out_len < sizeof out_buf) {
        out_buf[out_len++] = (uint8_t)value;
    } else {
        avr_tx_dropped++;
    }
}

static void uart_xon_hook(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (value) {
        uart_xoff = 0;
    }
}

static void uart_xoff_hook(avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    uart_xoff = value != 0;
}

static void uart_flags_quiet(void)
{
    uint32_t f = 0;
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &f);
    f &= ~(uint32_t)(AVR_UART_FLAG_STDIO | AVR_UART_FLAG_POLL_SLEEP);
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &f);
}

/* Move queued host bytes into the AVR's receive FIFO while it has room and
 * the receiver is on (UCSR0B.RXEN0). */
static void feed_uart(void)
{
    const uint8_t ucsr0b = avr->data[0xC1];
    if (!(ucsr0b & (1u << 4))) {
        return;
    }
    while (host_q_len > 0 && !uart_xoff) {
        uint8_t b = host_q[host_q_head];
        host_q_head = (host_q_head + 1u) % HOST_Q_MAX;
        host_q_len--;
        avr_raise_irq(uart_in, b);
    }
}

static void flush_out(void)
{
    size_t off = 0;
    while (off < out_len) {
        ssize_t n = write(pty_master, out_buf + off, out_len - off);
        if (n <= 0) {
            /* Nobody reading (or buffer full): drop, as a real UART would
             * into a closed port. */
            avr_tx_dropped += out_len - off;
            break;
        }
        off += (size_t)n;
        pty_written += (uint64_t)n;
    }
    out_len = 0;
}

static void read_pty(void)
{
    uint8_t buf[512];
    for (;;) {
        ssize_t n = read(pty_master, buf, sizeof buf);
        ssize_t i;
        if (n <= 0) {
            return;
        }
        for (i = 0; i < n; i++) {
            if (host_q_len < HOST_Q_MAX) {
                host_q[(host_q_head + host_q_len) % HOST_Q_MAX] = buf[i];
                host_q_len++;
            }
        }
        host_rx_total += (uint64_t)n;
    }
}

/* ---------------------------------------------------------- running */
static void run_until(avr_cycle_count_t target)
{
    double t0 = wall_now();
    avr_cycle_count_t c0 = avr->cycle;
    while (avr->cycle < target) {
        int st = avr_run(avr);
        if (st == cpu_Done || st == cpu_Crashed) {
            fprintf(stderr, "abcwc_harness: AVR stopped (state %d) at %llu us\n", st,
                    (unsigned long long)sim_us());
            exit(2);
        }
    }
    wall_running_s += wall_now() - t0;
    cycles_running += avr->cycle - c0;
}

/* Advance by `us` of simulated time in CHUNK_US steps, servicing the UART
 * between chunks. In lockstep mode no new host bytes are read meanwhile, so
 * the run is deterministic. */
static void advance(uint64_t us, int read_host)
{
    uint64_t done = 0;
    while (done < us) {
        uint64_t step = us - done < CHUNK_US ? us - done : CHUNK_US;
        if (read_host) {
            read_pty();
        }
        feed_uart();
        run_until(avr->cycle + avr_usec_to_cycles(avr, (uint32_t)step));
        flush_out();
        done += step;
    }
}

static void sleep_noop(avr_t *a, avr_cycle_count_t how_long)
{
    (void)a;
    (void)how_long;
}

/* ------------------------------------------------------------ control */
static int quit;

static void cmd_log(void)
{
    size_t i;
    fprintf(ctl, "L %zu", pot_log_len);
    for (i = 0; i < pot_log_len; i++) {
        fprintf(ctl, " %llu:%c:%u", (unsigned long long)pot_log[i].t_us, pot_log[i].ch,
                pot_log[i].value);
    }
    if (pot_log_dropped) {
        fprintf(ctl, " dropped:%llu", (unsigned long long)pot_log_dropped);
    }
    fputc('\n', ctl);
    fflush(ctl);
    pot_log_len = 0;
    pot_log_dropped = 0;
}

static void handle_line(char *line)
{
    long a = 0, b = 0;
    char word[32];
    char *p = line;
    while (*p == ' ' || *p == '\t') {
        p++;
    }
    if (*p == 0) {
        return;
    }
    if (sscanf(p, "J %ld %ld", &a, &b) == 2) {
        if (a < 0 || a > 1023 || b < 0 || b > 1023) {
            reply("ERR J: joystick values must be 0..1023 (pot scale), got %ld %ld", a, b);
            return;
        }
        joy_fb = (uint16_t)a;
        joy_lr = (uint16_t)b;
        reply("OK");
    } else if (sscanf(p, "E %ld %ld", &a, &b) == 2) {
        wheel_add(&wheels[0], a);
        wheel_add(&wheels[1], b);
        reply("OK");
    } else if (sscanf(p, "G %ld", &a) == 1) {
        if (a < -32768 || a > 32767) {
            reply("ERR G: gyro raw must be -32768..32767, got %ld", a);
            return;
        }
        gyro_raw = (int16_t)a;
        reply("OK");
    } else if (sscanf(p, "I %ld", &a) == 1) {
        imu_present = a != 0;
        reply("OK");
    } else if (sscanf(p, "S %ld", &a) == 1) {
        if (a < 0 || a > 65535) {
            reply("ERR S: sonar mm must be 0..65535, got %ld", a);
            return;
        }
        sonar_mm = (uint16_t)a;
        reply("OK");
    } else if (p[0] == 'A' && (p[1] == ' ' || p[1] == '\t')) {
        double ms = 0;
        long long want = -1;
        int n = sscanf(p + 1, "%lf %lld", &ms, &want);
        if (n < 1 || ms < 0) {
            reply("ERR A: usage A <ms> [host_bytes]");
            return;
        }
        if (mode != MODE_LOCKSTEP) {
            reply("ERR A: only in lockstep mode (M lockstep)");
            return;
        }
        if (n == 2) {
            /* Wait (wall clock, at most 2 s) until the host's bytes are in. */
            double deadline = wall_now() + 2.0;
            read_pty();
            while ((long long)host_rx_total < want && wall_now() < deadline) {
                usleep(200);
                read_pty();
            }
        } else {
            read_pty();
        }
        advance((uint64_t)(ms * 1000.0 + 0.5), 0);
        reply("T %llu %llu", (unsigned long long)sim_us(), (unsigned long long)pty_written);
    } else if (sscanf(p, "M %31s", word) == 1) {
        if (strcmp(word, "realtime") == 0) {
            mode = MODE_REALTIME;
        } else if (strcmp(word, "fast") == 0) {
            mode = MODE_FAST;
        } else if (strcmp(word, "lockstep") == 0) {
            mode = MODE_LOCKSTEP;
        } else {
            reply("ERR M: modes are realtime, fast, lockstep; got %s", word);
            return;
        }
        reply("OK");
    } else if (strncmp(p, "T?", 2) == 0) {
        double ratio = wall_running_s > 0
                           ? (double)cycles_running / F_CPU / wall_running_s
                           : 0.0;
        reply("T %llu %llu %.2f", (unsigned long long)sim_us(),
              (unsigned long long)avr->cycle, ratio);
    } else if (strncmp(p, "P?", 2) == 0) {
        reply("P %u %u %llu", pot_fb, pot_lr, (unsigned long long)pot_writes);
    } else if (strncmp(p, "L?", 2) == 0) {
        cmd_log();
    } else if (strncmp(p, "E?", 2) == 0) {
        reply("E %lld %lld %lld %lld", (long long)wheels[0].played,
              (long long)wheels[1].played, (long long)wheels[0].pending,
              (long long)wheels[1].pending);
    } else if (strncmp(p, "C?", 2) == 0) {
        reply("C %llu %llu %llu %zu", (unsigned long long)host_rx_total,
              (unsigned long long)avr_tx_total, (unsigned long long)avr_tx_dropped,
              host_q_len);
    } else if (p[0] == 'R' && (p[1] == 0 || p[1] == '\n' || p[1] == ' ')) {
        avr_reset(avr);
        uart_flags_quiet();
        host_q_len = 0;
        reply("OK");
    } else if (p[0] == 'Q') {
        quit = 1;
        reply("OK");
    } else {
        reply("ERR unknown command: %s", p);
    }
}

static char line_buf[1024];
static size_t line_len;

/* Read what is available on stdin and run complete lines. Returns -1 at
 * end of input. */
static int read_stdin(void)
{
    char buf[1024];
    ssize_t n = read(STDIN_FILENO, buf, sizeof buf);
    ssize_t i;
    if (n == 0) {
        return -1;
    }
    if (n < 0) {
        return errno == EAGAIN ? 0 : -1;
    }
    for (i = 0; i < n && !quit; i++) {
        if (buf[i] == '\n' || buf[i] == '\r') {
            line_buf[line_len] = 0;
            handle_line(line_buf);
            line_len = 0;
        } else if (line_len + 1 < sizeof line_buf) {
            line_buf[line_len++] = buf[i];
        }
    }
    return 0;
}

static int open_pty(char *path, size_t cap)
{
    struct termios tio;
    const char *name;
    pty_master = posix_openpt(O_RDWR | O_NOCTTY);
    if (pty_master < 0 || grantpt(pty_master) != 0 || unlockpt(pty_master) != 0) {
        return -1;
    }
    name = ptsname(pty_master);
    if (!name) {
        return -1;
    }
    snprintf(path, cap, "%s", name);
    /* Keep a slave open ourselves: reads on the master then never fail with
     * EIO while no host is attached. Raw mode: no echo, no line editing. */
    pty_slave = open(path, O_RDWR | O_NOCTTY);
    if (pty_slave < 0 || tcgetattr(pty_slave, &tio) != 0) {
        return -1;
    }
    cfmakeraw(&tio);
    cfsetispeed(&tio, B115200);
    cfsetospeed(&tio, B115200);
    tcsetattr(pty_slave, TCSANOW, &tio);
    fcntl(pty_master, F_SETFL, fcntl(pty_master, F_GETFL) | O_NONBLOCK);
    return 0;
}

static avr_irq_t *pin_irq(char port, int bit)
{
    return avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ(port), bit);
}

/* Pins the harness drives. Every level we drive is also declared as the
 * port's "external" value, so that when the firmware writes another pin of
 * the same port (simavr 1.6 then re-applies external pulls to all inputs)
 * our level stays, instead of being reset. */
typedef struct {
    char port;
    uint8_t mask;
    uint8_t value;
} driven_port_t;
static driven_port_t driven[3] = {{'D', 0, 0}, {'E', 0, 0}, {'H', 0, 0}};

static void drive_pin(char port, int bit, int level)
{
    avr_ioport_external_t e;
    driven_port_t *d = NULL;
    size_t i;
    for (i = 0; i < sizeof driven / sizeof driven[0]; i++) {
        if (driven[i].port == port) {
            d = &driven[i];
        }
    }
    if (!d) {
        fprintf(stderr, "abcwc_harness: port %c is not driven\n", port);
        exit(3);
    }
    d->mask = (uint8_t)(d->mask | (1u << bit));
    d->value = (uint8_t)(level ? (d->value | (1u << bit)) : (d->value & ~(1u << bit)));
    memset(&e, 0, sizeof e);
    e.name = (unsigned long)port;
    e.mask = d->mask;
    e.value = d->value;
    avr_ioctl(avr, AVR_IOCTL_IOPORT_SET_EXTERNAL(port), &e);
    avr_raise_irq(pin_irq(port, bit), (uint32_t)(level != 0));
}

static void usage(void)
{
    fprintf(stderr,
            "usage: abcwc_harness [--mode realtime|fast|lockstep] [--speed X] firmware.elf\n");
    exit(64);
}

int main(int argc, char **argv)
{
    elf_firmware_t fw;
    const char *elf = NULL;
    char path[256];
    int i;

    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--mode") == 0 && i + 1 < argc) {
            const char *m = argv[++i];
            mode = strcmp(m, "fast") == 0       ? MODE_FAST
                   : strcmp(m, "lockstep") == 0 ? MODE_LOCKSTEP
                   : strcmp(m, "realtime") == 0 ? MODE_REALTIME
                                                : -1;
            if (mode < 0) {
                usage();
            }
        } else if (strcmp(argv[i], "--speed") == 0 && i + 1 < argc) {
            speed = atof(argv[++i]);
            if (speed <= 0) {
                usage();
            }
        } else if (argv[i][0] == '-') {
            usage();
        } else {
            elf = argv[i];
        }
    }
    if (!elf) {
        usage();
    }
    signal(SIGPIPE, SIG_IGN);
    /* simavr prints to stdout; keep stdout for the control channel only. */
    ctl = fdopen(dup(STDOUT_FILENO), "w");
    if (!ctl || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
        perror("abcwc_harness: stdout");
        return 1;
    }

    memset(&fw, 0, sizeof fw);
    if (elf_read_firmware(elf, &fw) != 0) {
        fprintf(stderr, "abcwc_harness: cannot read %s\n", elf);
        return 1;
    }
    avr = avr_make_mcu_by_name("atmega2560");
    if (!avr || avr_init(avr) != 0) {
        fprintf(stderr, "abcwc_harness: no atmega2560 in this simavr\n");
        return 1;
    }
    fw.frequency = F_CPU;
    avr_load_firmware(avr, &fw);
    avr->frequency = F_CPU;
    avr->log = getenv("HARNESS_TRACE") ? LOG_TRACE : LOG_ERROR;
    avr->sleep = sleep_noop;

    /* Edge-triggered encoders: drop simavr's (slow) level-trigger polling. */
    for (i = 0; i < 8; i++) {
        avr_extint_set_strict_lvl_trig(avr, (uint8_t)i, 0);
    }

    /* UART0 <-> pty. */
    if (open_pty(path, sizeof path) != 0) {
        perror("abcwc_harness: pty");
        return 1;
    }
    uart_flags_quiet();
    uart_in = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
                            uart_out_hook, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON),
                            uart_xon_hook, NULL);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF),
                            uart_xoff_hook, NULL);

    /* SPI: ADC chip select pin 10 (PB4), pot chip select pin 8 (PH5). */
    spi_in = avr_io_getirq(avr, AVR_IOCTL_SPI_GETIRQ(0), SPI_IRQ_INPUT);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_SPI_GETIRQ(0), SPI_IRQ_OUTPUT),
                            spi_out_hook, NULL);
    avr_irq_register_notify(pin_irq('B', 4), adc_cs_hook, NULL);
    avr_irq_register_notify(pin_irq('H', 5), pot_cs_hook, NULL);

    /* TWI: the MPU9250. */
    twi_in = avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0), TWI_IRQ_INPUT);
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_TWI_GETIRQ(0), TWI_IRQ_OUTPUT),
                            twi_hook, NULL);

    /* Encoders: left A pin 18 (PD3, INT3), B pin 19 (PD2); right A pin 2
     * (PE4, INT4), B pin 3 (PE5). Forward: left B low, right B high. */
    wheels[0] = (wheel_t){"left", 'D', 3, 2, 0, 0, 0, 0, 0, 0};
    wheels[1] = (wheel_t){"right", 'E', 4, 5, 1, 0, 0, 0, 0, 0};
    drive_pin('D', 3, 0);
    drive_pin('D', 2, 0);
    drive_pin('E', 4, 0);
    drive_pin('E', 5, 0);

    /* Sonar on pin 9 (PH6). */
    drive_pin('H', 6, 0);
    avr_cycle_timer_register_usec(avr, SONAR_PERIOD_US, sonar_timer, NULL);

    fprintf(ctl, "%s\n", path);
    fflush(ctl);
    fcntl(STDIN_FILENO, F_SETFL, fcntl(STDIN_FILENO, F_GETFL) | O_NONBLOCK);

    {
        double wall0 = wall_now();
        uint64_t sim0 = sim_us();
        int last_mode = mode;
        while (!quit) {
            if (mode != last_mode) {
                wall0 = wall_now();
                sim0 = sim_us();
                last_mode = mode;
            }
            if (mode == MODE_LOCKSTEP) {
                fd_set rd;
                FD_ZERO(&rd);
                FD_SET(STDIN_FILENO, &rd);
                if (select(STDIN_FILENO + 1, &rd, NULL, NULL, NULL) < 0 && errno != EINTR) {
                    break;
                }
                if (read_stdin() < 0) {
                    break;
                }
                continue;
            }
            if (read_stdin() < 0) {
                break;
            }
            advance(CHUNK_US, 1);
            if (mode == MODE_REALTIME) {
                double ahead = (double)(sim_us() - sim0) * 1e-6 / speed -
                               (wall_now() - wall0);
                if (ahead > 0.002) {
                    usleep((useconds_t)(ahead * 1e6));
                }
            }
        }
    }
    fprintf(stderr,
            "abcwc_harness: simulated %.3f s; AVR ran at %.2fx real time; "
            "host->avr %llu bytes, avr->host %llu bytes (%llu dropped)\n",
            (double)sim_us() * 1e-6,
            wall_running_s > 0 ? (double)cycles_running / F_CPU / wall_running_s : 0.0,
            (unsigned long long)host_rx_total, (unsigned long long)avr_tx_total,
            (unsigned long long)avr_tx_dropped);
    avr_terminate(avr);
    return 0;
}
