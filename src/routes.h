/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/routes.h -- the receive routes (routes.c): which service takes the frames of a COB-ID.
 * Not installed; kernel.h includes it (every service sets its own routes).
 */
#ifndef CANOLA_ROUTES_H
#define CANOLA_ROUTES_H

#include "build.h"
#include "canola/node.h"

/* Route kinds, each with its slot (a channel, an entry, a PDO): one route per kind and slot.
 * When two owners share a key, the lower kind (then the lower slot) takes the frames. */
enum co_route_kind {
    CO_ROUTE_NMT = 1,     /* 0x000: NMT command */
    CO_ROUTE_GUARD_RTR,   /* own 0x700 + id: node guarding request (RTR) */
    CO_ROUTE_GUARD_REPLY, /* 0x700 + n: guarding reply of a guarded node (slot = watch) */
    CO_ROUTE_HB_CONSUMER, /* 0x700 + n: heartbeat of a consumed node (slot = consumer) */
    CO_ROUTE_SDO_SERVER,  /* an SDO server's request COB-ID (slot = channel) */
    CO_ROUTE_SDO_CLIENT,  /* an SDO client's response COB-ID (slot = channel) */
    CO_ROUTE_SYNC,        /* 0x1005 */
    CO_ROUTE_TIME,        /* 0x1012, when consuming */
    CO_ROUTE_EMCY,        /* a COB-ID of 0x1028 (slot = consumer entry) */
    CO_ROUTE_RPDO,        /* an RPDO's COB-ID (slot = RPDO) */
    CO_ROUTE_TPDO_RTR,    /* a TPDO's COB-ID, for remote requests (slot = TPDO) */
    CO_ROUTE_LSS_SLAVE,   /* 0x7E5: LSS request */
    CO_ROUTE_LSS_MASTER,  /* 0x7E4: LSS answer */
    CO_ROUTE_MGR_BOOTUP,  /* 0x700 + n of a slave the manager boots (slot = n) */
};

#define CO_ROUTE_OFF UINT32_MAX /* the key of no frame: no route */
/* The route of `kind` and `slot` takes the frames of `key` from now on (a route key: see
 * co_cob_key), in place of the key it had; CO_ROUTE_OFF: it goes. A full table drops a new
 * route. O(routes). */
void co_route_set(co_node_t *node, uint8_t kind, uint8_t slot, uint32_t key);
/* The position of the route that takes the frames of `key`: the first of its owners (the
 * routes are sorted by key, then owner), or route_count when none does. O(log routes). */
uint16_t co_routes_find(const co_node_t *node, uint32_t key);
/* The route key of a received frame. */
static inline uint32_t co_route_key(const co_frame_t *frame)
{
    return frame->id | ((frame->flags & CO_FRAME_EXT) ? 0x80000000u : 0u);
}

/* Bit of a route key in co_node_t.route_groups: its block of 64 identifiers, modulo 32. */
static inline uint32_t co_route_group(uint32_t key) { return 1u << ((key >> 6) & 31u); }

#endif /* CANOLA_ROUTES_H */
