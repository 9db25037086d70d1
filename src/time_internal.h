/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/time_internal.h -- TIME (see canola/time.h): the consumer and producer of 0x1012
 * (time.c, CO_CONFIG_TIME; without it neither role, whatever 0x1012 says). Not installed.
 */
#ifndef CANOLA_TIME_INTERNAL_H
#define CANOLA_TIME_INTERNAL_H

#include "kernel.h"
#include "standin.h"

#if CO_CONFIG_TIME
void co_time_reset_comm(co_node_t *node);
void co_time_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
void co_time_written(co_node_t *node, const co_od_entry_t *entry); /* 0x1012 */
#else /* time.cob_id stays 0, nothing is routed */
#define co_time_reset_comm co_none_node
#define co_time_ingest co_none_slot_frame
#define co_time_written co_none_entry
#endif

/* TIME's object (node_od.c): 0x1012, its COB-ID (checked even when TIME is left out). */
#define CO_TIME_OBJECT_ROWS                                                                        \
    CO_OBJECT_ROW(0x1012, 0x1012, CO_COB_SUB0, NULL, CO_CONFIG_TIME ? co_time_written : NULL)

#endif /* CANOLA_TIME_INTERNAL_H */
