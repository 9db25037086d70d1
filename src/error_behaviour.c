/* SPDX-License-Identifier: Apache-2.0 */
/*
 * error_behaviour.c -- communication errors and what the node does about them: error-control
 * events (to the application and the manager), EMCY 0x8130 while communication is lost, the
 * bus events a driver reports, and the error behaviour of 0x1029 sub1 (a change of NMT state).
 * CiA 301's own loop: error control -> error behaviour -> NMT -> every service.
 */
#include "node_internal.h"

void co_node_ec_event(co_node_t *node, co_ec_event_kind_t kind, uint8_t node_id, uint8_t state,
                      uint8_t previous)
{
    co_ec_event_t ev = {.kind = kind, .node_id = node_id, .state = state, .previous = previous};
    if (node->cfg.on_errctl) {
        node->cfg.on_errctl(node->cfg.user, &ev);
    }
    co_manager_ec_event(node, &ev); /* the manager boots slaves on boot-up, watches losses */
}

void co_node_error_behaviour(co_node_t *node)
{
    switch (co_entry_uint(&node->cfg.od, node->error_behaviour)) {
    case 0:
        if (node->nmt_state == CO_NMT_OPERATIONAL) {
            (void)co_nmt_apply(node, CO_NMT_CMD_ENTER_PRE_OPERATIONAL);
        }
        break;
    case 2:
        (void)co_nmt_apply(node, CO_NMT_CMD_STOP);
        break;
    default: /* 1 and manufacturer-specific values: no change */
        break;
    }
}

void co_node_comm_lost(co_node_t *node)
{
    (void)co_emcy_raise(node, 0x8130, NULL);
    co_node_error_behaviour(node);
}

/* Anything still lost: a consumed heartbeat, or our own life guarding. */
static bool comm_still_lost(const co_node_t *node)
{
    return co_hb_consumer_lost(node) || co_guard_life_lost(node);
}

void co_node_comm_resumed(co_node_t *node)
{
    if (!comm_still_lost(node)) {
        (void)co_emcy_clear(node, 0x8130); /* (not active: nothing to clear, nothing sent) */
    }
}

void co_node_bus_event(co_node_t *node, co_bus_event_t event)
{
    switch (event) {
    case CO_BUS_RX_OVERRUN:
        /* An event, not a state the driver reports the end of: it stays active until the
         * application clears it (co_emcy_clear(node, 0x8110)). */
        (void)co_emcy_raise(node, 0x8110, NULL);
        break;
    case CO_BUS_ERROR_PASSIVE:
        if (!co_emcy_active(node, 0x8120)) { /* a state: reported once while it lasts */
            (void)co_emcy_raise(node, 0x8120, NULL);
        }
        break;
    case CO_BUS_ERROR_ACTIVE:
        (void)co_emcy_clear(node, 0x8120);
        break;
    case CO_BUS_OFF:
        co_node_error_behaviour(node); /* nothing can be sent while bus-off: no EMCY */
        break;
    case CO_BUS_OFF_RECOVERED:
        /* Like the overrun, the application clears 0x8140. Recovery restarts the error
         * counters, so the controller is error active again: 0x8120 ends (after the
         * raise, so that this costs one frame, not an error reset and a raise). */
        (void)co_emcy_raise(node, 0x8140, NULL);
        (void)co_emcy_clear(node, 0x8120);
        break;
    }
}
