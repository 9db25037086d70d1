/*
 * src/internal.h -- what the core's modules tell each other. Not installed.
 */
#ifndef CANOLA_INTERNAL_H
#define CANOLA_INTERNAL_H

#include "canola/node.h"

/* Receive route kinds (co_route_t.kind). */
enum co_route_kind {
    CO_ROUTE_NMT = 1,     /* 0x000: NMT command */
    CO_ROUTE_GUARD_RTR,   /* own 0x700 + id: node guarding request (RTR) */
    CO_ROUTE_HB_CONSUMER, /* 0x700 + n: heartbeat of a consumed node (slot = consumer) */
    CO_ROUTE_GUARD_REPLY, /* 0x700 + n: guarding reply of a guarded node (slot = watch) */
};

/* Heartbeat consumer watch states (co_hb_consumer_t.watch). */
enum co_hb_watch {
    CO_HB_WATCH_UNUSED = 0, /* entry off (node-ID or time 0) */
    CO_HB_WATCH_WAITING,    /* configured; monitoring starts at the next heartbeat */
    CO_HB_WATCH_ACTIVE,     /* monitoring: deadline_us is the time-out */
    CO_HB_WATCH_LOST,       /* timed out; a heartbeat resumes it */
};

#define CO_STATE_NONE 0xFFu /* "no state heard yet" */

static inline uint64_t co_min_u64(uint64_t a, uint64_t b) { return a < b ? a : b; }
static inline uint64_t co_ms_to_us(uint32_t ms) { return (uint64_t)ms * 1000u; }

/* Integer value of an optional entry (0 when the OD lacks it). */
static inline uint64_t co_entry_uint(const co_od_entry_t *entry)
{
    return entry ? co_od_entry_uint(entry) : 0;
}

/* Route key: the identifier, bit 31 marking 29-bit identifiers. */
static inline uint32_t co_route_key(const co_frame_t *frame)
{
    return frame->id | ((frame->flags & CO_FRAME_EXT) ? 0x80000000u : 0u);
}

/* node.c */
void co_node_schedule(co_node_t *node, uint64_t due_us);
void co_node_ec_event(co_node_t *node, co_ec_event_kind_t kind, uint8_t node_id, uint8_t state,
                      uint8_t previous);
void co_node_comm_error(co_node_t *node);

/* routes.c */
void co_routes_rebuild(co_node_t *node);
const co_route_t *co_routes_find(const co_node_t *node, uint32_t key);

/* txq.c */
void co_txq_flush(co_node_t *node);

/* nmt.c */
void co_nmt_ingest(co_node_t *node, const co_frame_t *frame);
void co_nmt_reset(co_node_t *node, bool application);

/* heartbeat.c */
void co_hb_reset_comm(co_node_t *node);
void co_hb_state_entered(co_node_t *node);
void co_hb_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_hb_poll(co_node_t *node, uint64_t now_us);
co_abort_t co_hb_check_write(const co_node_t *node, const co_od_entry_t *entry,
                             const uint8_t *data, uint32_t len);
void co_hb_written(co_node_t *node, const co_od_entry_t *entry);
co_err_t co_hb_bind(co_node_t *node);

/* guarding.c */
void co_guard_reset_comm(co_node_t *node);
void co_guard_rtr(co_node_t *node, const co_frame_t *frame);
void co_guard_reply(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_guard_poll(co_node_t *node, uint64_t now_us);
void co_guard_written(co_node_t *node);

#endif /* CANOLA_INTERNAL_H */
