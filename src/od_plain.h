/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/od_plain.h -- values read and written in place: the parameters the services read on
 * every SYNC or poll, and whole numbers copied as they are stored (the dictionary's and the
 * PDOs' common reads and writes). Not installed.
 */
#ifndef CANOLA_OD_PLAIN_H
#define CANOLA_OD_PLAIN_H

#include "build.h"
#include "canola/od.h"

/* Integer value of an entry found once (0 for NULL); u8/u16/u32 read in place (kernel.c). */
uint64_t co_entry_uint(const co_od_t *od, const co_od_entry_t *entry);

/* The wire size of a type whose storage is its wire form (on a little-endian host: the
 * numbers as wide as their wire form), 1, 2, 4 or 8 bytes; 0 for the others. By type code,
 * without a table: the common reads and writes of a whole number copy it as it is. */
#define CO_NATIVE_1 ((1u << CO_TYPE_INTEGER8) | (1u << CO_TYPE_UNSIGNED8))
#define CO_NATIVE_2 ((1u << CO_TYPE_INTEGER16) | (1u << CO_TYPE_UNSIGNED16))
#define CO_NATIVE_4                                                                                \
    ((1u << CO_TYPE_INTEGER32) | (1u << CO_TYPE_UNSIGNED32) | (1u << CO_TYPE_REAL32))
#define CO_NATIVE_8                                                                                \
    ((1u << CO_TYPE_INTEGER64) | (1u << CO_TYPE_UNSIGNED64) | (1u << CO_TYPE_REAL64))
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define CO_NATIVE_HOST 1u
#else
#define CO_NATIVE_HOST 0u
#endif
static inline uint32_t co_native_size(unsigned type)
{
    uint32_t bit = CO_NATIVE_HOST && type < 32u ? 1u << type : 0u;
    return (bit & CO_NATIVE_4)                         ? 4u
           : (bit & CO_NATIVE_2)                       ? 2u
           : (bit & CO_NATIVE_1)                       ? 1u
           : CO_CONFIG_OD_64BIT && (bit & CO_NATIVE_8) ? 8u
                                                       : 0u;
}

/* Copy a number of 1, 2, 4 or 8 bytes (anything else copies 8): fixed-size moves, no
 * library call, so a loop around it needs no saved registers; the byte
 * loop where words need their alignment (co_copy_fixed). */
static inline void co_copy_number(void *dst, const void *src, uint32_t bytes)
{
#if CO_UNALIGNED_ACCESS
    switch (bytes) {
    case 1:
        memcpy(dst, src, 1);
        break;
    case 2:
        memcpy(dst, src, 2);
        break;
    case 4:
        memcpy(dst, src, 4);
        break;
    default:
        memcpy(dst, src, 8);
        break;
    }
#else
    co_copy_bytes(dst, src, bytes == 1 || bytes == 2 || bytes == 4 ? bytes : 8u);
#endif
}

#endif /* CANOLA_OD_PLAIN_H */
