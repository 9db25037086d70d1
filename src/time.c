/* time.c -- placeholder being replaced within this change (see canola/time.h). */
#include "internal.h"

void co_time_encode(const co_time_of_day_t *t, uint8_t out[6])
{
    (void)t;
    (void)out;
}
co_time_of_day_t co_time_decode(const uint8_t in[6])
{
    (void)in;
    co_time_of_day_t t = {0, 0};
    return t;
}
uint64_t co_time_to_us(const co_time_of_day_t *t)
{
    (void)t;
    return 0;
}
co_time_of_day_t co_time_from_us(uint64_t us)
{
    (void)us;
    co_time_of_day_t t = {0, 0};
    return t;
}
co_err_t co_time_send(co_node_t *node, const co_time_of_day_t *t)
{
    (void)node;
    (void)t;
    return CO_ERR_STATE;
}
void co_time_reset_comm(co_node_t *node) { (void)node; }
void co_time_add_routes(co_node_t *node) { (void)node; }
void co_time_ingest(co_node_t *node, const co_frame_t *frame)
{
    (void)node;
    (void)frame;
}
void co_time_written(co_node_t *node, const co_od_entry_t *entry)
{
    (void)node;
    (void)entry;
}
