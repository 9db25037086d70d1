/* SPDX-License-Identifier: Apache-2.0 */
/*
 * kernel.c -- what every service may call below the node (kernel.h): the schedule, the NMT
 * gate (which services each state allows: the send and receive paths ask it), and the
 * dictionary's parameters.
 */
#include "kernel.h"
#include "od_plain.h"

void co_node_schedule(co_node_t *node, uint64_t due_us)
{
    if (due_us < node->next_due_us) {
        node->next_due_us = due_us;
    }
}

uint16_t co_nmt_services(co_nmt_state_t state) { return co_nmt_gate((uint8_t)state); }

bool co_nmt_allows(co_nmt_state_t state, co_service_t service)
{
    return (co_nmt_services(state) & (uint16_t)service) != 0;
}

uint32_t co_od_u32(const co_node_t *node, uint16_t index, uint8_t sub, uint32_t absent)
{
    uint64_t v = absent;
    (void)co_od_get_uint(&node->cfg.od, index, sub, &v);
    return (uint32_t)v;
}

uint64_t co_entry_uint(const co_od_t *od, const co_od_entry_t *entry)
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

co_abort_t co_od_read_check(const co_node_t *node, const co_od_entry_t *entry)
{
    if (entry->index != 0x1003 || entry->sub == 0) {
        return CO_ABORT_NONE;
    }
    return entry->sub > co_od_u32(node, 0x1003, 0, 0xFF) ? CO_ABORT_NO_DATA : CO_ABORT_NONE;
}
