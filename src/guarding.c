/* SPDX-License-Identifier: Apache-2.0 */
/*
 * guarding.c -- node guarding: the node's answers to guarding RTRs and its life
 * guarding (0x100C x 0x100D), and the master's watch of guarded nodes.
 */
#include "errctl_internal.h"

#if CO_CONFIG_GUARDING

#define GUARD_COB_BASE 0x700u

/* ---- slave side */

static uint64_t life_time_us(const co_node_t *node)
{
    uint64_t guard_ms = co_entry_uint(&node->cfg.od, node->guard_time);
    uint64_t factor = co_entry_uint(&node->cfg.od, node->life_factor);
    return co_long_ms_to_us((uint32_t)(guard_ms * factor));
}

void co_guard_bind(co_node_t *node)
{
    node->life_deadline_us = CO_TIME_NEVER;
    node->guard_time = co_od_find(&node->cfg.od, 0x100C, 0, NULL);
    node->life_factor = co_od_find(&node->cfg.od, 0x100D, 0, NULL);
}

void co_guard_reset_comm(co_node_t *node)
{
    node->guard_toggle = 0; /* the first answer after reset communication has toggle 0 */
    node->life_guarding = false;
    node->life_lost = false;
    node->life_deadline_us = CO_TIME_NEVER;
    /* the guarding requests to this node-ID (an unconfigured node has none) */
    bool configured = node->node_id >= 1 && node->node_id <= 127;
    co_route_set(node, CO_ROUTE_GUARD_RTR, 0,
                 configured ? GUARD_COB_BASE + node->node_id : CO_ROUTE_OFF);
}

void co_guard_rtr(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)slot;
    if (!(frame->flags & CO_FRAME_RTR)) {
        /* A boot-up or heartbeat on our own error-control ID: another node has our node-ID.
         * Reported once until the application clears 0x8150 (it repeats every heartbeat). */
        CO_COUNT(node, rx_malformed);
        if (!co_emcy_active(node, 0x8150)) {
            (void)co_emcy_raise(node, 0x8150, NULL);
            co_node_ec_event(node, CO_EC_ID_COLLISION, node->node_id,
                             frame->len ? frame->data[0] : 0xFFu, node->nmt_state);
        }
        return;
    }
    if (co_entry_uint(&node->cfg.od, node->hb_period) != 0) {
        return; /* heartbeat and guarding are exclusive: the heartbeat is in use */
    }
    co_frame_t reply = {.id = GUARD_COB_BASE + node->node_id,
                        .len = 1,
                        .data = {(uint8_t)((node->guard_toggle << 7) | node->nmt_state)}};
    node->guard_toggle ^= 1u;
    co_node_send_as(node, &reply, CO_SVC_ERROR_CONTROL);

    uint64_t life_us = life_time_us(node);
    node->life_guarding = life_us != 0;
    node->life_deadline_us = life_us ? node->now_us + life_us : CO_TIME_NEVER;
    co_node_schedule(node, node->life_deadline_us);
    if (node->life_lost) {
        node->life_lost = false;
        co_node_ec_event(node, CO_EC_LIFE_GUARD_RESUMED, node->node_id, node->nmt_state,
                         node->nmt_state);
        co_node_comm_resumed(node);
    }
}

void co_guard_written(co_node_t *node, const co_od_entry_t *entry)
{
    (void)entry; /* 0x100C or 0x100D: the life time is their product */
    if (!node->life_guarding || node->life_lost) {
        return;
    }
    uint64_t life_us = life_time_us(node);
    node->life_guarding = life_us != 0;
    node->life_deadline_us = life_us ? node->now_us + life_us : CO_TIME_NEVER;
    co_node_schedule(node, node->life_deadline_us);
}

static uint64_t life_poll(co_node_t *node, uint64_t now_us)
{
    if (!node->life_guarding || node->life_lost) {
        return CO_TIME_NEVER;
    }
    if (now_us < node->life_deadline_us) {
        return node->life_deadline_us;
    }
    node->life_lost = true;
    node->life_deadline_us = CO_TIME_NEVER;
    co_node_ec_event(node, CO_EC_LIFE_GUARD, node->node_id, node->nmt_state, node->nmt_state);
    co_node_comm_lost(node);
    return CO_TIME_NEVER;
}

/* ---- master side */

static uint64_t watch_life_us(const co_guard_watch_t *w)
{
    return co_long_ms_to_us((uint32_t)w->guard_ms * w->factor);
}

