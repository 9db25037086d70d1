/* SPDX-License-Identifier: Apache-2.0 */
/*
 * sync.c -- the SYNC consumer (0x1005, 0x1007, 0x1019); the producer (0x1005 bit 30,
 * 0x1006) is sync_producer.c, left out with CO_CONFIG_SYNC_PRODUCER 0.
 *
 * co_sync_t keeps the COB-ID and the entries of period, window and counter overflow,
 * found once per reset communication; their values are read when needed, so a new value
 * counts from the next use on, without a look-up per SYNC.
 */
#include "pdo_internal.h" /* co_pdo_sync */
#include "sync_internal.h"

#define SYNC_EMCY_LENGTH 0x8240u /* unexpected SYNC data length */

/* ---- consumer (the producer hands its own SYNC here too) */

void co_sync_handled(co_node_t *node, uint8_t counter)
{
    node->sync.last_us = node->now_us;
    node->sync.last_counter = counter;
    co_pdo_sync(node, counter);
    if (node->cfg.on_sync) {
        node->cfg.on_sync(node->cfg.user, counter);
    }
}

void co_sync_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)slot;
    if (frame->flags & CO_FRAME_RTR) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    bool with_counter = co_sync_overflow(node) != 0;
    if (frame->len != (with_counter ? 1u : 0u)) {
        CO_COUNT(node, rx_malformed);
        (void)co_emcy_raise(node, SYNC_EMCY_LENGTH, NULL);
        return;
    }
    co_sync_handled(node, with_counter ? frame->data[0] : 0);
}

bool co_sync_in_window(const co_node_t *node, uint64_t now_us)
{
    return co_sync_window_open(node, now_us);
}

uint8_t co_sync_counter(const co_node_t *node) { return node->sync.last_counter; }

/* ---- lifecycle and object dictionary */

/* The SYNC consumer's route: every node with 0x1005 consumes SYNC; bit 31 means nothing for
 * this object. */
static void route(co_node_t *node, bool present)
{
    co_route_set(node, CO_ROUTE_SYNC, 0, present ? co_cob_key(node->sync.cob_id) : CO_ROUTE_OFF);
}

void co_sync_reset_comm(co_node_t *node)
{
    co_sync_t *s = &node->sync;
    const co_od_entry_t *cob = co_od_find(&node->cfg.od, 0x1005, 0, NULL);
    s->cob_id = (uint32_t)co_entry_uint(&node->cfg.od, cob); /* absent: 0 */
    s->window = co_od_find(&node->cfg.od, 0x1007, 0, NULL);  /* absent: no window */
    s->overflow = co_od_find(&node->cfg.od, 0x1019, 0, NULL);
    s->last_us = CO_TIME_NEVER;
    s->last_counter = 0;
    co_sync_producer_reset(node);
    route(node, cob != NULL);
}

co_abort_t co_sync_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len)
{
    if (entry->index != 0x1019 || len < 1) {
        return CO_ABORT_NONE;
    }
    if (co_sync_producer_period(node) != 0) {
        return CO_ABORT_DATA_STATE; /* the counter may not change under running SYNCs */
    }
    return (data[0] == 1 || data[0] > 240) ? CO_ABORT_VALUE : CO_ABORT_NONE;
}

void co_sync_written(co_node_t *node, const co_od_entry_t *entry)
{
    co_sync_t *s = &node->sync;
    if (entry->index == 0x1005) {
        s->cob_id = (uint32_t)co_od_entry_uint(&node->cfg.od, entry);
        route(node, true); /* (the same: no change) */
    }
    co_sync_producer_written(node, entry->index); /* 0x1007 is read at each use */
}
