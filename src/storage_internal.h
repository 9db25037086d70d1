/* SPDX-License-Identifier: Apache-2.0 */
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
/* The indexes of a group: 0x1000..0x1FFF (communication), 0x2000..0x9FFF (application). */
static inline uint16_t co_group_first(co_param_group_t group) { return (uint16_t)(group << 12); }
static inline uint16_t co_group_last(co_param_group_t group)
{
    return group == CO_PARAMS_COMMUNICATION ? 0x1FFF : 0x9FFF;
}

/* The power-on values of a group's objects ($NODEID defaults of an unconfigured node, 0xFF,
 * stay at their base values). */
static inline void co_group_defaults(co_node_t *node, co_param_group_t group)
{
    uint8_t id = node->node_id == CO_NODE_ID_UNCONFIGURED ? 0 : node->node_id;
    co_od_reset(&node->cfg.od, co_group_first(group), co_group_last(group), id);
}

/* Reset application or communication: the group's power-on values, then those stored.
 * Returns what was wrong with the stored image (CO_STORE_INTACT, or CO_STORE_NONE when
 * nothing is stored), for co_storage_report once reset communication is done. */
#if CO_CONFIG_STORAGE
co_store_fault_t co_storage_reset_group(co_node_t *node, co_param_group_t group);
void co_storage_report(co_node_t *node, co_param_group_t group, co_store_fault_t fault);
void co_storage_show_capability(co_node_t *node, const co_od_entry_t *entry);
void co_storage_reset_comm(co_node_t *node);
#else
static inline co_store_fault_t co_storage_reset_group(co_node_t *node, co_param_group_t group)
{
    co_group_defaults(node, group); /* nothing is ever stored */
    return CO_STORE_NONE;
}
static inline void co_storage_report(co_node_t *node, co_param_group_t group,
                                     co_store_fault_t fault)
{
    (void)node;
    (void)group;
    (void)fault;
}
#define co_storage_reset_comm co_none_node
#endif

/* The stored parameters' objects (node_od.c): 0x1010 and 0x1011 (without storage every
 * command is refused). */
#if CO_CONFIG_STORAGE
#define CO_STORAGE_OBJECT_ROWS                                                                     \
    CO_OBJECT_ROW(0x1010, 0x1011, CO_COB_NONE, co_storage_check_write, co_storage_show_capability)
#else
#define CO_STORAGE_OBJECT_ROWS                                                                     \
    CO_OBJECT_ROW(0x1010, 0x1011, CO_COB_NONE, co_storage_check_write, NULL)
#endif

#endif /* CANOLA_STORAGE_INTERNAL_H */
