/* watchdog.h - the host-command watchdog (a software timer, not the AVR's
 * hardware watchdog). Any valid frame feeds it. If it is not fed for
 * WATCHDOG_TIMEOUT_MS while a host command holds the pots, the core drops the
 * command and puts both pots to neutral. Times are millis() values and may
 * wrap; all comparisons use unsigned differences. */
#ifndef ABCWC_WATCHDOG_H
#define ABCWC_WATCHDOG_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define WATCHDOG_TIMEOUT_MS 250u

typedef struct {
    uint32_t last_feed_ms;
} watchdog_t;

void watchdog_init(watchdog_t *w, uint32_t now_ms);
void watchdog_feed(watchdog_t *w, uint32_t now_ms);
/* 1 once WATCHDOG_TIMEOUT_MS or more have passed since the last feed. */
uint8_t watchdog_expired(const watchdog_t *w, uint32_t now_ms);

#ifdef __cplusplus
}
#endif

#endif
