/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/od_plain.h -- values read and written in place: the parameters the services read on
 * every SYNC or poll, and entries whose storage is their wire form, which the PDOs copy
 * without the dictionary's general read and write. Not installed.
 */
#ifndef CANOLA_OD_PLAIN_H
#define CANOLA_OD_PLAIN_H

#include "build.h"
#include "canola/od.h"

/* Integer value of an entry found once (0 for NULL); u8/u16/u32 read in place. */
static inline uint64_t co_entry_uint(const co_od_t *od, const co_od_entry_t *entry)
{
    if (entry == NULL) {
        return 0;
    }
    const void *value = co_od_value(od, entry);
    if (value != NULL) {
        switch (co_od_type(od, entry)) {
        case CO_TYPE_UNSIGNED8:
            return *(const uint8_t *)value;
        case CO_TYPE_UNSIGNED16:
            return *(const uint16_t *)value;
        case CO_TYPE_UNSIGNED32:
            return *(const uint32_t *)value;
        default:
            break;
        }
    }
    return co_od_entry_uint(od, entry);
}

/* The types whose native storage is their wire form (as in od.c: numbers as wide as their
 * wire form, on a little-endian host; BOOLEAN is left to the general paths, which check
 * that a written value is 0 or 1), as bits of a mask indexed by type code. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define CO_WIRE_NATIVE_TYPES                                                                       \
    ((1u << CO_TYPE_INTEGER8) | (1u << CO_TYPE_INTEGER16) | (1u << CO_TYPE_INTEGER32) |            \
     (1u << CO_TYPE_UNSIGNED8) | (1u << CO_TYPE_UNSIGNED16) | (1u << CO_TYPE_UNSIGNED32) |         \
     (1u << CO_TYPE_REAL32) | (1u << CO_TYPE_REAL64) | (1u << CO_TYPE_INTEGER64) |                 \
     (1u << CO_TYPE_UNSIGNED64))
#else
#define CO_WIRE_NATIVE_TYPES 0u
#endif

/* Copy a number of 1, 2, 4 or 8 bytes (anything else copies 8): fixed-size moves, no
 * library call, so a loop around it needs no saved registers (the PDOs' copies). */
static inline void co_copy_number(void *dst, const void *src, uint32_t bytes)
{
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
}

#endif /* CANOLA_OD_PLAIN_H */