co_err_t co_guard_watch(co_node_t *node, uint8_t node_id, uint16_t guard_ms, uint8_t factor)
{
    if (node_id < 1 || node_id > 127 || node_id == node->node_id ||
        (guard_ms != 0 && factor == 0)) {
        return CO_ERR_ARG;
    }
    if (guard_ms != 0 && co_hb_consumes(node, node_id)) {
        return CO_ERR_STATE;
    }
    co_guard_watch_t *slot = NULL;
    for (uint8_t i = 0; i < co_guard_watch_max(); i++) {
        co_guard_watch_t *w = &node->guard_watch[i];
        if (w->guard_ms != 0 && w->node_id == node_id) {
            slot = w;
            break;
        }
        if (w->guard_ms == 0 && slot == NULL) {
            slot = w;
        }
    }
    if (slot == NULL) {
        return guard_ms ? CO_ERR_FULL : CO_OK;
    }
    *slot = (co_guard_watch_t){.node_id = node_id,
                               .guard_ms = guard_ms,
                               .factor = factor,
                               .state = CO_STATE_NONE,
                               .toggle = CO_STATE_NONE,
                               .next_rtr_us = node->now_us,
                               .life_deadline_us = node->now_us};
    uint8_t watch = (uint8_t)(slot - node->guard_watch);
    if (guard_ms != 0) {
        slot->life_deadline_us = node->now_us + watch_life_us(slot);
        co_node_schedule(node, node->now_us);
    }
    co_route_set(node, CO_ROUTE_GUARD_REPLY, watch,
                 guard_ms != 0 ? GUARD_COB_BASE + node_id : CO_ROUTE_OFF);
    return CO_OK;
}

void co_guard_reply(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    if (frame->flags & CO_FRAME_RTR) {
        return; /* our own request, as another master would see it */
    }
    if (frame->len != 1) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    co_guard_watch_t *w = &node->guard_watch[slot];
    uint8_t toggle = (uint8_t)(frame->data[0] >> 7);
    uint8_t state = frame->data[0] & 0x7Fu;
    uint8_t previous = w->state;
    if (state == CO_NMT_INITIALISING) { /* boot-up: the node's toggle starts over */
        w->state = state;
        w->toggle = CO_STATE_NONE;
        co_node_ec_event(node, CO_EC_BOOT, w->node_id, state, previous);
        return;
    }
    if (w->toggle != CO_STATE_NONE && toggle != w->toggle) {
        w->toggle = (uint8_t)(toggle ^ 1u); /* resynchronise, but the reply does not count */
        co_node_ec_event(node, CO_EC_GUARD_TOGGLE, w->node_id, state, previous);
        return;
    }
    w->toggle = (uint8_t)(toggle ^ 1u);
    w->state = state;
    w->life_deadline_us = node->now_us + watch_life_us(w);
    co_node_schedule(node, w->life_deadline_us);
    if (w->lost) {
        w->lost = false;
        co_node_ec_event(node, CO_EC_GUARD_RESUMED, w->node_id, state, previous);
    } else if (previous == CO_STATE_NONE) {
        co_node_ec_event(node, CO_EC_STARTED, w->node_id, state, previous);
    } else if (state != previous) {
        co_node_ec_event(node, CO_EC_STATE_CHANGED, w->node_id, state, previous);
    }
}

static uint64_t watch_poll(co_node_t *node, co_guard_watch_t *w, uint64_t now_us)
{
    if (now_us >= w->next_rtr_us) {
        co_frame_t rtr = {.id = GUARD_COB_BASE + w->node_id, .flags = CO_FRAME_RTR, .len = 1};
        co_node_send_as(node, &rtr, CO_SVC_ERROR_CONTROL);
        w->next_rtr_us = now_us + co_ms_to_us(w->guard_ms);
    }
    if (!w->lost && now_us >= w->life_deadline_us) {
        w->lost = true;
        co_node_ec_event(node, CO_EC_GUARD_TIMEOUT, w->node_id, w->state, w->state);
    }
    return w->lost ? w->next_rtr_us : co_min_u64(w->next_rtr_us, w->life_deadline_us);
}

uint64_t co_guard_poll(co_node_t *node, uint64_t now_us)
{
    uint64_t next = life_poll(node, now_us);
    for (uint8_t i = 0; i < co_guard_watch_max(); i++) {
        if (node->guard_watch[i].guard_ms != 0) {
            next = co_min_u64(next, watch_poll(node, &node->guard_watch[i], now_us));
        }
    }
    return next;
}

bool co_guard_watches(const co_node_t *node, uint8_t node_id)
{
    for (uint8_t i = 0; i < co_guard_watch_max(); i++) {
        if (node->guard_watch[i].guard_ms != 0 && node->guard_watch[i].node_id == node_id) {
            return true;
        }
    }
    return false;
}

#else

co_err_t co_guard_watch(co_node_t *node, uint8_t node_id, uint16_t guard_ms, uint8_t factor)
{
    (void)node;
    (void)node_id;
    (void)guard_ms;
    (void)factor;
    return CO_ERR_STATE; /* no guarding in this build */
}

#endif
