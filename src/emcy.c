/* emcy.c -- placeholder being replaced within this change (see canola/emcy.h). */
#include "internal.h"

uint8_t co_emcy_register_bit(uint16_t code)
{
    (void)code;
    return 0;
}
co_err_t co_emcy_raise(co_node_t *node, uint16_t code, const uint8_t *manufacturer)
{
    (void)node;
    (void)code;
    (void)manufacturer;
    return CO_OK;
}
co_err_t co_emcy_clear(co_node_t *node, uint16_t code)
{
    (void)node;
    (void)code;
    return CO_ERR_NOT_FOUND;
}
bool co_emcy_active(const co_node_t *node, uint16_t code)
{
    (void)node;
    (void)code;
    return false;
}
void co_node_bus_event(co_node_t *node, co_bus_event_t event)
{
    (void)node;
    (void)event;
}
void co_emcy_reset_comm(co_node_t *node) { (void)node; }
void co_emcy_add_routes(co_node_t *node) { (void)node; }
void co_emcy_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame)
{
    (void)node;
    (void)slot;
    (void)frame;
}
uint64_t co_emcy_poll(co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
    return CO_TIME_NEVER;
}
co_abort_t co_emcy_check_write(const co_node_t *node, const co_od_entry_t *entry,
                               const uint8_t *data, uint32_t len)
{
    (void)node;
    (void)entry;
    (void)data;
    (void)len;
    return CO_ABORT_NONE;
}
void co_emcy_written(co_node_t *node, const co_od_entry_t *entry)
{
    (void)node;
    (void)entry;
}
void co_emcy_state_entered(co_node_t *node) { (void)node; }
