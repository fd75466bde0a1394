/* check.h - a tiny test framework that runs both on the host and on the
 * ATmega2560 (under simavr). Failures print the line number and the two
 * values; expression strings are left out to save the AVR's 8 KB of RAM. */
#ifndef ABCWC_CHECK_H
#define ABCWC_CHECK_H

#include <stdint.h>
#include <stdio.h>

extern uint32_t check_count;
extern uint32_t check_failures;

void check_fail(unsigned line, long got, long want);

#define CHECK_EQ(got, want)                                 \
    do {                                                    \
        long check_got_ = (long)(got);                      \
        long check_want_ = (long)(want);                    \
        check_count++;                                      \
        if (check_got_ != check_want_) {                    \
            check_failures++;                               \
            check_fail(__LINE__, check_got_, check_want_);  \
        }                                                   \
    } while (0)

#define CHECK(cond) CHECK_EQ(!!(cond), 1)

#endif
