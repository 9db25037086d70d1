/*
 * crc16.c -- CRC-16-CCITT as SDO block transfer uses it: polynomial 0x1021,
 * initial value 0, no reflection, no final XOR ("123456789" -> 0x31C3).
 * Table-driven, one look-up per byte; the table is const (512 bytes of flash).
 */
#include "internal.h"

static const uint16_t k_table[256] = {
#define R1(c) ((uint16_t)(((c)&0x8000u) ? (((c) << 1) ^ 0x1021u) : ((c) << 1)))
#define R2(c) R1(R1(c) & 0xFFFFu)
#define R4(c) R2(R2(c) & 0xFFFFu)
#define R8(c) R4(R4(c) & 0xFFFFu)
#define E(i) R8((uint32_t)(i) << 8)
#define E4(i) E(i), E((i) + 1), E((i) + 2), E((i) + 3)
#define E16(i) E4(i), E4((i) + 4), E4((i) + 8), E4((i) + 12)
    E16(0x00), E16(0x10), E16(0x20), E16(0x30), E16(0x40), E16(0x50), E16(0x60), E16(0x70),
    E16(0x80), E16(0x90), E16(0xA0), E16(0xB0), E16(0xC0), E16(0xD0), E16(0xE0), E16(0xF0),
#undef E16
#undef E4
#undef E
#undef R8
#undef R4
#undef R2
#undef R1
};

uint16_t co_crc16(uint16_t crc, const uint8_t *data, uint32_t len)
{
    for (uint32_t i = 0; i < len; i++) {
        crc = (uint16_t)((crc << 8) ^ k_table[(uint8_t)((crc >> 8) ^ data[i])]);
    }
    return crc;
}
