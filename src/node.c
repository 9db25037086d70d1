/* SPDX-License-Identifier: Apache-2.0 */
/*
 * node.c -- the node's life: init (the services bind their objects, the node's wiring),
 * start, ingest (a frame to the service its route names) and poll (every service's due work).
 */
#include "node_internal.h"

/* ---- the wiring: the calls up that services below the node make (kernel.h). An entry is
 * there only when the service that makes the call is in the build (canola/config.h). */

static const co_node_wiring_t k_wiring = {
    .write = co_node_write_entry,
#if CO_CONFIG_PDO_TIMERS
    .error_behaviour = co_node_error_behaviour,
#endif
#if CO_CONFIG_LSS_SLAVE
    .nmt_reset = co_nmt_reset,
#endif
#if CO_CONFIG_MANAGER
    .nmt_send = co_nmt_send,
    .nmt_apply = co_nmt_apply,
#endif
};

/* ---- lifecycle */

co_err_t co_node_init(co_node_t *node, const co_node_config_t *config)
{
    if (node == NULL || config == NULL || config->driver.tx == NULL || config->od.entries == NULL) {
        return CO_ERR_ARG;
    }
    uint8_t id = config->node_id;
    if ((id < 1 || id > 127) && id != CO_NODE_ID_UNCONFIGURED) {
        return CO_ERR_ARG;
    }
    if (co_od_validate(&config->od, NULL) != CO_OK) {
        return CO_ERR_CONFIG;
    }
    co_zero(node, sizeof *node);
    co_copy(&node->cfg, config, sizeof *config); /* (a struct copy would call memcpy) */
    node->wiring = &k_wiring;
    node->node_id = id;
    node->nmt_state = CO_NMT_INITIALISING;
    node->services = co_nmt_gate(CO_NMT_INITIALISING);
    node->next_due_us = CO_TIME_NEVER;
    node->hb_next_us = CO_TIME_NEVER;
    co_guard_bind(node);
    node->error_behaviour = co_od_find(&config->od, 0x1029, 1, NULL);
    return co_hb_bind(node);
}

co_err_t co_node_start(co_node_t *node, uint64_t now_us)
{
    if (node->started) {
        return CO_ERR_STATE;
    }
    node->started = true;
    node->now_us = now_us;
    co_nmt_reset(node, true);
    return CO_OK;
}

uint8_t co_node_id(const co_node_t *node) { return node->node_id; }

const co_node_stats_t *co_node_stats(const co_node_t *node)
{
#if CO_CONFIG_STATS
    return &node->stats;
#else
    static const co_node_stats_t none; /* counters that stay zero (canola/node.h) */
    (void)node;
    return &none;
#endif
}

/* ---- dispatch */

/* Each route kind: the service that takes its frames (with the route's slot) and the
 * co_service_t bit the NMT state must allow for them. One list, two tables (less code than a
 * switch, and a table of pointers packs no service bits between them). Left-out services
 * are stand-ins that ignore the frame; the last kinds (LSS, the manager) have no entry when
 * left out: no route of theirs is ever set, and both tables end before them. */
#if CO_CONFIG_LSS_SLAVE
#define LSS_SLAVE_ROUTE(X) X(CO_ROUTE_LSS_SLAVE, co_lss_slave_ingest, CO_SVC_LSS)
#else
#define LSS_SLAVE_ROUTE(X)
#endif
#if CO_CONFIG_LSS_MASTER
#define LSS_MASTER_ROUTE(X) X(CO_ROUTE_LSS_MASTER, co_lss_master_ingest, CO_SVC_LSS)
#else
#define LSS_MASTER_ROUTE(X)
#endif
#if CO_CONFIG_MANAGER
#define MANAGER_ROUTE(X) X(CO_ROUTE_MGR_BOOTUP, co_manager_bootup, CO_SVC_ERROR_CONTROL)
#else
#define MANAGER_ROUTE(X)
#endif
#define ROUTE_KINDS(X)                                                                             \
    X(CO_ROUTE_NMT, co_nmt_ingest, CO_SVC_NMT)                                                     \
    X(CO_ROUTE_GUARD_RTR, co_guard_rtr, CO_SVC_ERROR_CONTROL)                                      \
    X(CO_ROUTE_GUARD_REPLY, co_guard_reply, CO_SVC_ERROR_CONTROL)                                  \
    X(CO_ROUTE_HB_CONSUMER, co_hb_ingest, CO_SVC_ERROR_CONTROL)                                    \
    X(CO_ROUTE_SDO_SERVER, co_sdo_server_ingest, CO_SVC_SDO)                                       \
    X(CO_ROUTE_SDO_CLIENT, co_sdo_client_ingest, CO_SVC_SDO)                                       \
    X(CO_ROUTE_SYNC, co_sync_ingest, CO_SVC_SYNC)                                                  \
    X(CO_ROUTE_TIME, co_time_ingest, CO_SVC_TIME)                                                  \
    X(CO_ROUTE_EMCY, co_emcy_ingest, CO_SVC_EMCY)                                                  \
    X(CO_ROUTE_RPDO, co_pdo_rx, CO_SVC_PDO)                                                        \
    X(CO_ROUTE_TPDO_RTR, co_pdo_rtr, CO_SVC_PDO)                                                   \
    LSS_SLAVE_ROUTE(X) LSS_MASTER_ROUTE(X) MANAGER_ROUTE(X)

