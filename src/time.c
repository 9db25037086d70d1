/* SPDX-License-Identifier: Apache-2.0 */
/*
 * time.c -- TIME producer and consumer (0x1012), TIME_OF_DAY on the wire.
 */
#include "time_internal.h"

#define TIME_CONSUMER 0x80000000u /* 0x1012 bit 31 */
#define TIME_PRODUCER 0x40000000u /* 0x1012 bit 30 */
#define TIME_MS_MASK 0x0FFFFFFFu  /* bits 28..31 of the first u32 are reserved */
#define TIME_FRAME_LEN 6u
#define MS_PER_DAY 86400000u
#define US_PER_DAY 86400000000ull

/* ---- TIME_OF_DAY */

void co_time_encode(const co_time_of_day_t *t, uint8_t out[6])
{
    co_put_u32(out, t->ms & TIME_MS_MASK);
    co_put_u16(out + 4, t->days);
}

co_time_of_day_t co_time_decode(const uint8_t in[6])
{
    co_time_of_day_t t = {.ms = co_get_u32(in) & TIME_MS_MASK, .days = co_get_u16(in + 4)};
    return t;
}

uint64_t co_time_to_us(const co_time_of_day_t *t)
{
    return (uint64_t)t->days * US_PER_DAY + (uint64_t)t->ms * 1000u;
}

/* Days beyond what a u16 holds (year 2163 on) wrap, as the wire field does. */
co_time_of_day_t co_time_from_us(uint64_t us_since_1984)
{
    co_time_of_day_t t = {.ms = (uint32_t)((us_since_1984 % US_PER_DAY) / 1000u),
                          .days = (uint16_t)(us_since_1984 / US_PER_DAY)};
    return t;
}

/* ---- producer */

co_err_t co_time_send(co_node_t *node, const co_time_of_day_t *t)
{
    if (node == NULL || t == NULL) {
        return CO_ERR_ARG;
    }
    if (!(node->time.cob_id & TIME_PRODUCER) || !(node->services & CO_SVC_TIME)) {
        return CO_ERR_STATE;
    }
    if (t->ms >= MS_PER_DAY) {
        return CO_ERR_ARG;
    }
    uint8_t data[TIME_FRAME_LEN];
    co_time_encode(t, data);
    return co_node_send_cob(node, node->time.cob_id, data, TIME_FRAME_LEN, CO_SVC_TIME);
}

/* ---- consumer */

#if CO_CONFIG_TIME

void co_time_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)slot;
    if ((frame->flags & CO_FRAME_RTR) || frame->len != TIME_FRAME_LEN) {
        CO_COUNT(node, rx_malformed);
        return;
    }
    co_time_of_day_t t = co_time_decode(frame->data);
    if (node->cfg.on_time) {
        node->cfg.on_time(node->cfg.user, &t);
    }
}

/* ---- lifecycle and object dictionary */

/* Consuming (bit 31 set): the route of the COB-ID's identifier; else none. */
static void route(co_node_t *node)
{
    uint32_t cob = node->time.cob_id;
    co_route_set(node, CO_ROUTE_TIME, 0, (cob & TIME_CONSUMER) ? co_cob_key(cob) : CO_ROUTE_OFF);
}

void co_time_reset_comm(co_node_t *node)
{
    node->time.cob_id = co_od_u32(node, 0x1012, 0, 0); /* absent: 0, neither role */
    route(node);
}

void co_time_written(co_node_t *node, const co_od_entry_t *entry)
{
    if (entry->index != 0x1012) {
        return;
    }
    node->time.cob_id = (uint32_t)co_od_entry_uint(&node->cfg.od, entry);
    route(node); /* consuming starts or stops, or the identifier moves */
}

#endif /* CO_CONFIG_TIME: without it neither role, whatever 0x1012 says */
