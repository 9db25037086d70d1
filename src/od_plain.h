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
 * without a table (the common reads and writes of a whole number copy it as it is): the
 * size's log2 + 1 in bit planes, one mask per bit. */
#define CO_NATIVE_BIT(t) (1u << (t))
#define CO_NATIVE_PLANE0                                                                           \
    (CO_NATIVE_BIT(CO_TYPE_INTEGER8) | CO_NATIVE_BIT(CO_TYPE_UNSIGNED8) |                          \
     CO_NATIVE_BIT(CO_TYPE_INTEGER32) | CO_NATIVE_BIT(CO_TYPE_UNSIGNED32) |                        \
     CO_NATIVE_BIT(CO_TYPE_REAL32)) /* 1 and 3: 1 and 4 bytes */
#define CO_NATIVE_PLANE1                                                                           \
    (CO_NATIVE_BIT(CO_TYPE_INTEGER16) | CO_NATIVE_BIT(CO_TYPE_UNSIGNED16) |                        \
     CO_NATIVE_BIT(CO_TYPE_INTEGER32) | CO_NATIVE_BIT(CO_TYPE_UNSIGNED32) |                        \
     CO_NATIVE_BIT(CO_TYPE_REAL32)) /* 2 and 3: 2 and 4 bytes */
#define CO_NATIVE_PLANE2                                                                           \
    (CO_NATIVE_BIT(CO_TYPE_INTEGER64) | CO_NATIVE_BIT(CO_TYPE_UNSIGNED64) |                        \
     CO_NATIVE_BIT(CO_TYPE_REAL64)) /* 4: 8 bytes */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define CO_NATIVE_HOST 1u
#else
#define CO_NATIVE_HOST 0u
#endif
static inline uint32_t co_native_size(unsigned type)
{
    uint32_t t = type & 31u;
    uint32_t code = ((CO_NATIVE_PLANE0 >> t) & 1u) | (((CO_NATIVE_PLANE1 >> t) & 1u) << 1) |
                    (CO_CONFIG_OD_64BIT ? ((CO_NATIVE_PLANE2 >> t) & 1u) << 2 : 0u);
    return CO_NATIVE_HOST && type < 32u ? (1u << code) >> 1 : 0u;
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
