/*
 * routes.c -- the receive routes: which service owns which COB-ID.
 *
 * A small array sorted by key, searched by bisection, rebuilt from the services'
 * configuration whenever a COB-ID object changes (reset communication, a write to
 * 0x1016, a new guarding watch). Frames are dispatched in O(log routes) whatever
 * the number of services.
 */
#include "internal.h"

static uint16_t kind_service(uint8_t kind)
{
    switch (kind) {
    case CO_ROUTE_NMT:
        return CO_SVC_NMT;
    case CO_ROUTE_SDO_SERVER:
    case CO_ROUTE_SDO_CLIENT:
        return CO_SVC_SDO;
    case CO_ROUTE_SYNC:
        return CO_SVC_SYNC;
    case CO_ROUTE_TIME:
        return CO_SVC_TIME;
    case CO_ROUTE_EMCY:
        return CO_SVC_EMCY;
    case CO_ROUTE_RPDO:
    case CO_ROUTE_TPDO_RTR:
        return CO_SVC_PDO;
    case CO_ROUTE_LSS_SLAVE:
    case CO_ROUTE_LSS_MASTER:
        return CO_SVC_LSS;
    default:
        return CO_SVC_ERROR_CONTROL;
    }
}

void co_routes_add(co_node_t *node, uint32_t key, uint8_t kind, uint8_t slot)
{
    if (node->route_count >= CO_RX_ROUTES_MAX || co_routes_find(node, key)) {
        return; /* a key has one owner; the first configured keeps it */
    }
    /* Insertion keeps the array sorted; n is small and this runs only on changes. */
    uint16_t at = node->route_count;
    while (at > 0 && node->routes[at - 1].key > key) {
        co_copy(&node->routes[at], &node->routes[at - 1], sizeof node->routes[0]);
        at--;
    }
    /* (co_copy and field by field: a struct copy would call memcpy on Cortex-M0) */
    co_route_t *r = &node->routes[at];
    r->key = key;
    r->service = kind_service(kind);
    r->kind = kind;
    r->slot = slot;
    node->route_count++;
    node->route_groups |= co_route_group(key);
}

void co_routes_add_cob(co_node_t *node, uint32_t cob, uint8_t kind, uint8_t slot)
{
    co_routes_add(node, co_cob_key(cob), kind, slot);
}

void co_routes_rebuild(co_node_t *node)
{
    node->route_count = 0;
    node->route_hint = 0;
    node->route_groups = 0;
    co_routes_add(node, 0x000, CO_ROUTE_NMT, 0);
    co_guard_add_routes(node); /* own guarding RTR, guarded nodes' replies */
    co_hb_consumers_add_routes(node);
    co_sdo_server_add_routes(node);
    co_sdo_client_add_routes(node);
    co_sync_add_routes(node);
    co_time_add_routes(node);
    co_emcy_add_routes(node);
    co_pdo_add_routes(node);
    if (CO_CONFIG_LSS_SLAVE) {
        co_routes_add(node, CO_LSS_COB_MASTER, CO_ROUTE_LSS_SLAVE, 0);
    }
    if (co_lss_master_listening(node)) {
        co_routes_add(node, CO_LSS_COB_SLAVE, CO_ROUTE_LSS_MASTER, 0);
    }
    co_manager_add_routes(node); /* last: a consumed node's heartbeat route comes first */
    if (node->cfg.driver.on_routes_changed) {
        node->cfg.driver.on_routes_changed(node->cfg.driver.ctx);
    }
}

const co_route_t *co_routes_find(const co_node_t *node, uint32_t key)
{
    uint32_t lo = 0;
    uint32_t hi = node->route_count;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        uint32_t k = node->routes[mid].key;
        if (k == key) {
            return &node->routes[mid];
        }
        if (k < key) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

bool co_node_accepts(const co_node_t *node, const co_frame_t *frame)
{
    /* A software acceptance filter sees mostly other nodes' frames: most fall in a block
     * of 64 identifiers the node has no route in, and leave after one test. */
    uint32_t key = co_route_key(frame);
    return (node->route_groups & co_route_group(key)) && co_routes_find(node, key) != NULL;
}

uint32_t co_node_route_count(const co_node_t *node) { return node->route_count; }

uint32_t co_node_route_id(const co_node_t *node, uint32_t i)
{
    return i < node->route_count ? node->routes[i].key : 0;
}
