/* SPDX-License-Identifier: Apache-2.0 */
/*
 * hb_consumer.c -- the heartbeat consumer (0x1016 sub1..N, see canola/errctl.h). Left out
 * with CO_HB_CONSUMERS_MAX 0 (errctl_internal.h): 0x1016 is then a plain entry.
 */
#include "errctl_internal.h"

#if CO_HB_CONSUMERS_MAX > 0

static void consumer_decode(uint32_t value, uint8_t *node_id, uint16_t *time_ms)
{
    *node_id = (uint8_t)(value >> 16);
    *time_ms = (uint16_t)value;
}

/* (Re)load one consumer entry from its 0x1016 sub-index, with its route; monitoring waits
 * for the first heartbeat again. */
static void consumer_load(co_node_t *node, uint8_t slot)
{
    co_hb_consumer_t *c = &node->hb_consumers[slot];
    consumer_decode(co_od_u32(node, 0x1016, (uint8_t)(slot + 1), 0), &c->node_id, &c->time_ms);
    bool used = c->node_id >= 1 && c->node_id <= 127 && c->time_ms != 0;
    c->watch = used ? CO_HB_WATCH_WAITING : CO_HB_WATCH_UNUSED;
    c->state = CO_STATE_NONE;
    c->deadline_us = CO_TIME_NEVER;
    co_route_set(node, CO_ROUTE_HB_CONSUMER, slot, used ? 0x700u + c->node_id : CO_ROUTE_OFF);
}

co_err_t co_hb_consumers_bind(co_node_t *node)
{
    uint8_t count = 0;
    while (co_od_find(&node->cfg.od, 0x1016, (uint8_t)(count + 1), NULL) != NULL) {
        if (count == CO_HB_CONSUMERS_MAX || count == 127) {
            return CO_ERR_CONFIG;
        }
        count++;
    }
    node->hb_consumer_count = count;
    node->boot_deadline_us = CO_TIME_NEVER;
    return CO_OK;
}

void co_hb_consumers_reset(co_node_t *node)
{
    for (uint8_t i = 0; i < node->hb_consumer_count; i++) {
        consumer_load(node, i);
    }
    node->boot_deadline_us = CO_TIME_NEVER;
    if (node->cfg.boot_time_ms != 0 && node->hb_consumer_count != 0) {
        node->boot_deadline_us = node->now_us + co_ms_to_us(node->cfg.boot_time_ms);
        co_node_schedule(node, node->boot_deadline_us);
    }
}

static bool valid_state(uint8_t s)
{
    return s == CO_NMT_INITIALISING || s == CO_NMT_STOPPED || s == CO_NMT_OPERATIONAL ||
           s == CO_NMT_PRE_OPERATIONAL;
}

void co_hb_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    if (frame->flags & CO_FRAME_RTR) {
        return; /* a master guarding that node, not a heartbeat */
    }
    if (frame->len != 1 || !valid_state(frame->data[0])) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    co_hb_consumer_t *c = &node->hb_consumers[slot];
    uint8_t state = frame->data[0];
    uint8_t previous = c->state;
    bool was_running = previous != CO_STATE_NONE && previous != CO_NMT_INITIALISING;
    c->state = state;
    uint8_t watch = c->watch;
    bool back = watch == CO_HB_WATCH_LOST; /* heard again after a timeout */
    co_ec_event_kind_t event = CO_EC_STATE_CHANGED;
    if (state == CO_NMT_INITIALISING) {
        /* Boot-up: monitoring starts again with the node's first heartbeat. */
        c->watch = CO_HB_WATCH_WAITING;
        c->deadline_us = CO_TIME_NEVER;
        event = was_running ? CO_EC_REMOTE_RESET : CO_EC_BOOT;
        back = true; /* a lost node that boots is back */
    } else {
        c->watch = CO_HB_WATCH_ACTIVE;
        c->deadline_us = node->now_us + co_ms_to_us(c->time_ms);
        co_node_schedule(node, c->deadline_us);
        if (watch == CO_HB_WATCH_WAITING) {
            event = CO_EC_STARTED;
        } else if (back) {
            event = CO_EC_HB_RESUMED;
        } else if (state == previous) {
            return; /* nothing new */
        }
    }
    /* one call for every event: the events differ in kind only */
    co_node_ec_event(node, event, c->node_id, state, previous);
    if (back) {
        co_node_comm_resumed(node);
    }
}

