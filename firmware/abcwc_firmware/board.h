/* board.h - the wiring of the abcwc Arduino Mega 2560 shield (thesis
 * appendix A.18 and B.1), and the small drivers in board_*.cpp. */
#ifndef ABCWC_BOARD_H
#define ABCWC_BOARD_H

#include <stdint.h>

/* SPI chip selects. */
#define PIN_CS_ADC 10 /* MCP3004, PB4 */
#define PIN_CS_POT 8  /* MCP42010, PH5 */

/* MCP3004 command bytes: start, single-ended, channel. */
#define ADC_CH_LR 0xE0u /* channel 0: joystick turn (left/right) axis */
#define ADC_CH_FB 0xE8u /* channel 1: joystick drive (forward/back) axis */

/* MCP42010 command bytes: "write data" to pot 0, pot 1 or both. */
#define POT_CMD_LR 0x11u
#define POT_CMD_FB 0x12u
#define POT_CMD_BOTH 0x13u

/* Encoders: phase A on an external interrupt, phase B read in the ISR. */
#define PIN_ENC_LEFT_A 18  /* INT3, PD3 */
#define PIN_ENC_LEFT_B 19  /* PD2 */
#define PIN_ENC_RIGHT_A 2  /* INT4, PE4 */
#define PIN_ENC_RIGHT_B 3  /* PE5 */

/* MB1013 sonar pulse-width output (1 us per mm). */
#define PIN_SONAR 9        /* PH6 */

/* MPU9250 on the I2C bus (TWI): SDA 20, SCL 21. */
#define MPU_ADDR 0x68u

/* board_spi.cpp */
void spi_board_begin(void);
uint16_t adc_read(uint8_t command);           /* pot scale, 0..1023 */
void pot_write(uint8_t command, uint8_t value);

/* board_sensors.cpp */
void sensors_begin(void);
void encoders_read(uint32_t *left, uint32_t *right);
/* Latest sonar range in mm and the millis() time it was measured; returns 0
 * if no pulse has been measured since boot. */
uint8_t sonar_read(uint16_t *mm, uint32_t *at_ms);

/* board_gyro.cpp */
uint8_t gyro_begin(void);                     /* 1 if the MPU answered */
uint8_t gyro_read_z(int16_t *raw);            /* 1 on success */

#endif
