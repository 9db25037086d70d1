/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/node_internal.h -- the node on top of the services: what node.c (life: init, start,
 * ingest, poll), nmt.c (the state machine and its fan-out to the services), node_od.c (object
 * writes and their effects) and error_behaviour.c (communication errors, 0x1029) tell each
 * other. The only files that name every service. Not installed.
 */
#ifndef CANOLA_NODE_INTERNAL_H
#define CANOLA_NODE_INTERNAL_H

#include "emcy_internal.h"
#include "errctl_internal.h"
#include "kernel.h"
#include "lss_internal.h"
#include "manager_internal.h"
#include "od_plain.h"
#include "pdo_internal.h"
#include "sdo_internal.h"
#include "storage_internal.h"
#include "sync_internal.h"
#include "time_internal.h"

/* nmt.c */
void co_nmt_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
/* Reset communication (and, with `application`, reset application first): the services
 * start over, the boot-up goes out, pre-operational (or operational when self-starting). */
void co_nmt_reset(co_node_t *node, bool application);

/* error_behaviour.c: the error behaviour of 0x1029 sub1 (also for bus-off). */
void co_node_error_behaviour(co_node_t *node);

/* node_od.c: a whole new value for an entry, with checks, service effects and hooks (no
 * access rights): the node's wiring for co_node_write (kernel.h). */
co_abort_t co_node_write_entry(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len);

#endif /* CANOLA_NODE_INTERNAL_H */
