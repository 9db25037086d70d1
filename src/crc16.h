/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/crc16.h -- CRC-16-CCITT (crc16.c): polynomial 0x1021, initial value 0, no reflection,
 * no final XOR. SDO block transfers and the stored parameters' images use it. Not installed.
 */
#ifndef CANOLA_CRC16_H
#define CANOLA_CRC16_H

#include <stdint.h>

/* The CRC of `len` bytes at `data` (NULL when `len` is 0), continued from `crc` (start
 * with 0). */
uint16_t co_crc16(uint16_t crc, const uint8_t *data, uint32_t len);

#endif /* CANOLA_CRC16_H */
