/* board_spi.cpp - the joystick ADC (MCP3004) and the digital pot (MCP42010)
 * on the hardware SPI bus, mode 3, MSB first. */
#include <Arduino.h>
#include <SPI.h>

#include "board.h"

/* 1 MHz: within both chips' limits (MCP3004: 1.35 MHz at 5 V). */
static const SPISettings kSpi(1000000, MSBFIRST, SPI_MODE3);

void spi_board_begin(void)
{
    /* High first, then output: no select glitch at boot. */
    digitalWrite(PIN_CS_ADC, HIGH);
    digitalWrite(PIN_CS_POT, HIGH);
    pinMode(PIN_CS_ADC, OUTPUT);
    pinMode(PIN_CS_POT, OUTPUT);
    SPI.begin();
}

/* Reads one joystick channel. The 16-clock transfer ends one clock before
 * the conversion's last bit, so the value is the 10-bit result shifted
 * right by one: the "pot scale" of the thesis, centred on 254. */
uint16_t adc_read(uint8_t command)
{
    uint8_t hi, lo;
    SPI.beginTransaction(kSpi);
    digitalWrite(PIN_CS_ADC, LOW);
    hi = SPI.transfer(command);
    lo = SPI.transfer(0x00);
    digitalWrite(PIN_CS_ADC, HIGH);
    SPI.endTransaction();
    return (uint16_t)(((uint16_t)hi << 8) | lo) & 0x3FFu;
}

void pot_write(uint8_t command, uint8_t value)
{
    SPI.beginTransaction(kSpi);
    digitalWrite(PIN_CS_POT, LOW);
    SPI.transfer(command);
    SPI.transfer(value);
    digitalWrite(PIN_CS_POT, HIGH);
    SPI.endTransaction();
}
