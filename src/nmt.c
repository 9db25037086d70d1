/* SPDX-License-Identifier: Apache-2.0 */
/*
 * nmt.c -- the NMT state machine of a node and its fan-out: every service resets its
 * communication, starts, stops or catches up as the state says; and NMT commands as a master.
 * (Which services each state allows is the kernel's gate: co_nmt_services, kernel.c.)
 */
#include "node_internal.h"

#define NMT_FRAME_LEN 2u /* command specifier, node-ID (0: all) */

const char *co_nmt_state_name(uint8_t state)
{
    switch (state) {
    case CO_NMT_INITIALISING:
        return "initialising";
    case CO_NMT_STOPPED:
        return "stopped";
    case CO_NMT_OPERATIONAL:
        return "operational";
    case CO_NMT_PRE_OPERATIONAL:
        return "pre-operational";
    default:
        return "unknown";
    }
}

co_nmt_state_t co_nmt_state(const co_node_t *node) { return (co_nmt_state_t)node->nmt_state; }

/* The state changed: services that depend on it start, stop or catch up. (Out of line: the
 * state's own change, inline in co_nmt_apply, stays short.) */
static CO_FAST_NOINLINE void state_changed(co_node_t *node)
{
    co_txq_purge(node);
    if (!(node->services & CO_SVC_SDO)) {
        co_sdo_server_stop(node);
        co_sdo_client_stop(node);
    }
    co_sync_state_entered(node);
    co_emcy_state_entered(node);
    co_pdo_state_entered(node);
}

static CO_INLINE void enter(co_node_t *node, co_nmt_state_t state)
{
    if (node->nmt_state == (uint8_t)state) {
        return;
    }
    node->nmt_state = (uint8_t)state;
    node->services = co_nmt_gate((uint8_t)state);
    state_changed(node);
    if (node->cfg.on_state) {
        node->cfg.on_state(node->cfg.user, state);
    }
}

/* Initialisation as CiA 301 orders it: reset application (optional), reset
 * communication, boot-up once, pre-operational (or operational when self-starting). */
void co_nmt_reset(co_node_t *node, bool application)
{
    co_manager_reset_comm(node); /* first: leaving SDO's states ends the boot's transfers */
    enter(node, CO_NMT_INITIALISING);
    co_lss_slave_reset(node, application);
    co_store_fault_t app_image = CO_STORE_NONE;
    if (application) {
        app_image = co_storage_reset_group(node, CO_PARAMS_APPLICATION); /* 0x2000..0x9FFF */
        if (node->cfg.on_reset) {
            node->cfg.on_reset(node->cfg.user, CO_RESET_APPLICATION);
        }
    }
    co_store_fault_t comm_image = co_storage_reset_group(node, CO_PARAMS_COMMUNICATION);
    /* Every service takes its parameters again, and with them its receive routes. */
    co_route_set(node, CO_ROUTE_NMT, 0, 0x000);
    co_storage_reset_comm(node);
    co_hb_reset_comm(node);
    co_guard_reset_comm(node);
    co_sdo_server_reset_comm(node);
    co_sdo_client_reset_comm(node);
    co_sync_reset_comm(node);
    co_time_reset_comm(node);
    co_emcy_reset_comm(node);
    co_pdo_reset_comm(node);
    co_manager_routes(node);
    /* Rejected images now, when the history (0x1003, reset above) can keep their EMCYs. */
    co_storage_report(node, CO_PARAMS_COMMUNICATION, comm_image);
    co_storage_report(node, CO_PARAMS_APPLICATION, app_image);
    if (node->cfg.on_reset) {
        node->cfg.on_reset(node->cfg.user, CO_RESET_COMMUNICATION);
    }
    if (node->node_id == CO_NODE_ID_UNCONFIGURED) {
        return; /* waits in initialisation until LSS gives it a node-ID */
    }
    co_hb_frame_send(node, 0x00, 0); /* the boot-up */
    enter(node, node->cfg.self_start ? CO_NMT_OPERATIONAL : CO_NMT_PRE_OPERATIONAL);
    co_hb_state_entered(node);
}

co_err_t co_nmt_apply(co_node_t *node, co_nmt_cmd_t cmd)
{
    if (!node->started || node->nmt_state == CO_NMT_INITIALISING) {
        return CO_ERR_STATE;
    }
    switch (cmd) {
    case CO_NMT_CMD_START:
        enter(node, CO_NMT_OPERATIONAL);
        return CO_OK;
    case CO_NMT_CMD_STOP:
        enter(node, CO_NMT_STOPPED);
        return CO_OK;
    case CO_NMT_CMD_ENTER_PRE_OPERATIONAL:
        enter(node, CO_NMT_PRE_OPERATIONAL);
        return CO_OK;
    case CO_NMT_CMD_RESET_NODE:
        co_nmt_reset(node, true);
        return CO_OK;
    case CO_NMT_CMD_RESET_COMMUNICATION:
        co_nmt_reset(node, false);
        return CO_OK;
    }
    return CO_ERR_ARG;
}

void co_nmt_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)slot;
    if (frame->len != NMT_FRAME_LEN || (frame->flags & CO_FRAME_RTR)) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    uint8_t target = frame->data[1];
    if (target != 0 && target != node->node_id) {
        return;
    }
    if (co_nmt_apply(node, (co_nmt_cmd_t)frame->data[0]) == CO_ERR_ARG) {
        CO_COUNT(node, rx_malformed);
    }
}

static bool known_command(co_nmt_cmd_t cmd)
{
    return cmd == CO_NMT_CMD_START || cmd == CO_NMT_CMD_STOP ||
           cmd == CO_NMT_CMD_ENTER_PRE_OPERATIONAL || cmd == CO_NMT_CMD_RESET_NODE ||
           cmd == CO_NMT_CMD_RESET_COMMUNICATION;
}

co_err_t co_nmt_send(co_node_t *node, co_nmt_cmd_t cmd, uint8_t target)
{
    if (!known_command(cmd) || target > 127) {
        return CO_ERR_ARG;
    }
    uint8_t data[NMT_FRAME_LEN] = {(uint8_t)cmd, target};
    (void)co_node_send_cob(node, 0x000, data, NMT_FRAME_LEN, 0);
    if (target == 0 || target == node->node_id) {
        (void)co_nmt_apply(node, cmd);
    }
    return CO_OK;
}
