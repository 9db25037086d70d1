/* SPDX-License-Identifier: Apache-2.0 */
/*
 * emcy_consumer.c -- the EMCY consumer: 0x1028 subN holds COB-IDs to watch; each EMCY
 * frame received on one of them goes to on_emcy. Left out with CO_EMCY_CONSUMERS_MAX 0
 * (emcy_internal.h).
 */
#include <string.h>

#include "emcy_internal.h"

#if CO_EMCY_CONSUMERS_MAX > 0

/* Bind 0x1028 sub1..N (as many as the OD has, up to CO_EMCY_CONSUMERS_MAX), each with its
 * route (none for a COB-ID marked not valid, or a sub-index the OD lacks). */
void co_emcy_consumers_bind(co_node_t *node)
{
    co_emcy_t *e = &node->emcy;
    e->consumer_count = 0;
    for (uint8_t i = 0; i < CO_EMCY_CONSUMERS_MAX; i++) {
        uint64_t cob = CO_COB_INVALID;
        if (e->consumer_count == i &&
            co_od_get_uint(&node->cfg.od, 0x1028, (uint8_t)(i + 1), &cob) == CO_OK) {
            e->consumer_cob[e->consumer_count++] = (uint32_t)cob;
        }
        co_route_set(node, CO_ROUTE_EMCY, i, co_cob_route((uint32_t)cob));
    }
}

void co_emcy_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)slot; /* every consumer entry is handled alike */
    if (frame->len != CO_EMCY_FRAME_LEN || (frame->flags & CO_FRAME_RTR)) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    if (node->cfg.on_emcy == NULL) {
        return;
    }
    /* The sender's COB-ID in the form of a COB-ID object (bit 29 for 29-bit). */
    co_emcy_msg_t msg = {.cob_id = frame->id | ((frame->flags & CO_FRAME_EXT) ? CO_COB_EXT : 0u),
                         .code = co_get_u16(frame->data),
                         .reg = frame->data[2]};
    memcpy(msg.manufacturer, &frame->data[3], sizeof msg.manufacturer);
    node->cfg.on_emcy(node->cfg.user, &msg);
}

#endif
