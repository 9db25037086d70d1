/* SPDX-License-Identifier: Apache-2.0 */
/*
 * pdo_map.c -- PDO mappings (see canola/pdo.h): each mapping entry resolved to its
 * object's storage and a bit count once, when the mapping becomes valid, so that frames
 * pack and unpack without dictionary look-ups; and the re-mapping procedure's checks
 * (CO_CONFIG_PDO_DYNAMIC). Bit-granular entries and dummy entries are
 * CO_CONFIG_PDO_BIT_MAPPING.
 */
#include "pdo_internal.h"

#define PDO_MAP_BITS_MAX (8u * CO_FRAME_DATA_MAX) /* a mapping fills one frame at most */

#if CO_CONFIG_PDO_BIT_MAPPING
void pdo_copy_bits(uint8_t *dst, uint32_t dpos, const uint8_t *src, uint32_t spos, uint32_t n)
{
    /* At most 64 bits per PDO: a bit at a time is simple and cheap enough. */
    for (uint32_t i = 0; i < n; i++) {
        uint32_t s = spos + i;
        uint32_t d = dpos + i;
        unsigned bit = ((unsigned)src[s / 8u] >> (s % 8u)) & 1u;
        unsigned mask = 1u << (d % 8u);
        dst[d / 8u] = (uint8_t)((dst[d / 8u] & ~mask) | (bit << (d % 8u)));
    }
}
#endif

/* An object can carry PDO data in this direction: a fixed size of 1..8 bytes, the PDO
 * attribute, and storage or a hook to read (TPDO) / take (RPDO) the value. */
static bool mappable(const co_od_t *od, const co_od_entry_t *e, uint32_t size, bool tpdo)
{
    if (!(co_od_attr(od, e) & (tpdo ? CO_OD_TPDO : CO_OD_RPDO)) || size == 0 ||
        size > PDO_VALUE_MAX) {
        return false;
    }
    if (CO_CONFIG_OD_COMPACT) {
        return true; /* every compact entry has its value (co_od_entry_t.offset), no hooks */
    }
    const co_od_hooks_t *hooks = co_od_hooks_of(e);
    bool hook = hooks && (tpdo ? hooks->read != NULL : hooks->write != NULL);
    return co_od_value(od, e) != NULL || hook;
}

/* Bits an entry of `size` bytes may map: any 1..8 x size with bit-granular mapping, else
 * exactly the whole value. */
static bool bits_fit(uint8_t bits, uint32_t size)
{
    return CO_CONFIG_PDO_BIT_MAPPING ? bits <= 8u * size : bits == 8u * size;
}

/* One mapping entry value (index << 16 | sub << 8 | bits) into slot k of `out`. */
static co_abort_t resolve_item(const co_od_t *od, uint32_t value, bool tpdo, co_pdo_t *out,
                               unsigned k)
{
    uint16_t index = (uint16_t)(value >> 16);
    uint8_t bits = (uint8_t)value;
    out->map_entry[k] = CO_PDO_NO_ENTRY;
#if CO_CONFIG_PDO_BIT_MAPPING
    out->map_bits[k] = bits;
#endif
    if (bits == 0) {
        return CO_ABORT_NO_MAP;
    }
    if (CO_CONFIG_PDO_BIT_MAPPING && index >= CO_TYPE_BOOLEAN && index <= CO_TYPE_UNSIGNED32) {
        /* a dummy entry: skips bits of a received frame */
        bool fits = bits <= 8u * co_type_size((co_type_t)index);
        return (!tpdo && fits) ? CO_ABORT_NONE : CO_ABORT_NO_MAP;
    }
    const co_od_entry_t *e = co_od_find(od, index, (uint8_t)(value >> 8), NULL);
    uint32_t size = e != NULL ? co_type_size((co_type_t)co_od_type(od, e)) : 0;
    if (e == NULL || !mappable(od, e, size, tpdo) || !bits_fit(bits, size)) {
        return CO_ABORT_NO_MAP;
    }
#if CO_CONFIG_OD_COMPACT
    ptrdiff_t pos = e - od->entries;
    if (pos >= CO_PDO_NO_ENTRY) {
        return CO_ABORT_NO_MAP; /* past the positions a PDO slot holds: 65535 entries */
    }
    out->map_entry[k] = (uint16_t)pos;
#else
    out->map_entry[k] = e;
#endif
    return CO_ABORT_NONE;
}

/* Resolve entries 1..n of mapping object `index` into out's slots, count and bits; on a
 * failure count and bits stay 0. */
static co_abort_t resolve_mapping(const co_od_t *od, uint16_t index, uint8_t n, bool tpdo,
                                  co_pdo_t *out)
{
    out->count = 0;
    out->bits = 0;
    if (n == 0) {
        return CO_ABORT_NONE;
    }
    if (co_od_find(od, index, n, NULL) == NULL) {
        return CO_ABORT_VALUE_HIGH; /* more entries than the object has */
    }
    if (n > CO_PDO_MAP_MAX) {
        return CO_ABORT_MAP_LEN;
    }
    uint32_t total = 0;
    for (unsigned k = 0; k < n; k++) {
        const co_od_entry_t *e = co_od_find(od, index, (uint8_t)(k + 1u), NULL);
        if (e == NULL) {
            return CO_ABORT_VALUE_HIGH;
        }
        uint32_t item = (uint32_t)co_od_entry_uint(od, e);
        co_abort_t abort = resolve_item(od, item, tpdo, out, k);
        if (abort != CO_ABORT_NONE) {
            return abort;
        }
        total += (uint8_t)item; /* the entry's bits */
        if (total > PDO_MAP_BITS_MAX) {
            return CO_ABORT_MAP_LEN;
        }
    }
    out->count = n;
    out->bits = (uint8_t)total;
    return CO_ABORT_NONE;
}

/* A mapping that does not resolve (set natively, or stored before the rules) maps
 * nothing (resolve_mapping sets the count last): the PDO then does nothing until it is
 * re-mapped. */
void pdo_load_mapping(co_node_t *node, co_pdo_t *p, bool tpdo, uint16_t num)
{
    uint16_t idx = pdo_map_index(tpdo, num);
    (void)resolve_mapping(&node->cfg.od, idx, (uint8_t)co_od_u32(node, idx, 0, 0), tpdo, p);
}

#if CO_CONFIG_PDO_DYNAMIC
/* The re-mapping procedure: the PDO not valid, sub0 = 0 while entries change, then
 * sub0 = N, checked against the dictionary. */
co_abort_t pdo_check_mapping(const co_node_t *node, bool tpdo, uint16_t num, uint8_t sub,
                             const uint8_t *data, uint32_t len)
{
    uint16_t idx = pdo_map_index(tpdo, num);
    if (!(co_od_u32(node, pdo_comm_index(tpdo, num), 1, CO_COB_INVALID) & CO_COB_INVALID)) {
        return CO_ABORT_UNSUPPORTED;
    }
    if (sub != 0) {
        return co_od_u32(node, idx, 0, 0) != 0 ? CO_ABORT_UNSUPPORTED : CO_ABORT_NONE;
    }
    if (len != 1) {
        return CO_ABORT_NONE; /* the length check has refused it already */
    }
    co_pdo_t trial;
    trial.flags = 0; /* (resolve_mapping keeps the state bits: there are none) */
    return resolve_mapping(&node->cfg.od, idx, data[0], tpdo, &trial);
}
#endif
