/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/errctl.h -- NMT error control: heartbeat and node guarding, both roles.
 *
 * Heartbeat producer: object 0x1017 (UNSIGNED16, ms). Every period the node sends
 * 0x700 + node-ID with one byte, its NMT state. A new value takes effect at once
 * (the next heartbeat is one new period after the write); 0 stops it.
 *
 * Heartbeat consumer: object 0x1016 sub1..N (UNSIGNED32: node-ID in bits 16..23,
 * time in ms in bits 0..15; node-ID 0 or time 0 = entry unused). Monitoring of a
 * node starts with its first heartbeat (CiA 301); from then on a silence longer
 * than the time is a timeout. Two entries with the same node-ID and a non-zero
 * time, or an entry naming the node itself, are refused with abort 0x06040043.
 *
 * Node guarding (legacy): a master sends RTR on 0x700 + n every guard time; the
 * node answers one byte, toggle bit 7 (0 first after reset communication, then
 * alternating) and its state in bits 0..6. The node answers only while its
 * heartbeat producer is off (0x1017 = 0; CiA 301: the two are exclusive). Its life
 * time is 0x100C guard time (ms) x 0x100D life time factor; monitoring starts with
 * the first RTR, and a silence longer than the life time is a life guarding event.
 * The master side (co_guard_watch) sends the RTRs and checks toggle and state.
 *
 * Events reach the application through co_node_config_t.on_errctl. A heartbeat
 * timeout or a life guarding event also applies the error behaviour of 0x1029
 * sub1 (0: to pre-operational if operational, 1: no change, 2: to stopped) and
 * is the place where EMCY 0x8130 is produced once EMCY exists.
 *
 * Cost: a received heartbeat is O(log routes) to find its consumer plus O(1).
 * Memory: 16 bytes per consumer entry, 24 per guarded node.
 */
#ifndef CANOLA_ERRCTL_H
#define CANOLA_ERRCTL_H

#include "canola/nmt.h"

#ifdef __cplusplus
extern "C" {
#endif

/** What happened to a monitored node (or, for CO_EC_LIFE_GUARD*, to this node). */
typedef enum co_ec_event_kind {
    CO_EC_BOOT = 1,           /**< boot-up received (first boot, or after a timeout) */
    CO_EC_REMOTE_RESET,       /**< boot-up from a node that had been seen running: it was reset */
    CO_EC_STARTED,            /**< first heartbeat received: monitoring runs */
    CO_EC_STATE_CHANGED,      /**< the node reports another NMT state */
    CO_EC_HB_TIMEOUT,         /**< heartbeat not received within the consumer time */
    CO_EC_HB_RESUMED,         /**< heartbeat received again after a timeout */
    CO_EC_NOT_BOOTED,         /**< nothing heard from a consumed node within the boot time */
    CO_EC_GUARD_TIMEOUT,      /**< master: no guarding reply within the life time */
    CO_EC_GUARD_TOGGLE,       /**< master: a guarding reply with the wrong toggle bit */
    CO_EC_GUARD_RESUMED,      /**< master: a good guarding reply after a timeout */
    CO_EC_LIFE_GUARD,         /**< this node: no guarding RTR within its life time */
    CO_EC_LIFE_GUARD_RESUMED, /**< this node: guarding RTRs arrive again */
    CO_EC_ID_COLLISION,       /**< this node: a boot-up or heartbeat on its own COB-ID 0x700 +
                                   node-ID (another node has the same node-ID; `state` is the
                                   byte heard, 0xFF if none); also EMCY 0x8150, once until
                                   the application clears it */
} co_ec_event_kind_t;

typedef struct co_ec_event {
    co_ec_event_kind_t kind;
    uint8_t node_id;  /**< the monitored node (this node's ID for life guarding) */
    uint8_t state;    /**< the node's NMT state now (last known on timeouts) */
    uint8_t previous; /**< the state known before this event */
} co_ec_event_t;

/** Watch of one heartbeat consumer entry; public only so the node can embed it. */
typedef struct co_hb_consumer {
    uint64_t deadline_us; /**< ACTIVE: time-out instant */
    uint16_t time_ms;     /**< 0 = entry unused */
    uint8_t node_id;      /**< 0 = entry unused */
    uint8_t watch;        /**< internal: CO_HB_WATCH_* */
    uint8_t state;        /**< last NMT state heard (CO_NMT_*), 0xFF = none since this node's
                               last reset communication (or the entry's last write) */
} co_hb_consumer_t;

/** Master-side node guarding of one remote node; embedded in the node. */
typedef struct co_guard_watch {
    uint64_t next_rtr_us;
    uint64_t life_deadline_us;
    uint16_t guard_ms; /**< 0 = slot unused */
    uint8_t node_id;
    uint8_t factor;
    uint8_t state;  /**< last state reported, 0xFF = none yet */
    uint8_t toggle; /**< toggle expected in the next reply, 0xFF = take any */
    bool lost;
} co_guard_watch_t;

/** Heartbeat consumer view: the last NMT state heard from `node_id` by this node's
 *  consumer, or 0xFF when the node is not consumed or has not been heard. O(n). */
uint8_t co_hb_remote_state(const co_node_t *node, uint8_t node_id);

/** Start node guarding `node_id` (1..127) from the master side: an RTR every guard_ms,
 *  a timeout after guard_ms * factor without a reply. Replaces an existing watch of the
 *  same node; guard_ms = 0 removes it. Returns CO_ERR_FULL when all CO_GUARD_WATCH_MAX
 *  slots are taken, CO_ERR_ARG for a bad node-ID (or this node's own) or a zero factor,
 *  CO_ERR_STATE when the
 *  heartbeat consumer already watches that node. */
co_err_t co_guard_watch(co_node_t *node, uint8_t node_id, uint16_t guard_ms, uint8_t factor);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_ERRCTL_H */
