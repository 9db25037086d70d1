/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/kernel.h -- what every service may use: COB-IDs, the receive routes (routes.h),
 * sending, the schedule and time, the dictionary's parameters; at the end, the calls up to
 * the node that CiA 301 makes necessary (the only ones). Not installed. The layers:
 * docs/architecture.md (the kernel and od.c at the bottom, the services, the node on top:
 * node.c, nmt.c, node_od.c, error_behaviour.c). A service calls down and sideways, up only as
 * listed at the end.
 */
#ifndef CANOLA_KERNEL_H
#define CANOLA_KERNEL_H

#include "build.h"
#include "canola/node.h"
#include "counters.h" /* CO_COUNT */
#include "routes.h"   /* the receive routes */

/* ---- COB-IDs: the values of the objects 0x1005, 0x1012, 0x1014, 0x1200.., 0x1400.. */

#define CO_COB_INVALID 0x80000000u /* bit 31: not valid (no frames) */
#define CO_COB_EXT 0x20000000u     /* bit 29: a 29-bit identifier */

/* A COB-ID value that names an identifier of its own format: an 11-bit one (bit 29 clear)
 * has nothing in bits 11..28. */
static inline bool co_cob_valid(uint32_t cob)
{
    return (cob & CO_COB_EXT) || (cob & 0x1FFFF800u) == 0;
}

/* The route key of a COB-ID value: the identifier, bit 31 marking a 29-bit one. */
static inline uint32_t co_cob_key(uint32_t cob)
{
    return (cob & CO_COB_EXT) ? ((cob & CO_ID_EXT_MAX) | 0x80000000u) : (cob & CO_ID_STD_MAX);
}

/* The route key of a COB-ID value, CO_ROUTE_OFF (routes.h) when bit 31 says "not valid". */
static inline uint32_t co_cob_route(uint32_t cob)
{
    return (cob & CO_COB_INVALID) ? CO_ROUTE_OFF : co_cob_key(cob);
}

/* ---- sending (txq.c) */

/* co_node_send for a service's frame (`service`: a co_service_t bit, 0 = none): refused with
 * CO_ERR_STATE when the NMT state does not allow it now, and dropped from the queue if the
 * state stops allowing it before the driver takes it. */
co_err_t co_node_send_as(co_node_t *node, const co_frame_t *frame, uint16_t service);
/* Send `len` (up to CO_FRAME_DATA_MAX) bytes of `data` on the identifier a COB-ID value names, as
 * co_node_send_as does; the frame's other data bytes are zero. */
co_err_t co_node_send_cob(co_node_t *node, uint32_t cob, const uint8_t *data, uint8_t len,
                          uint16_t service);
/* Address a frame of `len` bytes to a COB-ID value (its id, flags and length). */
static inline void co_frame_address(co_frame_t *frame, uint32_t cob, uint8_t len)
{
    frame->id = (cob & CO_COB_EXT) ? (cob & CO_ID_EXT_MAX) : (cob & CO_ID_STD_MAX);
    frame->flags = (cob & CO_COB_EXT) ? CO_FRAME_EXT : 0;
    frame->len = len;
}
/* Drop the waiting frames of services the NMT state does not allow (at every state change). */
void co_txq_purge(co_node_t *node);
/* Hand the waiting frames to the driver (co_node_poll). */
void co_txq_flush(co_node_t *node);
/* A frame the driver did not take: queued (CO_ERR_BUSY) or counted dropped, as co_node_send_as. */
co_err_t co_txq_refused(co_node_t *node, const co_frame_t *frame, uint16_t service, co_err_t err);

/* Nothing waits to be sent: a sender of many frames (block transfer) sends only then. */
static inline bool co_txq_idle(const co_node_t *node) { return node->txq_count == 0; }

/* ---- time and the schedule (kernel.c) */

/* Run co_node_poll again by `due_us` at the latest (a service's new deadline). O(1). */
void co_node_schedule(co_node_t *node, uint64_t due_us);

static inline uint64_t co_min_u64(uint64_t a, uint64_t b) { return a < b ? a : b; }
/* Milliseconds of a 16-bit object (a period, a time-out) in microseconds: they fit 32 bits,
 * so the multiply is a 32-bit one (no 64-bit helper call on Cortex-M0). */
static inline uint64_t co_ms_to_us(uint16_t ms)
{
    uint32_t us = (uint32_t)ms * 1000u; /* a 32-bit product (clang-tidy: no widening) */
    return us;
}
/* Any 32-bit count of milliseconds (guard time x life time factor) in microseconds. */
static inline uint64_t co_long_ms_to_us(uint32_t ms) { return (uint64_t)ms * 1000u; }

/* ---- the dictionary's parameters (kernel.c; entries found once: co_entry_uint, od_plain.h) */

