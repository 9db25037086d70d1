/* sync.c -- placeholder being replaced within this change (see canola/sync.h). */
#include "internal.h"

bool co_sync_in_window(const co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
    return false;
}
uint8_t co_sync_counter(const co_node_t *node)
{
    (void)node;
    return 0;
}
void co_sync_reset_comm(co_node_t *node) { (void)node; }
void co_sync_add_routes(co_node_t *node) { (void)node; }
void co_sync_ingest(co_node_t *node, const co_frame_t *frame)
{
    (void)node;
    (void)frame;
}
uint64_t co_sync_poll(co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
    return CO_TIME_NEVER;
}
co_abort_t co_sync_check_write(const co_node_t *node, const co_od_entry_t *entry,
                               const uint8_t *data, uint32_t len)
{
    (void)node;
    (void)entry;
    (void)data;
    (void)len;
    return CO_ABORT_NONE;
}
void co_sync_written(co_node_t *node, const co_od_entry_t *entry)
{
    (void)node;
    (void)entry;
}
void co_sync_state_entered(co_node_t *node) { (void)node; }
