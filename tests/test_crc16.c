/* SPDX-License-Identifier: Apache-2.0 */
/* test_crc16.c -- the SDO block CRC against a bitwise reference, every table entry. */
#include "check.h"
#include "crc16.h"

/* Bit by bit, straight from the definition: polynomial 0x1021, initial 0. */
static uint16_t reference(uint16_t crc, const uint8_t *p, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++) {
        crc ^= (uint16_t)(p[i] << 8);
        for (int k = 0; k < 8; k++) {
            crc = (uint16_t)((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
        }
    }
    return crc;
}

static void test_check_value(void)
{
    CHECK_EQ(co_crc16(0, (const uint8_t *)"123456789", 9), 0x31C3);
    CHECK_EQ(reference(0, (const uint8_t *)"123456789", 9), 0x31C3);
    CHECK_EQ(co_crc16(0, NULL, 0), 0);
}

static void test_every_byte_pair_and_length(void)
{
    /* Both table entries of every byte value, through one and two byte inputs. */
    for (unsigned a = 0; a < 256; a++) {
        uint8_t one[1] = {(uint8_t)a};
        CHECK_EQ(co_crc16(0x1D0F, one, 1), reference(0x1D0F, one, 1));
        for (unsigned b = 0; b < 256; b += 17) {
            uint8_t two[2] = {(uint8_t)a, (uint8_t)b};
            CHECK_EQ(co_crc16((uint16_t)(a * 257u), two, 2),
                     reference((uint16_t)(a * 257u), two, 2));
        }
    }
    /* Odd and even lengths, continued in pieces. */
    uint8_t data[1000];
    for (unsigned i = 0; i < sizeof data; i++) {
        data[i] = (uint8_t)(i * 131u + 7u);
    }
    for (uint32_t len = 0; len <= 40; len++) {
        CHECK_EQ(co_crc16(0, data, len), reference(0, data, len));
    }
    uint16_t pieces = co_crc16(0, data, 7);
    pieces = co_crc16(pieces, data + 7, 500);
    pieces = co_crc16(pieces, data + 507, 493);
    CHECK_EQ(pieces, reference(0, data, 1000));
}

/* Every entry of every table: byte x at each place of an 8-byte step (the rest zero),
 * from a CRC that is itself not zero. */
static void test_every_table_entry(void)
{
    for (unsigned x = 0; x < 256; x++) {
        for (unsigned at = 0; at < 8; at++) {
            uint8_t step[8] = {0};
            step[at] = (uint8_t)x;
            CHECK_EQ(co_crc16((uint16_t)(0xA5C3u ^ x), step, 8),
                     reference((uint16_t)(0xA5C3u ^ x), step, 8));
            CHECK_EQ(co_crc16(0, step, 8), reference(0, step, 8));
        }
    }
}

int main(void)
{
    RUN(test_check_value);
    RUN(test_every_byte_pair_and_length);
    RUN(test_every_table_entry);
    return check_summary();
}
