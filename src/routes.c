/*
 * routes.c -- the receive routes: which service takes the frames of which COB-ID.
 *
 * A small array sorted by key (then kind and slot), searched by bisection: frames are
 * dispatched in O(log routes) whatever the number of services. Each service sets and clears
 * its own routes when its COB-ID objects change (reset communication, a write, a new watch),
 * one per kind and slot. A key with two owners keeps both: the lower kind (kernel.h orders
 * the kinds) takes the frames, the other waits behind it, its key marked SHADOW (a bit no
 * frame's key has, so the search never finds it), and takes over when the first goes.
 */
#include "kernel.h"

#define SHADOW 0x40000000u /* a route waiting behind another owner of its key */

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

/* The place of the route of `kind` and `slot`, or route_count when it has none. */
static uint16_t owned(const co_node_t *node, uint8_t kind, uint8_t slot)
{
    uint16_t i = 0;
    while (i < node->route_count &&
           (node->routes[i].kind != kind || node->routes[i].slot != slot)) {
        i++;
    }
    return i;
}

/* Route `r` comes before (key, kind, slot). */
static bool before(const co_route_t *r, uint32_t key, uint8_t kind, uint8_t slot)
{
    if (r->key != key) {
        return r->key < key;
    }
    return r->kind != kind ? r->kind < kind : r->slot < slot;
}

static void remove_at(co_node_t *node, uint16_t at)
{
    node->route_count--;
    for (uint16_t i = at; i < node->route_count; i++) {
        co_copy(&node->routes[i], &node->routes[i + 1u], sizeof node->routes[0]);
    }
}

/* The set of routes changed: the hint starts over at the first route (the first of its key,
 * as a hint must be), and the driver hears of it. */
static void changed(co_node_t *node)
{
    node->route_hint = 0;
    if (node->cfg.driver.on_routes_changed) {
        node->cfg.driver.on_routes_changed(node->cfg.driver.ctx);
    }
}

/* Insert a route where its order puts it (the caller made room). */
static void insert(co_node_t *node, uint32_t key, uint8_t kind, uint8_t slot)
{
    /* Insertion keeps the array sorted; n is small and this runs only on changes. */
    uint16_t at = node->route_count;
    while (at > 0 && !before(&node->routes[at - 1u], key, kind, slot)) {
        co_copy(&node->routes[at], &node->routes[at - 1u], sizeof node->routes[0]);
        at--;
    }
    /* (co_copy and field by field: a struct copy would call memcpy on Cortex-M0) */
    co_route_t *r = &node->routes[at];
    r->key = key;
    r->service = kind_service(kind);
    r->kind = kind;
    r->slot = slot;
    node->route_count++;
    /* (a route that goes leaves its bit: still a quick "no" for the other groups) */
    node->route_groups |= co_route_group(key);
}

/* Route `at` moves to `key` (its place in the order with it). */
static void rekey(co_node_t *node, uint16_t at, uint32_t key)
{
    uint8_t kind = node->routes[at].kind;
    uint8_t slot = node->routes[at].slot;
    remove_at(node, at);
    insert(node, key, kind, slot);
}

/* The owner of `key` went: the first that waits behind it (the lowest kind: the order puts
 * it first) takes the frames. */
static void next_owner(co_node_t *node, uint32_t key)
{
    for (uint16_t i = 0; i < node->route_count; i++) {
        if (node->routes[i].key == (key | SHADOW)) {
            rekey(node, i, key);
            return;
        }
    }
}

/* A new route of `key`: it takes the frames, unless an owner of a lower kind has them. */
static void add(co_node_t *node, uint8_t kind, uint8_t slot, uint32_t key)
{
    if (node->route_count >= CO_RX_ROUTES_MAX) {
        return; /* a full table drops the route */
    }
    const co_route_t *owner = co_routes_find(node, key);
    if (owner != NULL && !before(owner, key, kind, slot)) {
        rekey(node, (uint16_t)(owner - node->routes), key | SHADOW); /* it waits now */
        owner = NULL;
    }
    insert(node, owner != NULL ? key | SHADOW : key, kind, slot);
}

void co_route_set(co_node_t *node, uint8_t kind, uint8_t slot, uint32_t key)
{
    uint16_t at = owned(node, kind, slot);
    bool had = at < node->route_count;
    if (had ? (node->routes[at].key & ~SHADOW) == key : key == CO_ROUTE_OFF) {
        return; /* nothing changes */
    }
    if (had) {
        uint32_t old = node->routes[at].key;
        remove_at(node, at);
        if (!(old & SHADOW)) {
            next_owner(node, old);
        }
    }
    if (key != CO_ROUTE_OFF) {
        add(node, kind, slot, key);
    }
    changed(node);
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
    return i < node->route_count ? node->routes[i].key & ~SHADOW : 0;
}
