/* SPDX-License-Identifier: Apache-2.0 */
/*
 * heartbeat.c -- the heartbeat producer (0x1017). The consumer (0x1016) is
 * hb_consumer.c, left out with CO_HB_CONSUMERS_MAX 0.
 */
#include "errctl_internal.h"

#define HB_COB_BASE 0x700u

static CO_SIZE_NOINLINE uint16_t producer_period_ms(const co_node_t *node)
{
    return (uint16_t)co_entry_uint(&node->cfg.od, node->hb_period);
}

/* The producer runs from boot-up on, in every state but initialisation. */
static void producer_schedule(co_node_t *node)
{
    uint16_t period = producer_period_ms(node);
    if (period == 0 || node->nmt_state == CO_NMT_INITIALISING) {
        node->hb_next_us = CO_TIME_NEVER;
        return;
    }
    node->hb_next_us = node->now_us + co_ms_to_us(period);
    co_node_schedule(node, node->hb_next_us);
}

void co_hb_state_entered(co_node_t *node) { producer_schedule(node); }

static uint64_t producer_poll(co_node_t *node, uint64_t now_us)
{
    if (now_us < node->hb_next_us) {
        return node->hb_next_us;
    }
    co_hb_frame_send(node, node->nmt_state, CO_SVC_ERROR_CONTROL);
    uint64_t period_us = co_ms_to_us(producer_period_ms(node));
    node->hb_next_us += period_us;
    if (node->hb_next_us <= now_us) { /* polled late: keep the period, drop the missed beats */
        node->hb_next_us = now_us + period_us;
    }
    return node->hb_next_us;
}

void co_hb_frame_send(co_node_t *node, uint8_t state, uint16_t service)
{
    (void)co_node_send_cob(node, HB_COB_BASE + node->node_id, &state, 1, service);
}

co_err_t co_hb_bind(co_node_t *node)
{
    node->hb_period = co_od_find(&node->cfg.od, 0x1017, 0, NULL);
    return co_hb_consumers_bind(node);
}

void co_hb_reset_comm(co_node_t *node)
{
    co_hb_consumers_reset(node);
    node->hb_next_us = CO_TIME_NEVER;
}

uint64_t co_hb_poll(co_node_t *node, uint64_t now_us)
{
    uint64_t next = producer_poll(node, now_us);
    return co_min_u64(next, co_hb_consumers_poll(node, now_us));
}

void co_hb_written(co_node_t *node, const co_od_entry_t *entry)
{
    if (entry->index == 0x1017) {
        producer_schedule(node);
    } else {
        co_hb_consumer_written(node, entry);
    }
}

#if CO_HB_CONSUMERS_MAX == 0
uint8_t co_hb_remote_state(const co_node_t *node, uint8_t node_id)
{
    (void)node;
    (void)node_id;
    return CO_STATE_NONE; /* no consumer in this build */
}
#endif
