/* SPDX-License-Identifier: Apache-2.0 */
/*
 * kernel.c -- what every service may call below the node (kernel.h): the schedule, the NMT
 * gate (which services each state allows: the send and receive paths ask it), and the
 * dictionary's parameters.
 */
#include "kernel.h"

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

co_abort_t co_od_read_check(const co_node_t *node, const co_od_entry_t *entry)
{
    if (entry->index != 0x1003 || entry->sub == 0) {
        return CO_ABORT_NONE;
    }
    return entry->sub > co_od_u32(node, 0x1003, 0, 0xFF) ? CO_ABORT_NO_DATA : CO_ABORT_NONE;
}
