/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/errctl_internal.h -- error control (see canola/errctl.h): the heartbeat producer
 * (heartbeat.c), the heartbeat consumer (hb_consumer.c, CO_HB_CONSUMERS_MAX > 0) and node
 * guarding (guarding.c, CO_CONFIG_GUARDING). Their events go up by name (kernel.h): error
 * control is part of the node's own loop. Not installed.
 */
#ifndef CANOLA_ERRCTL_INTERNAL_H
#define CANOLA_ERRCTL_INTERNAL_H

#include "kernel.h"
#include "od_plain.h"
#include "standin.h"

#define CO_STATE_NONE 0xFFu /* "no state heard yet" */

/* Heartbeat consumer watch states (co_hb_consumer_t.watch). */
enum co_hb_watch {
    CO_HB_WATCH_UNUSED = 0, /* entry off (node-ID or time 0) */
    CO_HB_WATCH_WAITING,    /* configured; monitoring starts at the next heartbeat */
    CO_HB_WATCH_ACTIVE,     /* monitoring: deadline_us is the time-out */
    CO_HB_WATCH_LOST,       /* timed out; a heartbeat resumes it */
};

/* heartbeat.c: the producer (0x1017); bind, reset and poll take the consumer along. */
co_err_t co_hb_bind(co_node_t *node);
void co_hb_reset_comm(co_node_t *node);
void co_hb_state_entered(co_node_t *node);
uint64_t co_hb_poll(co_node_t *node, uint64_t now_us);
void co_hb_written(co_node_t *node, const co_od_entry_t *entry); /* 0x1016, 0x1017 */
/* The frame on 0x700 + node-ID: a heartbeat (the state) or the boot-up (0, service 0). */
void co_hb_frame_send(co_node_t *node, uint8_t state, uint16_t service);

/* hb_consumer.c: the consumer (0x1016). */
#if CO_HB_CONSUMERS_MAX > 0
co_err_t co_hb_consumers_bind(co_node_t *node);
void co_hb_consumers_reset(co_node_t *node);
void co_hb_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_hb_consumers_poll(co_node_t *node, uint64_t now_us);
co_abort_t co_hb_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                             uint32_t len);
void co_hb_consumer_written(co_node_t *node, const co_od_entry_t *entry);
bool co_hb_consumer_lost(const co_node_t *node);             /* some consumed heartbeat is lost */
bool co_hb_consumes(const co_node_t *node, uint8_t node_id); /* an entry watches it */
#else
static inline co_err_t co_hb_consumers_bind(co_node_t *node)
{
    (void)node;
    return CO_OK; /* 0x1016, if any, is a plain entry */
}
#define co_hb_consumers_reset co_none_node
#define co_hb_ingest co_none_slot_frame
#define co_hb_consumers_poll co_none_poll
#define co_hb_check_write co_none_check
#define co_hb_consumer_written co_none_entry
#define co_hb_consumer_lost co_none_state
#define co_hb_consumes co_none_node_id
#endif

/* guarding.c: the node's answers and life guarding (0x100C, 0x100D), the master's watches. */
static inline uint8_t co_guard_watch_max(void) { return CO_GUARD_WATCH_MAX; } /* (may be 0) */
#if CO_CONFIG_GUARDING
void co_guard_bind(co_node_t *node);
void co_guard_reset_comm(co_node_t *node);
void co_guard_rtr(co_node_t *node, uint8_t slot, const co_frame_t *frame);
void co_guard_reply(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_guard_poll(co_node_t *node, uint64_t now_us);
void co_guard_written(co_node_t *node, const co_od_entry_t *entry); /* 0x100C, 0x100D */
bool co_guard_watches(const co_node_t *node, uint8_t node_id);      /* a master-side watch */
static inline bool co_guard_life_lost(const co_node_t *node) { return node->life_lost; }
#else
#define co_guard_bind co_none_node
#define co_guard_reset_comm co_none_node
#define co_guard_rtr co_none_slot_frame
#define co_guard_reply co_none_slot_frame
#define co_guard_poll co_none_poll
#define co_guard_written co_none_entry
#define co_guard_watches co_none_node_id
#define co_guard_life_lost co_none_state
#endif

/* Error control's objects (node_od.c): 0x1017 the heartbeat, 0x1016 its consumer's entries
 * and 0x100C/0x100D guarding, each where it is built. */
#if CO_HB_CONSUMERS_MAX > 0
#define CO_HB_CONSUMER_ROWS                                                                        \
    CO_OBJECT_ROW(0x1016, 0x1016, CO_COB_NONE, co_hb_check_write, co_hb_written)
#else
#define CO_HB_CONSUMER_ROWS
#endif
#if CO_CONFIG_GUARDING
#define CO_GUARD_ROWS CO_OBJECT_ROW(0x100C, 0x100D, CO_COB_NONE, NULL, co_guard_written)
#else
#define CO_GUARD_ROWS
#endif
#define CO_ERRCTL_OBJECT_ROWS                                                                      \
    CO_OBJECT_ROW(0x1017, 0x1017, CO_COB_NONE, NULL, co_hb_written)                                \
    CO_HB_CONSUMER_ROWS                                                                            \
    CO_GUARD_ROWS

#endif /* CANOLA_ERRCTL_INTERNAL_H */