typedef void (*ingest_fn)(co_node_t *node, uint8_t slot, const co_frame_t *frame);
#define INGEST_OF(kind, ingest, service) [(kind)] = (ingest),
#define SERVICE_OF(kind, ingest, service) [(kind)] = (service),
static const ingest_fn k_ingest[] = {ROUTE_KINDS(INGEST_OF)};
static const uint16_t k_service[] = {ROUTE_KINDS(SERVICE_OF)};

/* Hand a frame to the service its route names (routes hold the kinds above only). */
static CO_INLINE void dispatch(co_node_t *node, uint16_t route, const co_frame_t *frame)
{
    k_ingest[node->route_kind[route]](node, node->route_slot[route], frame);
}

/* A frame whose service the NMT state does not allow now: dropped and counted, unless
 * it is the one that ends an LSS quiet time. */
static CO_FAST_NOINLINE void ingest_gated(co_node_t *node, uint16_t route, const co_frame_t *frame)
{
    if (co_lss_slave_resume(node, k_service[node->route_kind[route]])) {
        dispatch(node, route, frame);
    } else {
        CO_COUNT(node, rx_gated);
    }
}

/* A routed frame: to its service, or to the gate when the NMT state does not allow it. */
static CO_INLINE void deliver(co_node_t *node, uint16_t route, const co_frame_t *frame)
{
    if (!(node->services & k_service[node->route_kind[route]])) {
        ingest_gated(node, route, frame);
        return;
    }
    dispatch(node, route, frame);
}

void co_node_ingest(co_node_t *node, uint64_t now_us, const co_frame_t *frame)
{
    node->now_us = now_us;
    CO_COUNT(node, rx_frames);
    /* Above 29 bits or the frame's data: malformed. An identifier of 12..29 bits without the
     * EXT flag is malformed too, but matches no route (routes hold valid keys only), so it is
     * told apart from the unrouted ones off the common path. */
    if (frame->len > CO_FRAME_DATA_MAX || frame->id > CO_ID_EXT_MAX) {
        CO_COUNT(node, rx_malformed); /* no controller delivers this: never let it match */
        return;
    }
    uint16_t found = co_routes_find(node, co_route_key(frame));
    if (found == node->route_count) {
        if (!(frame->flags & CO_FRAME_EXT) && frame->id > CO_ID_STD_MAX) {
            CO_COUNT(node, rx_malformed);
        } else {
            CO_COUNT(node, rx_unrouted);
        }
        return;
    }
    deliver(node, found, frame);
}

/* ---- time */

/* Out of line: co_node_poll's idle path (below) then saves no registers. */
static CO_FAST_NOINLINE uint64_t poll_due(co_node_t *node, uint64_t now_us)
{
    node->now_us = now_us;
    if (node->txq_count) {
        co_txq_flush(node);
    }
    if (!node->started) {
        return CO_TIME_NEVER;
    }
    /* Services may schedule work while they run (a reset, a new watch): start from
     * "never" and let co_node_schedule lower it, then add what the services return.
     * Work one service scheduled for now while the pass ran (an SDO time-out that ends a
     * manager's boot step) is done by another pass, so the deadline returned lies ahead. */
    for (uint32_t pass = 0; pass < 3; pass++) {
        node->next_due_us = CO_TIME_NEVER;
        uint64_t next = co_lss_slave_poll(node, now_us); /* first: it may end a quiet time */
        next = co_min_u64(next, co_hb_poll(node, now_us));
        next = co_min_u64(next, co_guard_poll(node, now_us));
        next = co_min_u64(next, co_sdo_server_poll(node, now_us));
        next = co_min_u64(next, co_sdo_client_poll(node, now_us));
        next = co_min_u64(next, co_sync_poll(node, now_us));
        next = co_min_u64(next, co_emcy_poll(node, now_us));
        co_pdo_poll(node, now_us); /* (schedules its deadlines itself: less code) */
        next = co_min_u64(next, co_lss_master_poll(node, now_us));
        next = co_min_u64(next, co_manager_poll(node, now_us));
        next = co_min_u64(next, co_flash_poll(node, now_us));
        co_node_schedule(node, next);
        if (node->next_due_us > now_us) {
            break;
        }
    }
    return node->next_due_us;
}

uint64_t co_node_poll(co_node_t *node, uint64_t now_us)
{
    node->now_us = now_us; /* the clock the application's calls in between will use */
    if (now_us < node->next_due_us && node->txq_count == 0) {
        return node->next_due_us;
    }
    return poll_due(node, now_us);
}
