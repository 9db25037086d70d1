/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/sync_internal.h -- the SYNC family (see canola/sync.h): the consumer (sync.c) and the
 * producer (sync_producer.c, CO_CONFIG_SYNC_PRODUCER). A SYNC taken goes on to the PDOs
 * (co_pdo_sync). Not installed.
 */
#ifndef CANOLA_SYNC_INTERNAL_H
#define CANOLA_SYNC_INTERNAL_H

#include "kernel.h"
#include "od_plain.h"
#include "standin.h"

/* sync.c: the consumer. */
void co_sync_reset_comm(co_node_t *node);
void co_sync_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
co_abort_t co_sync_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len);
void co_sync_written(co_node_t *node, const co_od_entry_t *entry); /* 0x1005..0x1007, 0x1019 */
/* A SYNC taken (received, or sent by this node's producer). */
void co_sync_handled(co_node_t *node, uint8_t counter);

/* co_sync_in_window, inline for the PDO paths that ask at every SYNC and synchronous RPDO. */
static inline bool co_sync_window_open(const co_node_t *node, uint64_t now_us)
{
    uint64_t last = node->sync.last_us;
    if (last == CO_TIME_NEVER || now_us < last) {
        return false;
    }
    uint32_t window = (uint32_t)co_entry_uint(&node->cfg.od, node->sync.window);
    return window == 0 || now_us - last < window;
}

/* Overflow value when SYNCs carry a counter, 0 when they carry no data (0x1019 is 0, or
 * the refused value 1 set natively). */
static inline uint8_t co_sync_overflow(const co_node_t *node)
{
    uint8_t n = (uint8_t)co_entry_uint(&node->cfg.od, node->sync.overflow);
    return n >= 2 ? n : 0;
}

/* sync_producer.c: the producer. */
#if CO_CONFIG_SYNC_PRODUCER
uint64_t co_sync_poll(co_node_t *node, uint64_t now_us);
void co_sync_state_entered(co_node_t *node);
void co_sync_producer_reset(co_node_t *node);
void co_sync_producer_written(co_node_t *node, uint16_t index);
uint32_t co_sync_producer_period(const co_node_t *node); /* 0x1006, us */
#else
#define co_sync_poll co_none_poll
#define co_sync_state_entered co_none_node
#define co_sync_producer_reset co_none_node
static inline void co_sync_producer_written(co_node_t *node, uint16_t index)
{
    (void)node;
    (void)index;
}
static inline uint32_t co_sync_producer_period(const co_node_t *node)
{
    (void)node;
    return 0; /* 0x1006 has no effect: 0x1019 may always change */
}
#endif

/* The SYNC's objects (node_od.c): 0x1005 its COB-ID, 0x1019 the counter overflow; 0x1006
 * and 0x1007, the producer's period and window, where the producer is built. */
#if CO_CONFIG_SYNC_PRODUCER
#define CO_SYNC_PRODUCER_ROWS CO_OBJECT_ROW(0x1006, 0x1007, CO_COB_NONE, NULL, co_sync_written)
#else
#define CO_SYNC_PRODUCER_ROWS
#endif
#define CO_SYNC_OBJECT_ROWS                                                                        \
    CO_OBJECT_ROW(0x1005, 0x1005, CO_COB_SUB0, NULL, co_sync_written)                              \
    CO_SYNC_PRODUCER_ROWS                                                                          \
    CO_OBJECT_ROW(0x1019, 0x1019, CO_COB_NONE, co_sync_check_write, co_sync_written)

#endif /* CANOLA_SYNC_INTERNAL_H */
