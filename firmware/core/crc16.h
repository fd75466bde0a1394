/* crc16.h - CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection,
 * no final xor). Check value: crc16 of "123456789" is 0x29B1. */
#ifndef ABCWC_CRC16_H
#define ABCWC_CRC16_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CRC16_INIT 0xFFFFu

/* Feed one byte into a running CRC. */
uint16_t crc16_update(uint16_t crc, uint8_t byte);

/* CRC of a whole buffer, starting from CRC16_INIT. */
uint16_t crc16(const uint8_t *data, size_t len);

#ifdef __cplusplus
}
#endif

#endif
