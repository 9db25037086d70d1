/*
 * txq.c -- sending frames: straight to the driver when it is free, else into a
 * bounded queue kept in arbitration order (the frame the bus would let through
 * first leaves first; equal identifiers keep their order, so SDO segments of one
 * transfer never overtake each other).
 */
#include <string.h>

#include "internal.h"

/* Arbitration rank: lower wins. An 11-bit frame beats a 29-bit frame with the
 * same 11 base bits (its IDE bit is dominant). */
static uint32_t priority(const co_frame_t *frame)
{
    if (frame->flags & CO_FRAME_EXT) {
        return ((frame->id >> 18) << 19) | (1u << 18) | (frame->id & 0x3FFFFu);
    }
    return (frame->id & CO_ID_STD_MAX) << 19;
}

/* Hand one frame to the driver; true when it is gone (sent or refused for good). */
static bool driver_take(co_node_t *node, const co_frame_t *frame)
{
    co_err_t err = node->cfg.driver.tx(node->cfg.driver.ctx, frame);
    if (err == CO_ERR_BUSY) {
        return false;
    }
    if (err == CO_OK) {
        node->stats.tx_frames++;
    } else {
        node->stats.tx_dropped++;
        if (node->cfg.on_error) {
            node->cfg.on_error(node->cfg.user, CO_NODE_ERR_TX_DRIVER);
        }
    }
    return true;
}

void co_txq_flush(co_node_t *node)
{
    uint8_t sent = 0;
    while (sent < node->txq_count && driver_take(node, &node->txq[sent])) {
        sent++;
    }
    if (sent) {
        node->txq_count = (uint8_t)(node->txq_count - sent);
        memmove(&node->txq[0], &node->txq[sent], node->txq_count * sizeof node->txq[0]);
        if (node->txq_count == 0) {
            /* room again: a paced sender (block transfer) goes on at the next poll */
            co_node_schedule(node, node->now_us);
        }
    }
}

static co_err_t enqueue(co_node_t *node, const co_frame_t *frame)
{
    if (node->txq_count >= CO_TX_QUEUE_LEN) {
        node->stats.tx_overflow++;
        if (node->cfg.on_error) {
            node->cfg.on_error(node->cfg.user, CO_NODE_ERR_TX_OVERFLOW);
        }
        return CO_ERR_FULL;
    }
    uint32_t rank = priority(frame);
    uint8_t at = node->txq_count;
    while (at > 0 && priority(&node->txq[at - 1]) > rank) {
        at--;
    }
    memmove(&node->txq[at + 1], &node->txq[at], (size_t)(node->txq_count - at) * sizeof *frame);
    node->txq[at] = *frame;
    node->txq_count++;
    node->stats.tx_queued++;
    return CO_OK;
}

co_err_t co_node_send(co_node_t *node, const co_frame_t *frame)
{
    if (node->txq_count == 0 && driver_take(node, frame)) {
        return CO_OK;
    }
    co_err_t err = enqueue(node, frame);
    co_txq_flush(node);
    return err;
}
