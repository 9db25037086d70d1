/*
 * sync.c -- SYNC producer and consumer (0x1005, 0x1006, 0x1007, 0x1019).
 *
 * co_sync_t keeps the COB-ID and the entries of period, window and counter overflow,
 * found once per reset communication; their values are read when needed, so a new value
 * counts from the next use on, without a look-up per SYNC.
 */
#include "internal.h"

#define SYNC_PRODUCER 0x40000000u /* 0x1005 bit 30 */
#define SYNC_EMCY_LENGTH 0x8240u  /* unexpected SYNC data length */

static uint32_t od_value(const co_node_t *node, uint16_t index)
{
    uint64_t v = 0;
    (void)co_od_get_uint(&node->cfg.od, index, 0, &v); /* absent: 0, the feature is off */
    return (uint32_t)v;
}

static uint32_t period_us(const co_node_t *node)
{
    return (uint32_t)co_entry_uint(node->sync.period);
}

/* Overflow value when SYNCs carry a counter, 0 when they carry no data (0x1019 is 0, or
 * the refused value 1 set natively). */
static uint8_t counter_overflow(const co_node_t *node)
{
    uint8_t n = (uint8_t)co_entry_uint(node->sync.overflow);
    return n >= 2 ? n : 0;
}

/* ---- consumer (the producer hands its own SYNC here too) */

static void sync_handled(co_node_t *node, uint8_t counter)
{
    node->sync.last_us = node->now_us;
    node->sync.last_counter = counter;
    co_pdo_sync(node, counter);
    if (node->cfg.on_sync) {
        node->cfg.on_sync(node->cfg.user, counter);
    }
}

void co_sync_ingest(co_node_t *node, const co_frame_t *frame)
{
    if (frame->flags & CO_FRAME_RTR) {
        node->stats.rx_malformed++;
        return;
    }
    bool with_counter = counter_overflow(node) != 0;
    if (frame->len != (with_counter ? 1u : 0u)) {
        node->stats.rx_malformed++;
        (void)co_emcy_raise(node, SYNC_EMCY_LENGTH, NULL);
        return;
    }
    sync_handled(node, with_counter ? frame->data[0] : 0);
}

bool co_sync_in_window(const co_node_t *node, uint64_t now_us)
{
    return co_sync_window_open(node, now_us);
}

uint8_t co_sync_counter(const co_node_t *node) { return node->sync.last_counter; }

/* ---- producer */

static bool producer_enabled(const co_node_t *node)
{
    return (node->sync.cob_id & SYNC_PRODUCER) && (node->services & CO_SVC_SYNC) &&
           period_us(node) != 0;
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
    s->next_us = node->now_us + period_us(node);
    co_node_schedule(node, s->next_us);
}

static void produce(co_node_t *node)
{
    co_sync_t *s = &node->sync;
    uint8_t overflow = counter_overflow(node);
    co_frame_t f = co_cob_frame(s->cob_id, overflow ? 1 : 0);
    uint8_t counter = 0;
    if (overflow) {
        if (s->counter == 0 || s->counter > overflow) {
            s->counter = 1; /* the overflow value shrank behind our back */
        }
        counter = s->counter;
        s->counter = counter == overflow ? 1 : (uint8_t)(counter + 1);
        f.data[0] = counter;
    }
    co_node_send_as(node, &f, CO_SVC_SYNC);
    sync_handled(node, counter); /* a node does not receive its own frames */
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
    uint32_t period = period_us(node);
    s->next_us += period;
    if (s->next_us <= now_us) { /* polled late: keep the period, drop the missed SYNCs */
        s->next_us = now_us + period;
    }
    return s->next_us;
}

/* ---- lifecycle and object dictionary */

void co_sync_reset_comm(co_node_t *node)
{
    co_sync_t *s = &node->sync;
    s->cob_id = od_value(node, 0x1005);
    s->period = co_od_find(&node->cfg.od, 0x1006, 0, NULL); /* absent: 0, feature off */
    s->window = co_od_find(&node->cfg.od, 0x1007, 0, NULL);
    s->overflow = co_od_find(&node->cfg.od, 0x1019, 0, NULL);
    s->next_us = CO_TIME_NEVER; /* initialising: starts on entering pre-operational */
    s->last_us = CO_TIME_NEVER;
    s->counter = 1;
    s->last_counter = 0;
}

void co_sync_add_routes(co_node_t *node)
{
    /* Every node with 0x1005 consumes SYNC; bit 31 means nothing for this object. */
    if (co_od_find(&node->cfg.od, 0x1005, 0, NULL) != NULL) {
        co_routes_add(node, co_cob_key(node->sync.cob_id), CO_ROUTE_SYNC, 0);
    }
}

void co_sync_state_entered(co_node_t *node) { producer_update(node, false); }

co_abort_t co_sync_check_write(const co_node_t *node, const co_od_entry_t *entry,
                               const uint8_t *data, uint32_t len)
{
    if (entry->index != 0x1019 || len < 1) {
        return CO_ABORT_NONE;
    }
    if (period_us(node) != 0) {
        return CO_ABORT_DATA_STATE; /* the counter may not change under running SYNCs */
    }
    return (data[0] == 1 || data[0] > 240) ? CO_ABORT_VALUE : CO_ABORT_NONE;
}

void co_sync_written(co_node_t *node, const co_od_entry_t *entry)
{
    co_sync_t *s = &node->sync;
    switch (entry->index) {
    case 0x1005: {
        uint32_t old = s->cob_id;
        s->cob_id = (uint32_t)co_od_entry_uint(entry);
        if (co_cob_key(old) != co_cob_key(s->cob_id)) {
            co_routes_rebuild(node);
        }
        producer_update(node, false);
        break;
    }
    case 0x1006:
        producer_update(node, true);
        break;
    case 0x1019:
        s->counter = 1;
        break;
    default: /* 0x1007 is read at each use */
        break;
    }
}
