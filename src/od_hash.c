/* SPDX-License-Identifier: Apache-2.0 */
/*
 * od_hash.c -- building the optional hash table of a dictionary (co_od_t.hash) at run
 * time; canola.odgen writes the same table into generated dictionaries.
 */
#include "canola/od.h"

/* The general form hashes its dense key array; the compact form, which has none, the
 * entries' own keys. */
static bool has_keys(const co_od_t *od)
{
#if CO_CONFIG_OD_COMPACT
    return od->entries != NULL || od->count == 0;
#else
    return od->keys != NULL;
#endif
}

static uint32_t key_of(const co_od_t *od, uint32_t i)
{
#if CO_CONFIG_OD_COMPACT
    return CO_OD_KEY(od->entries[i].index, od->entries[i].sub);
#else
    return od->keys[i];
#endif
}

uint8_t co_od_hash_bits(uint32_t count)
{
    if (count > 32767u) {
        return 0;
    }
    uint8_t bits = 1;
    while ((1u << bits) < 2u * count) {
        bits++;
    }
    return bits;
}

co_err_t co_od_hash_build(co_od_t *od, uint16_t *slots, uint8_t bits)
{
    if (od == NULL || slots == NULL || !has_keys(od) || bits < 1 || bits > 16 ||
        od->count >= (1u << bits)) {
        return CO_ERR_ARG;
    }
    uint32_t mask = (1u << bits) - 1u;
    for (uint32_t i = 0; i <= mask; i++) {
        slots[i] = 0;
    }
    for (uint32_t i = 0; i < od->count; i++) {
        uint32_t slot = CO_OD_HASH_HOME(key_of(od, i), mask);
        while (slots[slot] != 0) {
            slot = (slot + 1u) & mask;
        }
        slots[slot] = (uint16_t)(i + 1u);
    }
    od->hash = slots;
    od->hash_mask = (uint16_t)mask;
    return CO_OK;
}
