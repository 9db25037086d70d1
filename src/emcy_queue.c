/* SPDX-License-Identifier: Apache-2.0 */
/*
 * emcy_queue.c -- the EMCY inhibit time (0x1015, units of 100 us): frames raised faster
 * wait in a queue of CO_EMCY_QUEUE_LEN and leave one inhibit time apart, and frames raised
 * while the NMT state holds EMCY back leave on entering pre-operational or operational.
 * Left out with CO_EMCY_QUEUE_LEN 0 (emcy_internal.h: every frame then leaves at once).
 */
#include <string.h>

#include "emcy_internal.h"

#if CO_EMCY_QUEUE_LEN > 0

#define EMCY_INHIBIT_UNIT_US 100u

static uint64_t inhibit_us(const co_node_t *node)
{
    uint16_t units = (uint16_t)co_od_u32(node, 0x1015, 0, 0);
    uint32_t us = (uint32_t)units * EMCY_INHIBIT_UNIT_US; /* UNSIGNED16: a 32-bit product */
    return us;
}

/* Earliest time the next frame may leave (the inhibit time counts from the latest frame,
 * with the value 0x1015 has now, so a new inhibit time applies at once). */
static uint64_t producer_free_at(const co_node_t *node)
{
    if (node->emcy.last_us == CO_TIME_NEVER) {
        return 0;
    }
    return node->emcy.last_us + inhibit_us(node);
}

static void queue_pop(co_emcy_t *e)
{
    e->queue_count--;
    for (uint8_t i = 0; i < e->queue_count; i++) {
        co_copy(e->queue[i], e->queue[i + 1u], sizeof e->queue[0]);
    }
}

/* Send what waits and may leave now; returns when the next waiting frame may leave
 * (CO_TIME_NEVER when none waits, or while the NMT state holds EMCY back). */
uint64_t co_emcy_poll(co_node_t *node, uint64_t now_us)
{
    co_emcy_t *e = &node->emcy;
    if (e->queue_count == 0 || !(node->services & CO_SVC_EMCY)) {
        return CO_TIME_NEVER;
    }
    if (co_emcy_producer_off(node)) {
        e->queue_count = 0; /* 0x1014 set invalid behind the node's back: send nothing */
        return CO_TIME_NEVER;
    }
    while (e->queue_count > 0) {
        uint64_t free_at = producer_free_at(node);
        if (now_us < free_at) {
            return free_at;
        }
        co_emcy_frame_send(node, e->queue[0]);
        e->last_us = now_us;
        queue_pop(e);
    }
    return CO_TIME_NEVER;
}

void co_emcy_queue_emit(co_node_t *node, const uint8_t data[CO_EMCY_FRAME_LEN])
{
    co_emcy_t *e = &node->emcy;
    (void)co_emcy_poll(node, node->now_us); /* make room: frames due may leave first */
    if (e->queue_count >= CO_EMCY_QUEUE_LEN) {
        e->dropped++; /* the newest is the one lost: the queue keeps the order of events */
        return;
    }
    co_copy(e->queue[e->queue_count], data, CO_EMCY_FRAME_LEN);
    e->queue_count++;
    co_emcy_state_entered(node);
}

void co_emcy_queue_reset(co_node_t *node)
{
    node->emcy.last_us = CO_TIME_NEVER;
    if (co_emcy_producer_off(node)) {
        node->emcy.queue_count = 0;
    }
}

void co_emcy_queue_clear(co_node_t *node) { node->emcy.queue_count = 0; }

void co_emcy_state_entered(co_node_t *node)
{
    co_node_schedule(node, co_emcy_poll(node, node->now_us));
}

#endif
