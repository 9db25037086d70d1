/* pdo.c -- placeholder being replaced within this change (see canola/pdo.h). */
#include "internal.h"

uint32_t co_pdo_event(co_node_t *node, uint16_t index, uint8_t sub)
{
    (void)node;
    (void)index;
    (void)sub;
    return 0;
}
co_err_t co_tpdo_request(co_node_t *node, uint8_t n)
{
    (void)node;
    (void)n;
    return CO_ERR_ARG;
}
co_err_t co_pdo_bind(co_node_t *node)
{
    (void)node;
    return CO_OK;
}
void co_pdo_reset_comm(co_node_t *node) { (void)node; }
void co_pdo_add_routes(co_node_t *node) { (void)node; }
void co_pdo_rx(co_node_t *node, uint8_t rpdo, const co_frame_t *frame)
{
    (void)node;
    (void)rpdo;
    (void)frame;
}
void co_pdo_rtr(co_node_t *node, uint8_t tpdo, const co_frame_t *frame)
{
    (void)node;
    (void)tpdo;
    (void)frame;
}
void co_pdo_sync(co_node_t *node, uint8_t counter)
{
    (void)node;
    (void)counter;
}
uint64_t co_pdo_poll(co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
    return CO_TIME_NEVER;
}
co_abort_t co_pdo_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                              uint32_t len)
{
    (void)node;
    (void)entry;
    (void)data;
    (void)len;
    return CO_ABORT_NONE;
}
void co_pdo_written(co_node_t *node, const co_od_entry_t *entry)
{
    (void)node;
    (void)entry;
}
void co_pdo_changed(co_node_t *node, const co_od_entry_t *entry)
{
    (void)node;
    (void)entry;
}
void co_pdo_state_entered(co_node_t *node) { (void)node; }
