/* SPDX-License-Identifier: Apache-2.0 */
/*
 * emcy_history.c -- the EMCY error history 0x1003: every raise recorded, newest at sub1,
 * sub0 the number recorded; writing 0 to sub0 clears it, anything else is refused with
 * 0x06090030. Left out with CO_CONFIG_EMCY_HISTORY 0 (emcy_internal.h).
 */
#include "emcy_internal.h"

#if CO_CONFIG_EMCY_HISTORY

/* The recorded value: error code in the low 16 bits, the first two manufacturer bytes
 * (little-endian) as the "additional information" in the high 16 bits. Newest at sub1:
 * every recorded value moves one sub down; the oldest falls off the end of what the OD
 * holds. */
void co_emcy_history_record(co_node_t *node, uint16_t code, const uint8_t mfr[5])
{
    const co_od_t *od = &node->cfg.od;
    uint64_t count = 0;
    if (co_od_get_uint(od, 0x1003, 0, &count) != CO_OK) {
        return; /* no history in this dictionary */
    }
    uint64_t carry = (uint32_t)code | ((uint32_t)co_get_u16(mfr) << 16);
    uint8_t subs = 0;
    for (uint8_t sub = 1; sub != 0; sub++) {
        uint64_t old = 0;
        if (co_od_get_uint(od, 0x1003, sub, &old) != CO_OK) {
            break;
        }
        (void)co_od_set_uint(od, 0x1003, sub, carry);
        carry = old;
        subs = sub;
    }
    (void)co_od_set_uint(od, 0x1003, 0, count < subs ? count + 1 : subs);
}

void co_emcy_history_clear(co_node_t *node)
{
    const co_od_t *od = &node->cfg.od;
    (void)co_od_set_uint(od, 0x1003, 0, 0);
    for (uint8_t sub = 1; sub != 0; sub++) {
        if (co_od_set_uint(od, 0x1003, sub, 0) != CO_OK) {
            break;
        }
    }
}

co_abort_t co_emcy_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len)
{
    (void)node;
    if (entry->index != 0x1003 || entry->sub != 0) {
        return CO_ABORT_NONE;
    }
    for (uint32_t i = 0; i < len; i++) {
        if (data[i] != 0) {
            return CO_ABORT_VALUE; /* only 0 (clear the history) may be written */
        }
    }
    return CO_ABORT_NONE;
}

#endif
