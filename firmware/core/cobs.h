/* cobs.h - Consistent Overhead Byte Stuffing (Cheshire & Baker, 1999).
 *
 * COBS rewrites a buffer so that it contains no 0x00 byte, at a cost of at
 * most one byte per 254 plus one. On the wire every frame is the COBS image
 * of (header, payload, CRC) followed by a single 0x00 delimiter, so a
 * receiver that loses bytes resynchronises at the next 0x00. */
#ifndef ABCWC_COBS_H
#define ABCWC_COBS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Largest encoded size for a source of n bytes (without the delimiter). */
#define COBS_MAX_ENCODED(n) ((n) + ((n) / 254u) + 1u)

/* Encode src[0..len) into dst (capacity cap). Returns the encoded length
 * (no delimiter written), or 0 if dst is too small. */
size_t cobs_encode(const uint8_t *src, size_t len, uint8_t *dst, size_t cap);

/* Decode src[0..len) (one frame, delimiter removed) into dst (capacity cap).
 * Returns 1 and sets *out_len on success; returns 0 if the input is not a
 * valid COBS image (contains 0x00, a group runs past the end) or dst is too
 * small. */
uint8_t cobs_decode(const uint8_t *src, size_t len, uint8_t *dst, size_t cap,
                    size_t *out_len);

#ifdef __cplusplus
}
#endif

#endif
