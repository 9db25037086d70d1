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

uint16_t co_nmt_services(co_nmt_state_t state)
{
    switch (state) {
    case CO_NMT_INITIALISING:
        return CO_SVC_BOOTUP | CO_SVC_LSS;
    case CO_NMT_PRE_OPERATIONAL:
        return CO_SVC_NMT | CO_SVC_ERROR_CONTROL | CO_SVC_SDO | CO_SVC_SYNC | CO_SVC_TIME |
               CO_SVC_EMCY | CO_SVC_LSS;
    case CO_NMT_OPERATIONAL:
        return CO_SVC_NMT | CO_SVC_ERROR_CONTROL | CO_SVC_SDO | CO_SVC_SYNC | CO_SVC_TIME |
               CO_SVC_EMCY | CO_SVC_PDO | CO_SVC_LSS;
    case CO_NMT_STOPPED:
        return CO_SVC_NMT | CO_SVC_ERROR_CONTROL | CO_SVC_LSS;
    default:
        return CO_SVC_LSS;
    }
}

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