uint64_t co_hb_consumers_poll(co_node_t *node, uint64_t now_us)
{
    uint64_t next = CO_TIME_NEVER;
    for (uint8_t i = 0; i < node->hb_consumer_count; i++) {
        co_hb_consumer_t *c = &node->hb_consumers[i];
        if (c->watch != CO_HB_WATCH_ACTIVE) {
            continue;
        }
        if (now_us >= c->deadline_us) {
            c->watch = CO_HB_WATCH_LOST;
            c->deadline_us = CO_TIME_NEVER;
            co_node_ec_event(node, CO_EC_HB_TIMEOUT, c->node_id, c->state, c->state);
            co_node_comm_lost(node);
        } else {
            next = co_min_u64(next, c->deadline_us);
        }
    }
    if (now_us >= node->boot_deadline_us) {
        node->boot_deadline_us = CO_TIME_NEVER;
        for (uint8_t i = 0; i < node->hb_consumer_count; i++) {
            const co_hb_consumer_t *c = &node->hb_consumers[i];
            if (c->watch != CO_HB_WATCH_UNUSED && c->state == CO_STATE_NONE) { /* never heard */
                co_node_ec_event(node, CO_EC_NOT_BOOTED, c->node_id, CO_STATE_NONE, CO_STATE_NONE);
            }
        }
    }
    return co_min_u64(next, node->boot_deadline_us);
}

bool co_hb_consumer_lost(const co_node_t *node)
{
    for (uint8_t i = 0; i < node->hb_consumer_count; i++) {
        if (node->hb_consumers[i].watch == CO_HB_WATCH_LOST) {
            return true;
        }
    }
    return false;
}

bool co_hb_consumes(const co_node_t *node, uint8_t node_id)
{
    for (uint8_t i = 0; i < node->hb_consumer_count; i++) {
        const co_hb_consumer_t *c = &node->hb_consumers[i];
        if (c->watch != CO_HB_WATCH_UNUSED && c->node_id == node_id) {
            return true;
        }
    }
    return false;
}

/* ---- object dictionary writes */

co_abort_t co_hb_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                             uint32_t len)
{
    if (entry->index != 0x1016 || entry->sub == 0 || len != 4) {
        return CO_ABORT_NONE;
    }
    uint8_t id;
    uint16_t time_ms;
    consumer_decode(co_get_u32(data), &id, &time_ms);
    if (id == 0 || time_ms == 0) {
        return CO_ABORT_NONE;
    }
    if (id == node->node_id) {
        return CO_ABORT_PARAM_INCOMPAT; /* a node does not consume its own heartbeat */
    }
    for (uint8_t i = 0; i < node->hb_consumer_count; i++) {
        if ((uint8_t)(i + 1) == entry->sub) {
            continue;
        }
        uint8_t other_id;
        uint16_t other_time;
        consumer_decode(co_od_u32(node, 0x1016, (uint8_t)(i + 1), 0), &other_id, &other_time);
        if (other_id == id && other_time != 0) {
            return CO_ABORT_PARAM_INCOMPAT;
        }
    }
    if (co_guard_watches(node, id)) {
        return CO_ABORT_PARAM_INCOMPAT; /* guarded already: one error control per node */
    }
    return CO_ABORT_NONE;
}

void co_hb_consumer_written(co_node_t *node, const co_od_entry_t *entry)
{
    if (entry->index == 0x1016 && entry->sub >= 1 && entry->sub <= node->hb_consumer_count) {
        consumer_load(node, (uint8_t)(entry->sub - 1));
    }
}

uint8_t co_hb_remote_state(const co_node_t *node, uint8_t node_id)
{
    for (uint8_t i = 0; i < node->hb_consumer_count; i++) {
        const co_hb_consumer_t *c = &node->hb_consumers[i];
        if (c->watch != CO_HB_WATCH_UNUSED && c->node_id == node_id) {
            return c->state;
        }
    }
    return CO_STATE_NONE;
}

#endif
