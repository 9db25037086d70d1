/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/standin.h -- the shapes of the stand-ins a family header maps a left-out feature's
 * functions onto (canola/config.h): no-ops the compiler removes with their calls, so that a
 * switch removes whole functions and their state. Not installed.
 */
#ifndef CANOLA_STANDIN_H
#define CANOLA_STANDIN_H

#include "canola/node.h"

static inline void co_none_node(co_node_t *node) { (void)node; }
static inline uint64_t co_none_poll(co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
    return CO_TIME_NEVER;
}
static inline void co_none_slot_frame(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)node;
    (void)slot;
    (void)frame;
}
static inline void co_none_entry(co_node_t *node, const co_od_entry_t *entry)
{
    (void)node;
    (void)entry;
}
static inline co_abort_t co_none_check(co_node_t *node, const co_od_entry_t *entry,
                                       const uint8_t *data, uint32_t len)
{
    (void)node;
    (void)entry;
    (void)data;
    (void)len;
    return CO_ABORT_NONE;
}
static inline bool co_none_node_id(const co_node_t *node, uint8_t node_id)
{
    (void)node;
    (void)node_id;
    return false;
}
static inline bool co_none_state(const co_node_t *node)
{
    (void)node;
    return false;
}

#endif /* CANOLA_STANDIN_H */
