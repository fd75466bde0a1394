/* cobs.c - see cobs.h. Each group is a code byte c (1..255) followed by c-1
 * non-zero data bytes; a group with c < 255 stands for its data plus one 0x00,
 * except the last group of the frame. */
#include "cobs.h"

size_t cobs_encode(const uint8_t *src, size_t len, uint8_t *dst, size_t cap)
{
    size_t out = 1;        /* next free position in dst */
    size_t code_pos = 0;   /* where the current group's code byte goes */
    uint8_t code = 1;      /* 1 + data bytes in the current group */
    size_t i;

    if (cap < 1u) {
        return 0;
    }
    for (i = 0; i < len; i++) {
        if (src[i] != 0u) {
            if (out >= cap) {
                return 0;
            }
            dst[out++] = src[i];
            code++;
        }
        /* A zero ends its group. So does a full group (254 data bytes), which
         * carries no implied zero: open a new group only if more data follows. */
        if (src[i] == 0u || (code == 0xFFu && i + 1u < len)) {
            dst[code_pos] = code;
            code_pos = out;
            if (out >= cap) {
                return 0;
            }
            out++;
            code = 1;
        }
    }
    dst[code_pos] = code;
    return out;
}

uint8_t cobs_decode(const uint8_t *src, size_t len, uint8_t *dst, size_t cap,
                    size_t *out_len)
{
    size_t in = 0;
    size_t out = 0;

    while (in < len) {
        uint8_t code = src[in++];
        uint8_t k;
        if (code == 0u) {
            return 0;
        }
        for (k = 1; k < code; k++) {
            if (in >= len || src[in] == 0u || out >= cap) {
                return 0;
            }
            dst[out++] = src[in++];
        }
        if (code != 0xFFu && in < len) {
            if (out >= cap) {
                return 0;
            }
            dst[out++] = 0;
        }
    }
    *out_len = out;
    return 1;
}
