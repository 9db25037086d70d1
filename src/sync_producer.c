/* SPDX-License-Identifier: Apache-2.0 */
/*
 * sync_producer.c -- the SYNC producer (0x1005 bit 30, 0x1006 period, the counter of
 * 0x1019; see canola/sync.h). Left out with CO_CONFIG_SYNC_PRODUCER 0 (sync_internal.h).
 */
#include "sync_internal.h"

#if CO_CONFIG_SYNC_PRODUCER

#define SYNC_PRODUCER 0x40000000u /* 0x1005 bit 30 */

uint32_t co_sync_producer_period(const co_node_t *node)
{
    return (uint32_t)co_entry_uint(&node->cfg.od, node->sync.period);
}

static CO_SIZE_INLINE bool producer_enabled(const co_node_t *node)
{
    return (node->sync.cob_id & SYNC_PRODUCER) && (node->services & CO_SVC_SYNC) &&
           co_sync_producer_period(node) != 0;
}

/* Start, keep or stop the producer as configuration and NMT state now say. A producer
 * that starts (or `restart`s for a new period) sends its first SYNC one period from now;
 * one that keeps running keeps its cadence. A fresh start counts from 1 again. */
static void producer_update(co_node_t *node, bool restart)
{
    co_sync_t *s = &node->sync;
    if (!producer_enabled(node)) {
        s->next_us = CO_TIME_NEVER;
        return;
    }
    bool running = s->next_us != CO_TIME_NEVER;
    if (running && !restart) {
        return;
    }
    if (!running) {
        s->counter = 1;
    }
    s->next_us = node->now_us + co_sync_producer_period(node);
    co_node_schedule(node, s->next_us);
}

static void produce(co_node_t *node)
{
    co_sync_t *s = &node->sync;
    uint8_t overflow = co_sync_overflow(node);
    uint8_t counter = 0;
    if (overflow) {
        if (s->counter == 0 || s->counter > overflow) {
            s->counter = 1; /* the overflow value shrank behind our back */
        }
        counter = s->counter;
        s->counter = counter == overflow ? 1 : (uint8_t)(counter + 1);
    }
    co_node_send_cob(node, s->cob_id, &counter, overflow ? 1 : 0, CO_SVC_SYNC);
    co_sync_handled(node, counter); /* a node does not receive its own frames */
}

uint64_t co_sync_poll(co_node_t *node, uint64_t now_us)
{
    co_sync_t *s = &node->sync;
    if (now_us < s->next_us) {
        return s->next_us;
    }
    if (!producer_enabled(node)) { /* configuration changed without a write through the node */
        s->next_us = CO_TIME_NEVER;
        return CO_TIME_NEVER;
    }
    produce(node);
    uint32_t period = co_sync_producer_period(node);
    s->next_us += period;
    if (s->next_us <= now_us) { /* polled late: keep the period, drop the missed SYNCs */
        s->next_us = now_us + period;
    }
    return s->next_us;
}

void co_sync_producer_reset(co_node_t *node)
{
    co_sync_t *s = &node->sync;
    s->period = co_od_find(&node->cfg.od, 0x1006, 0, NULL); /* absent: 0, feature off */
    s->next_us = CO_TIME_NEVER; /* initialising: starts on entering pre-operational */
    s->counter = 1;
}

void co_sync_state_entered(co_node_t *node) { producer_update(node, false); }

void co_sync_producer_written(co_node_t *node, uint16_t index)
{
    switch (index) {
    case 0x1005:
        producer_update(node, false);
        break;
    case 0x1006:
        producer_update(node, true);
        break;
    case 0x1019:
        node->sync.counter = 1;
        break;
    default:
        break;
    }
}

#endif
