/* SPDX-License-Identifier: Apache-2.0 */
/*
 * routes.c -- the receive routes: which service takes the frames of which COB-ID.
 *
 * A small array sorted by key, then owner (kind and slot), searched by bisection: frames are
 * dispatched in O(log routes) whatever the number of services. Each service sets and clears
 * its own routes when its COB-ID objects change (reset communication, a write, a new watch),
 * one per kind and slot. A key with two owners keeps both, side by side: the first, the
 * lower kind (routes.h orders the kinds), takes the frames; the other waits behind it and
 * takes over when the first goes.
 */
#include "kernel.h"

/* The owner of route i as one number, by which the owners of one key rank: the lower kind,
 * then the lower slot, comes first. */
static uint16_t owner_of(uint8_t kind, uint8_t slot)
{
    return (uint16_t)((unsigned)kind << 8 | slot);
}

static uint16_t owner_at(const co_node_t *node, unsigned i)
{
    return owner_of(node->route_kind[i], node->route_slot[i]);
}

/* The position of the route of `owner`, or route_count when it has none. */
static uint16_t owned(const co_node_t *node, uint16_t owner)
{
    uint16_t i = 0;
    while (i < node->route_count && owner_at(node, i) != owner) {
        i++;
    }
    return i;
}

/* Route i becomes (key, owner). */
static void put(co_node_t *node, unsigned i, uint32_t key, uint16_t owner)
{
    node->route_keys[i] = key;
    node->route_kind[i] = (uint8_t)(owner >> 8);
    node->route_slot[i] = (uint8_t)owner;
}

/* The routes in their order again (key, then owner): an insertion sort, as few routes are
 * out of place and this runs only on changes. */
static void sort(co_node_t *node)
{
    for (unsigned i = 1; i < node->route_count; i++) {
        uint32_t key = node->route_keys[i];
        uint16_t owner = owner_at(node, i);
        unsigned at = i;
        for (; at > 0; at--) {
            unsigned before = at - 1u;
            uint32_t k = node->route_keys[before];
            if (k < key || (k == key && owner_at(node, before) < owner)) {
                break; /* (no two routes have one owner) */
            }
            put(node, at, k, owner_at(node, before));
        }
        put(node, at, key, owner);
    }
}

void co_route_set(co_node_t *node, uint8_t kind, uint8_t slot, uint32_t key)
{
    uint16_t owner = owner_of(kind, slot);
    uint16_t i = owned(node, owner);
    if (i < node->route_count) {
        if (node->route_keys[i] == key) {
            return; /* nothing changes */
        }
    } else {
        if (key == CO_ROUTE_OFF || node->route_count >= CO_RX_ROUTES_MAX) {
            return; /* nothing changes, or a full table drops the new route */
        }
        node->route_count++;
    }
    put(node, i, key, owner);
    sort(node); /* a route going (CO_ROUTE_OFF, above every key) ends up last: it goes */
    if (key == CO_ROUTE_OFF) {
        node->route_count--;
    } else {
        /* (a route that goes leaves its bit: still a quick "no" for the other groups) */
        node->route_groups |= co_route_group(key);
    }
    /* The driver hears of the change. */
    if (node->cfg.driver.on_routes_changed) {
        node->cfg.driver.on_routes_changed(node->cfg.driver.ctx);
    }
}

uint16_t co_routes_find(const co_node_t *node, uint32_t key)
{
    uint32_t lo = 0;
    uint32_t hi = node->route_count;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        uint32_t k = node->route_keys[mid];
        if (k == key) {
            while (mid > 0 && node->route_keys[mid - 1] == key) {
                mid--; /* the first owner of the key takes its frames */
            }
            return (uint16_t)mid;
        }
        if (k < key) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return node->route_count;
}

bool co_node_accepts(const co_node_t *node, const co_frame_t *frame)
{
    /* A software acceptance filter sees mostly other nodes' frames: most fall in a block
     * of 64 identifiers the node has no route in, and leave after one test. */
    uint32_t key = co_route_key(frame);
    return (node->route_groups & co_route_group(key)) &&
           co_routes_find(node, key) < node->route_count;
}

uint32_t co_node_route_count(const co_node_t *node) { return node->route_count; }

uint32_t co_node_route_id(const co_node_t *node, uint32_t i)
{
    return i < node->route_count ? node->route_keys[i] : 0;
}
