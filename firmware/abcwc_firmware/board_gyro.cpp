/* board_gyro.cpp - the MPU9250's gyro z over raw TWI (I2C), polled, with a
 * time limit on every wait so that a stuck bus can never stall the loop.
 * Registers from the MPU-9250 register map (rev 1.6). */
#include <Arduino.h>
#include <avr/interrupt.h>
#include <util/twi.h>

#include "board.h"
#include "protocol.h" /* i16_from_u16 */

#define REG_SMPLRT_DIV 0x19u
#define REG_CONFIG 0x1Au
#define REG_GYRO_CONFIG 0x1Bu
#define REG_GYRO_ZOUT_H 0x47u
#define REG_PWR_MGMT_1 0x6Bu
#define REG_WHO_AM_I 0x75u

#define TWI_WAIT_US 1000u

/* Each bus operation is started by writing TWCR with TWINT set; its end is
 * signalled by the TWI interrupt, whose handler saves the status and turns
 * the interrupt off again (TWINT stays set until the next operation). This
 * works on the chip and also under simavr, whose TWINT flag reads back set
 * right after it is written, so polling TWINT is not reliable there. */
static volatile uint8_t twi_done;
static volatile uint8_t twi_status;

ISR(TWI_vect)
{
    twi_status = TW_STATUS;
    TWCR = _BV(TWEN); /* TWIE off; writing 0 to TWINT leaves it set */
    twi_done = 1;
}

/* Start one operation (extra TWCR bits in `bits`) and wait for its status.
 * Returns the TWI status, or 0xFF on time-out. */
static uint8_t twi_op(uint8_t bits)
{
    uint32_t start = micros();
    twi_done = 0;
    TWCR = (uint8_t)(_BV(TWINT) | _BV(TWEN) | _BV(TWIE) | bits);
    while (!twi_done) {
        if ((uint32_t)(micros() - start) > TWI_WAIT_US) {
            TWCR = _BV(TWEN);
            return 0xFFu;
        }
    }
    return twi_status;
}

static void twi_stop(void)
{
    uint32_t start = micros();
    TWCR = (uint8_t)(_BV(TWINT) | _BV(TWEN) | _BV(TWSTO));
    while (TWCR & _BV(TWSTO)) {
        if ((uint32_t)(micros() - start) > TWI_WAIT_US) {
            TWCR = 0; /* release the bus; the next start re-enables TWI */
            return;
        }
    }
}

static uint8_t twi_start(uint8_t sla_rw)
{
    uint8_t st = twi_op(_BV(TWSTA));
    if (st != TW_START && st != TW_REP_START) {
        return 0;
    }
    TWDR = sla_rw;
    st = twi_op(0);
    /* Some simulators report DATA_ACK for the address byte; accept both. */
    return (uint8_t)(st == TW_MT_SLA_ACK || st == TW_MR_SLA_ACK || st == TW_MT_DATA_ACK);
}

static uint8_t twi_write(uint8_t b)
{
    TWDR = b;
    return (uint8_t)(twi_op(0) == TW_MT_DATA_ACK);
}

static uint8_t twi_read(uint8_t ack, uint8_t *b)
{
    uint8_t st = twi_op(ack ? _BV(TWEA) : 0);
    *b = TWDR;
    return (uint8_t)(st == (ack ? TW_MR_DATA_ACK : TW_MR_DATA_NACK));
}

static uint8_t mpu_write(uint8_t reg, uint8_t value)
{
    uint8_t ok = (uint8_t)(twi_start((uint8_t)(MPU_ADDR << 1) | TW_WRITE) &&
                           twi_write(reg) && twi_write(value));
    twi_stop();
    return ok;
}

static uint8_t mpu_read(uint8_t reg, uint8_t *buf, uint8_t n)
{
    uint8_t i;
    uint8_t ok = (uint8_t)(twi_start((uint8_t)(MPU_ADDR << 1) | TW_WRITE) &&
                           twi_write(reg) &&
                           twi_start((uint8_t)(MPU_ADDR << 1) | TW_READ));
    for (i = 0; ok && i < n; i++) {
        ok = twi_read((uint8_t)(i + 1u < n), &buf[i]);
    }
    twi_stop();
    return ok;
}

uint8_t gyro_begin(void)
{
    uint8_t who = 0;
    /* 400 kHz: TWBR = (F_CPU / f - 16) / 2, prescaler 1. */
    TWSR = 0;
    TWBR = (uint8_t)((F_CPU / 400000ul - 16u) / 2u);
    TWCR = _BV(TWEN);
    if (!mpu_read(REG_WHO_AM_I, &who, 1)) {
        return 0;
    }
    /* MPU9250 0x71, MPU9255 0x73, MPU6500 0x70, MPU6050 0x68: same gyro. */
    if (who != 0x71u && who != 0x73u && who != 0x70u && who != 0x68u) {
        return 0;
    }
    return (uint8_t)(mpu_write(REG_PWR_MGMT_1, 0x01) &&  /* wake, PLL clock */
                     mpu_write(REG_CONFIG, 0x04) &&      /* DLPF 20 Hz */
                     mpu_write(REG_SMPLRT_DIV, 19) &&    /* 1 kHz / 20 = 50 Hz */
                     mpu_write(REG_GYRO_CONFIG, 0x08));  /* +-500 deg/s: 65.5 LSB/(deg/s) */
}

uint8_t gyro_read_z(int16_t *raw)
{
    uint8_t b[2];
    if (!mpu_read(REG_GYRO_ZOUT_H, b, 2)) {
        return 0;
    }
    *raw = i16_from_u16((uint16_t)(((uint16_t)b[0] << 8) | b[1]));
    return 1;
}
