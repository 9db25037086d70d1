/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/lss_internal.h -- LSS (CiA 305, see canola/lss.h): the slave (lss_slave.c,
 * CO_CONFIG_LSS_SLAVE) and the master (lss_master.c, CO_CONFIG_LSS_MASTER). The slave's reset
 * communication with a new node-ID goes up through the node's wiring (kernel.h). Not installed.
 */
#ifndef CANOLA_LSS_INTERNAL_H
#define CANOLA_LSS_INTERNAL_H

#include "kernel.h"
#include "standin.h"

#define CO_LSS_FRAME_LEN 8u /* every LSS frame: the command, then 7 bytes */

#if CO_CONFIG_LSS_SLAVE
void co_lss_slave_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_lss_slave_poll(co_node_t *node, uint64_t now_us);
/* At every reset: the node-ID the node runs with from now on (CiA 305 pending node-ID). */
void co_lss_slave_reset(co_node_t *node, bool application);
/* A frame of `service` arrived while the services are off: true when that was the quiet
 * time after a bit rate switch, it is over now (services back), and `service` may run. */
bool co_lss_slave_resume(co_node_t *node, uint16_t service);
#else
static inline bool co_lss_slave_resume(co_node_t *node, uint16_t service)
{
    (void)node;
    (void)service;
    return false;
}
#define co_lss_slave_ingest co_none_slot_frame
#define co_lss_slave_poll co_none_poll
static inline void co_lss_slave_reset(co_node_t *node, bool application)
{
    (void)node;
    (void)application;
}
#endif

#if CO_CONFIG_LSS_MASTER
void co_lss_master_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
uint64_t co_lss_master_poll(co_node_t *node, uint64_t now_us);
#else
#define co_lss_master_ingest co_none_slot_frame
#define co_lss_master_poll co_none_poll
#endif

#endif /* CANOLA_LSS_INTERNAL_H */
