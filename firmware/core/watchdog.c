/* watchdog.c - see watchdog.h. */
#include "watchdog.h"

void watchdog_init(watchdog_t *w, uint32_t now_ms)
{
    w->last_feed_ms = now_ms;
}

void watchdog_feed(watchdog_t *w, uint32_t now_ms)
{
    w->last_feed_ms = now_ms;
}

uint8_t watchdog_expired(const watchdog_t *w, uint32_t now_ms)
{
    return (uint8_t)((uint32_t)(now_ms - w->last_feed_ms) >= WATCHDOG_TIMEOUT_MS);
}