/* The value of an optional integer entry, `absent` when the dictionary lacks it (or it is
 * no integer): the services' parameters, 32 bits at most. */
uint32_t co_od_u32(const co_node_t *node, uint16_t index, uint8_t sub, uint32_t absent);

/* ---- the services' objects: each service's internal header lists the rows of the objects
 * it owns in the communication area (a macro of CO_OBJECT_ROWs), node_od.c puts the lists
 * together and, on every write there, runs the owner's check and effect. */
typedef co_abort_t (*co_object_check_fn)(co_node_t *node, const co_od_entry_t *entry,
                                         const uint8_t *data, uint32_t len);
typedef void (*co_object_written_fn)(co_node_t *node, const co_od_entry_t *entry);
typedef struct co_object_row {
    unsigned first : 12; /* the objects 0x1000 + first .. + span */
    unsigned span : 12;
    unsigned cob : 8;             /* CO_COB_SUB*: the sub-indices holding a COB-ID */
    co_object_check_fn check;     /* refuse a value the service cannot take (NULL: none) */
    co_object_written_fn written; /* the new value takes effect (NULL: nothing to do) */
} co_object_row_t;
/* A bit per sub-index 0..6, bit 7 for 7 and above: a new COB-ID must name an identifier of
 * its own format (co_cob_valid). */
enum { CO_COB_NONE = 0x00, CO_COB_SUB0 = 0x01, CO_COB_SUB1_2 = 0x06, CO_COB_SUB1_UP = 0xFE };
#define CO_OBJECT_ROW(first, last, cob, check, written)                                            \
    {(first)-0x1000u, (last) - (first), (cob), (check), (written)},

/* Whether the network may read `entry` now: CO_ABORT_NO_DATA for a sub-index of 0x1003 above
 * the number of errors recorded (CiA 301 §7.5.2.4: no data), else CO_ABORT_NONE. O(1). */
co_abort_t co_od_read_check(const co_node_t *node, const co_od_entry_t *entry);

/* ---- the NMT gate: the services each state allows (co_nmt_services, canola/nmt.h; inline
 * for the state changes). The send and receive paths test node->services, set from it. */
static inline uint16_t co_nmt_gate(uint8_t state)
{
    uint16_t stopped = CO_SVC_NMT | CO_SVC_ERROR_CONTROL | CO_SVC_LSS;
    uint16_t pre = stopped | CO_SVC_SDO | CO_SVC_SYNC | CO_SVC_TIME | CO_SVC_EMCY;
    return state == CO_NMT_OPERATIONAL       ? (uint16_t)(pre | CO_SVC_PDO)
           : state == CO_NMT_PRE_OPERATIONAL ? pre
           : state == CO_NMT_STOPPED         ? stopped
           : state == CO_NMT_INITIALISING    ? (uint16_t)(CO_SVC_BOOTUP | CO_SVC_LSS)
                                             : (uint16_t)CO_SVC_LSS;
}

/* ---- calls up to the node: exactly the ones CiA 301 makes necessary
 *
 * Error control (heartbeat.c, hb_consumer.c, guarding.c) is part of the node's own loop
 * (error control -> error behaviour -> NMT -> every service): it names its calls
 * (error_behaviour.c). */
void co_node_ec_event(co_node_t *node, co_ec_event_kind_t kind, uint8_t node_id, uint8_t state,
                      uint8_t previous);
void co_node_comm_lost(co_node_t *node);    /* EMCY 0x8130, the error behaviour (0x1029) */
void co_node_comm_resumed(co_node_t *node); /* 0x8130 clears once nothing is lost any more */

/* Every other service reaches up through the node's wiring, filled by co_node_init (node.c):
 * it names no file above it. */
typedef struct co_node_wiring {
    /* An object write and its effects on the services (node_od.c): the SDO server's
     * downloads, the SDO client's local channel, the manager's 0x1016 entries. */
    co_abort_t (*write)(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                        uint32_t len);
    /* The error behaviour of 0x1029 sub1 (error_behaviour.c): an RPDO's deadline missed. */
    void (*error_behaviour)(co_node_t *node);
    /* NMT requests (nmt.c): LSS's reset communication with a new node-ID, the manager's
     * commands to the network and to its own node. */
    void (*nmt_reset)(co_node_t *node, bool application);
    co_err_t (*nmt_send)(co_node_t *node, co_nmt_cmd_t cmd, uint8_t target);
    co_err_t (*nmt_apply)(co_node_t *node, co_nmt_cmd_t cmd);
} co_node_wiring_t;

/* A whole new value for an entry, with checks, service effects and hooks (no access rights). */
static inline co_abort_t co_node_write(co_node_t *node, const co_od_entry_t *entry,
                                       const uint8_t *data, uint32_t len)
{
    return node->wiring->write(node, entry, data, len);
}

#endif /* CANOLA_KERNEL_H */
