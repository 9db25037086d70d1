/* SPDX-License-Identifier: Apache-2.0 */
/*
 * crc16.c -- CRC-16-CCITT as SDO block transfer uses it: polynomial 0x1021,
 * initial value 0, no reflection, no final XOR ("123456789" -> 0x31C3).
 *
 * Several bytes per step ("slicing"): T_k[x] (k_tables[k - 1]) is the CRC of byte x
 * followed by k - 1 zero bytes. The CRC is linear over XOR, so n bytes b0..b(n-1) move
 * the CRC c in one step to
 *   T_n[(c >> 8) ^ b0] ^ T_(n-1)[(c & 0xFF) ^ b1] ^ T_(n-2)[b2] ^ ... ^ T_1[b(n-1)].
 * Eight bytes a step with CO_CONFIG_CRC16_FAST (4 KiB of const tables, about 3
 * instructions a byte). Otherwise a nibble a step (a 32-byte table, about 18 instructions a
 * byte): a build for size, where the CRC serves stored images and, if built, SDO block
 * transfers, and the kilobytes count more than the cycles.
 */
#include "crc16.h"
#include "build.h" /* CO_CONFIG_CRC16_FAST */

#if CO_CONFIG_CRC16_FAST
#include "crc16_tables.inc"

uint16_t co_crc16(uint16_t crc, const uint8_t *data, uint32_t len)
{
    if (len == 0) {
        return crc; /* data may be NULL: no pointer arithmetic on it */
    }
    const uint16_t(*t)[256] = k_tables;
    const uint8_t *p = data;
    const uint8_t *end = data + len;
    for (const uint8_t *end8 = data + (len & ~7u); p != end8; p += 8) {
        crc =
            (uint16_t)(t[7][(uint8_t)((crc >> 8) ^ p[0])] ^ t[6][(uint8_t)(crc ^ p[1])] ^
                       t[5][p[2]] ^ t[4][p[3]] ^ t[3][p[4]] ^ t[2][p[5]] ^ t[1][p[6]] ^ t[0][p[7]]);
    }
    for (; end - p >= 2; p += 2) {
        crc = (uint16_t)(t[1][(uint8_t)((crc >> 8) ^ p[0])] ^ t[0][(uint8_t)(crc ^ p[1])]);
    }
    if (p != end) {
        crc = (uint16_t)((crc << 8) ^ t[0][(uint8_t)((crc >> 8) ^ p[0])]);
    }
    return crc;
}
#else
/* k_nibbles[x]: the CRC of the four bits x followed by none (T1's first 16 entries). */
static const uint16_t k_nibbles[16] = {0x0000, 0x1021, 0x2042, 0x3063, 0x4084, 0x50A5,
                                       0x60C6, 0x70E7, 0x8108, 0x9129, 0xA14A, 0xB16B,
                                       0xC18C, 0xD1AD, 0xE1CE, 0xF1EF};

uint16_t co_crc16(uint16_t crc, const uint8_t *data, uint32_t len)
{
    for (uint32_t i = 0; i < len; i++) {
        crc = (uint16_t)((crc << 4) ^ k_nibbles[(crc >> 12) ^ (data[i] >> 4)]);
        crc = (uint16_t)((crc << 4) ^ k_nibbles[(crc >> 12) ^ (data[i] & 15u)]);
    }
    return crc;
}
#endif
