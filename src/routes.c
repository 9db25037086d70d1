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

/* The route of `kind` and `slot`, or NULL when it has none. */
static co_route_t *owned(co_node_t *node, uint8_t kind, uint8_t slot)
{
    for (co_route_t *r = node->routes; r < node->routes + node->route_count; r++) {
        if (r->kind == kind && r->slot == slot) {
            return r;
        }
    }
    return NULL;
}

/* Route `a` comes before route `b` among the owners of one key: the lower kind, then slot. */
static bool lower(const co_route_t *a, const co_route_t *b)
{
    return a->kind != b->kind ? a->kind < b->kind : a->slot < b->slot;
}

/* The routes of `key` (none: CO_ROUTE_OFF, which no masked key equals): the lowest takes
 * the frames, the others wait behind it, their key marked SHADOW. */
static void settle(co_node_t *node, uint32_t key)
{
    co_route_t *owner = NULL;
    for (co_route_t *r = node->routes; r < node->routes + node->route_count; r++) {
        if ((r->key & ~SHADOW) == key) {
            r->key = key | SHADOW;
            owner = owner == NULL || lower(r, owner) ? r : owner;
        }
    }
    if (owner != NULL) {
        owner->key = key;
    }
}

/* Route `a` may come before route `b` in the table: key, then kind and slot. */
static CO_SIZE_NOINLINE bool in_order(const co_route_t *a, const co_route_t *b)
{
    return a->key != b->key ? a->key < b->key : lower(a, b);
}

/* The routes in their order again: an insertion sort, as few routes are out of place and
 * this runs only on changes. (co_copy, not struct copies: those would call memcpy on
 * Cortex-M0.) */
static void sort(co_node_t *node)
{
    for (uint16_t i = 1; i < node->route_count; i++) {
        if (in_order(&node->routes[i - 1u], &node->routes[i])) {
            continue; /* in place: most are */
        }
        co_route_t r;
        co_copy(&r, &node->routes[i], sizeof r);
        uint16_t at = i;
        for (; at > 0 && !in_order(&node->routes[at - 1u], &r); at--) {
            co_copy(&node->routes[at], &node->routes[at - 1u], sizeof r);
        }
        co_copy(&node->routes[at], &r, sizeof r);
    }
}

void co_route_set(co_node_t *node, uint8_t kind, uint8_t slot, uint32_t key)
{
    co_route_t *r = owned(node, kind, slot);
    uint32_t old = CO_ROUTE_OFF;
    if (r != NULL) {
        old = r->key & ~SHADOW;
        if (old == key) {
            return; /* nothing changes */
        }
    } else {
        if (key == CO_ROUTE_OFF || node->route_count >= CO_RX_ROUTES_MAX) {
            return; /* nothing changes, or a full table drops the new route */
        }
        r = &node->routes[node->route_count++];
        r->service = kind_service(kind);
        r->kind = kind;
        r->slot = slot;
    }
    r->key = key;
    settle(node, old); /* its next owner takes the frames */
    settle(node, key);
    sort(node); /* a route going (CO_ROUTE_OFF, above every key) ends up last: it goes */
    if (key == CO_ROUTE_OFF) {
        node->route_count--;
    } else {
        /* (a route that goes leaves its bit: still a quick "no" for the other groups) */
        node->route_groups |= co_route_group(key);
    }
    /* The hint starts over at the first route (the first of its key, as a hint must be),
     * and the driver hears of the change. */
    node->route_hint = 0;
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
    return i < node->route_count ? node->routes[i].key & ~SHADOW : 0;
}
