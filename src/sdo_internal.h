/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/sdo_internal.h -- the SDO family (see canola/sdo.h): the server channels (sdo_server.c),
 * the client channels (sdo_client.c, CO_SDO_CLIENTS_MAX > 0, and sdo_value.c over them), and
 * the CRC of block transfers (crc16.c). The protocol's words: sdo_protocol.h. Not installed.
 */
#ifndef CANOLA_SDO_INTERNAL_H
#define CANOLA_SDO_INTERNAL_H

#include "kernel.h"
#include "standin.h"

/* Table sizes as values: a configuration may set one to 0, and a loop bound that is a
 * literal 0 would make the compiler warn about an always-false comparison. */
static inline uint8_t co_sdo_servers_max(void) { return CO_SDO_SERVERS_MAX; }
static inline uint8_t co_sdo_clients_max(void) { return CO_SDO_CLIENTS_MAX; }

/* SDO server and client time-out (co_node_config_t.sdo_timeout_ms, default 1 s). */
static inline uint64_t co_sdo_timeout_us(const co_node_t *node)
{
    uint16_t ms = node->cfg.sdo_timeout_ms;
    return co_ms_to_us(ms ? ms : (uint16_t)1000u);
}

/* sdo_server.c */
void co_sdo_server_reset_comm(co_node_t *node);
void co_sdo_server_stop(co_node_t *node); /* SDO not allowed now: transfers end silently */
void co_sdo_server_ingest(co_node_t *node, uint8_t channel, const co_frame_t *frame);
void co_sdo_server_written(co_node_t *node, const co_od_entry_t *entry); /* 0x1200.. */
co_abort_t co_sdo_server_check_write(co_node_t *node, const co_od_entry_t *entry,
                                     const uint8_t *data, uint32_t len); /* 0x1200 */
#if CO_CONFIG_SDO_SEGMENTED || CO_CONFIG_SDO_BLOCK
uint64_t co_sdo_server_poll(co_node_t *node, uint64_t now_us);
#else
#define co_sdo_server_poll co_none_poll /* expedited transfers leave nothing open */
#endif

/* sdo_client.c: without client channels nothing is routed, polled or kept. */
#if CO_SDO_CLIENTS_MAX > 0
void co_sdo_client_reset_comm(co_node_t *node);
void co_sdo_client_stop(co_node_t *node);
void co_sdo_client_written(co_node_t *node, const co_od_entry_t *entry); /* 0x1280.. */
void co_sdo_client_ingest(co_node_t *node, uint8_t channel, const co_frame_t *frame);
uint64_t co_sdo_client_poll(co_node_t *node, uint64_t now_us);
#else
#define co_sdo_client_reset_comm co_none_node
#define co_sdo_client_stop co_none_node
#define co_sdo_client_written co_none_entry
#define co_sdo_client_ingest co_none_slot_frame
#define co_sdo_client_poll co_none_poll
#endif

/* SDO's objects (node_od.c): the server parameters 0x1200.., the client parameters 0x1280..
 * (without clients they have no effect: no server channel is 0x1200 + 0x80 or more). */
#if CO_SDO_CLIENTS_MAX > 0
#define CO_SDO_OBJECT_ROWS                                                                         \
    CO_OBJECT_ROW(0x1200, 0x127F, CO_COB_SUB1_2, co_sdo_server_check_write, co_sdo_server_written) \
    CO_OBJECT_ROW(0x1280, 0x12FF, CO_COB_SUB1_2, NULL, co_sdo_client_written)
#else
#define CO_SDO_OBJECT_ROWS                                                                         \
    CO_OBJECT_ROW(0x1200, 0x12FF, CO_COB_SUB1_2, co_sdo_server_check_write, co_sdo_server_written)
#endif

#endif /* CANOLA_SDO_INTERNAL_H */
