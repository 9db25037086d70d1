/* SPDX-License-Identifier: Apache-2.0 */
/*
 * txq.c -- sending frames: straight to the driver when it is free, else into a
 * bounded queue kept in arbitration order (the frame the bus would let through
 * first leaves first; equal identifiers keep their order, so SDO segments of one
 * transfer never overtake each other). A service's frame remembers its service: when
 * the NMT state changes, frames whose service the new state does not allow (an SDO
 * answer queued just before "stop") are dropped instead of sent.
 */
#include "kernel.h"

/* Arbitration rank: lower wins. An 11-bit frame beats a 29-bit frame with the
 * same 11 base bits (its IDE bit is dominant). */
static uint32_t priority(const co_frame_t *frame)
{
    if (frame->flags & CO_FRAME_EXT) {
        return ((frame->id >> 18) << 19) | (1u << 18) | (frame->id & 0x3FFFFu);
    }
    return (frame->id & CO_ID_STD_MAX) << 19;
}

/* A frame lost: the application hears of it. */
static void lost(const co_node_t *node, co_node_error_t error)
{
    if (node->cfg.on_error) {
        node->cfg.on_error(node->cfg.user, error);
    }
}

/* The driver refused a frame for good. */
static void dropped(co_node_t *node)
{
    CO_COUNT(node, tx_dropped);
    lost(node, CO_NODE_ERR_TX_DRIVER);
}

/* Hand one frame to the driver; true when it is gone (sent or refused for good). */
static bool driver_take(co_node_t *node, const co_frame_t *frame)
{
    co_err_t err = node->cfg.driver.tx(node->cfg.driver.ctx, frame);
    if (err == CO_ERR_BUSY) {
        return false;
    }
    if (err == CO_OK) {
        CO_COUNT(node, tx_frames);
    } else {
        dropped(node);
    }
    return true;
}

/* Waiting frame i's service is one the NMT state no longer allows. */
static bool void_now(const co_node_t *node, unsigned i)
{
    uint16_t service = node->txq[i].tag.service;
    return service != 0 && !(node->services & service);
}

/* Move waiting frame `from` (and its service) to place `to`. (co_copy: GCC makes this
 * assignment a call of the C library's memcpy on Cortex-M0, which a build for size does not
 * otherwise link.) */
static void move(co_node_t *node, unsigned to, unsigned from)
{
    co_copy(&node->txq[to], &node->txq[from], sizeof node->txq[to]);
}

/* One pass over the queue (not empty): the frames that go (`send`: to the driver, up to the first
 * it refuses; else the void ones, counted) leave, the rest move up in their order. */
static CO_SIZE_NOINLINE void pass(co_node_t *node, bool send)
{
    uint8_t count = node->txq_count;
    uint8_t kept = 0;
    for (unsigned i = 0; i < count; i++) {
        if (send ? kept == 0 && driver_take(node, &node->txq[i].frame) : void_now(node, i)) {
            CO_COUNT_ADD(node, tx_gated, send ? 0u : 1u);
            continue;
        }
        if (kept != i) {
            move(node, kept, i); /* (not onto itself: memcpy's ranges must not overlap) */
        }
        kept++;
    }
    node->txq_count = kept;
    if (send && kept == 0) {
        /* room again: a paced sender (block transfer) goes on at the next poll */
        co_node_schedule(node, node->now_us);
    }
}

/* (An empty queue, the usual case, is tested here: GCC saves pass's registers before its
 * first test.) */
void co_txq_purge(co_node_t *node)
{
    if (node->txq_count != 0) {
        pass(node, false);
    }
}

/* Nothing waiting is void here: every state change purges the queue (co_txq_purge). */
void co_txq_flush(co_node_t *node)
{
    if (node->txq_count != 0) {
        pass(node, true);
    }
}

static co_err_t enqueue(co_node_t *node, const co_frame_t *frame, uint16_t service)
{
    if (node->txq_count >= CO_TX_QUEUE_LEN) {
        CO_COUNT(node, tx_overflow);
        lost(node, CO_NODE_ERR_TX_OVERFLOW);
        return CO_ERR_FULL;
    }
    uint32_t rank = priority(frame);
    uint8_t at = node->txq_count;
    while (at > 0 && priority(&node->txq[at - 1].frame) > rank) {
        move(node, at, (uint8_t)(at - 1)); /* insertion: the later frames move down */
        at--;
    }
    node->txq[at].frame = *frame; /* (its padding is unspecified after this: service next) */
    node->txq[at].tag.service = service;
    node->txq_count++;
    CO_COUNT(node, tx_queued);
    return CO_OK;
}

co_err_t co_txq_refused(co_node_t *node, const co_frame_t *frame, uint16_t service, co_err_t err)
{
    if (err != CO_ERR_BUSY) {
        dropped(node);
        return CO_OK; /* gone for good: the frame is not the caller's problem any more */
    }
    err = enqueue(node, frame, service);
    co_txq_flush(node);
    return err;
}

co_err_t co_node_send_as(co_node_t *node, const co_frame_t *frame, uint16_t service)
{
    if (service != 0 && !(node->services & service)) {
        CO_COUNT(node, tx_gated);
        return CO_ERR_STATE;
    }
    if (node->txq_count == 0 && driver_take(node, frame)) {
        return CO_OK;
    }
    return co_txq_refused(node, frame, service, CO_ERR_BUSY); /* queued */
}

co_err_t co_node_send_cob(co_node_t *node, uint32_t cob, const uint8_t *data, uint8_t len,
                          uint16_t service)
{
    co_frame_t f;
    co_frame_address(&f, cob, len);
    for (unsigned i = 0; i < sizeof f.data; i++) { /* (no memcpy, no memset) */
        f.data[i] = i < len ? data[i] : 0;
    }
    return co_node_send_as(node, &f, service);
}

co_err_t co_node_send(co_node_t *node, const co_frame_t *frame)
{
    return co_node_send_as(node, frame, 0);
}
