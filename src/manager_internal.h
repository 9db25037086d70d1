/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/manager_internal.h -- the CANopen manager (CiA 302-2, see canola/manager.h): the slaves'
 * boot (manager.c) and program download (program_master.c), both CO_CONFIG_MANAGER; both drive
 * SDO client channels. Its NMT commands go up through the node's wiring (kernel.h). Not
 * installed.
 */
#ifndef CANOLA_MANAGER_INTERNAL_H
#define CANOLA_MANAGER_INTERNAL_H

#include "kernel.h"
#include "standin.h"

#if CO_CONFIG_MANAGER
uint64_t co_manager_poll(co_node_t *node, uint64_t now_us);
/* The master's own reset communication, before the services forget their state: the boot
 * in progress ends without a verdict, and the manager starts over at the next poll. */
void co_manager_reset_comm(co_node_t *node);
void co_manager_routes(co_node_t *node); /* the slaves' boot-up routes, for this node-ID */
void co_manager_bootup(co_node_t *node, uint8_t n, const co_frame_t *frame);
void co_manager_ec_event(co_node_t *node, const co_ec_event_t *ev);
uint64_t co_flash_poll(co_node_t *node, uint64_t now_us); /* program_master.c: progress */
#else
#define co_manager_poll co_none_poll
#define co_manager_reset_comm co_none_node
#define co_manager_routes co_none_node
#define co_manager_bootup co_none_slot_frame
static inline void co_manager_ec_event(co_node_t *node, const co_ec_event_t *ev)
{
    (void)node;
    (void)ev;
}
#define co_flash_poll co_none_poll
#endif

#endif /* CANOLA_MANAGER_INTERNAL_H */
