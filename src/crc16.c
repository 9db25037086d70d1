/*
 * crc16.c -- CRC-16-CCITT as SDO block transfer uses it: polynomial 0x1021,
 * initial value 0, no reflection, no final XOR ("123456789" -> 0x31C3).
 *
 * Several bytes per step ("slicing"): T_k[x] (k_tables[k - 1]) is the CRC of byte x
 * followed by k - 1 zero bytes. The CRC is linear over XOR, so n bytes b0..b(n-1) move
 * the CRC c in one step to
 *   T_n[(c >> 8) ^ b0] ^ T_(n-1)[(c & 0xFF) ^ b1] ^ T_(n-2)[b2] ^ ... ^ T_1[b(n-1)].
 * Eight bytes a step with CO_CONFIG_CRC16_FAST (4 KiB of const tables, about 3
 * instructions a byte), two otherwise (1 KiB, about 7).
 */
#include "crc16.h"
#include "build.h" /* CO_CONFIG_CRC16_FAST */

#if CO_CONFIG_CRC16_FAST
#define CRC16_SLICES 8
#else
#define CRC16_SLICES 2
#endif

#include "crc16_tables.inc"

uint16_t co_crc16(uint16_t crc, const uint8_t *data, uint32_t len)
{
    if (len == 0) {
        return crc; /* data may be NULL: no pointer arithmetic on it */
    }
    const uint16_t(*t)[256] = k_tables;
    const uint8_t *p = data;
    const uint8_t *end = data + len;
#if CO_CONFIG_CRC16_FAST
    for (const uint8_t *end8 = data + (len & ~7u); p != end8; p += 8) {
        crc =
            (uint16_t)(t[7][(uint8_t)((crc >> 8) ^ p[0])] ^ t[6][(uint8_t)(crc ^ p[1])] ^
                       t[5][p[2]] ^ t[4][p[3]] ^ t[3][p[4]] ^ t[2][p[5]] ^ t[1][p[6]] ^ t[0][p[7]]);
    }
#endif
    for (; end - p >= 2; p += 2) {
        crc = (uint16_t)(t[1][(uint8_t)((crc >> 8) ^ p[0])] ^ t[0][(uint8_t)(crc ^ p[1])]);
    }
    if (p != end) {
        crc = (uint16_t)((crc << 8) ^ t[0][(uint8_t)((crc >> 8) ^ p[0])]);
    }
    return crc;
}
