/*
 * src/storage_internal.h -- stored parameters (see canola/storage.h): 0x1010 and 0x1011, and
 * the loads at reset (storage.c; CO_CONFIG_STORAGE 0 keeps the dictionary's values and
 * refuses every command). Not installed.
 */
#ifndef CANOLA_STORAGE_INTERNAL_H
#define CANOLA_STORAGE_INTERNAL_H

#include "kernel.h"
#include "standin.h"

co_abort_t co_storage_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                                  uint32_t len);
#if CO_CONFIG_STORAGE
void co_storage_load(co_node_t *node, co_param_group_t group);
void co_storage_show_capability(co_node_t *node, const co_od_entry_t *entry);
void co_storage_reset_comm(co_node_t *node);
#else
static inline void co_storage_load(co_node_t *node, co_param_group_t group)
{
    (void)node;
    (void)group; /* nothing is ever stored */
}
#define co_storage_reset_comm co_none_node
#endif

#endif /* CANOLA_STORAGE_INTERNAL_H */
