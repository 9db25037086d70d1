/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/nmt.h -- network management: the NMT state machine of a node and the
 * NMT commands a master sends.
 *
 * A node powers on in INITIALISING, runs reset application (objects
 * 0x2000..0x9FFF back to their power-on values), then reset communication
 * (0x1000..0x1FFF), sends its boot-up frame (0x700 + node-ID, one byte 0x00)
 * exactly once and enters PRE-OPERATIONAL (or OPERATIONAL when configured to
 * start itself). NMT commands arrive on COB-ID 0x000 as two bytes
 * [command, node-ID]; node-ID 0 addresses every node. Frames of any other
 * length are ignored.
 *
 * Which services run in which state (CiA 301):
 *
 *                      INIT  PRE-OP  OPERATIONAL  STOPPED
 *   boot-up             X
 *   NMT commands              X        X            X
 *   error control             X        X            X
 *   SDO                       X        X
 *   SYNC, TIME, EMCY          X        X
 *   PDO                                X
 *
 * co_nmt_allows() is that table; the node's dispatcher and every producer
 * consult it, so a service never needs its own state check.
 */
#ifndef CANOLA_NMT_H
#define CANOLA_NMT_H

#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

/** NMT states, valued as heartbeat and node guarding carry them. */
typedef enum co_nmt_state {
    CO_NMT_INITIALISING = 0x00,
    CO_NMT_STOPPED = 0x04,
    CO_NMT_OPERATIONAL = 0x05,
    CO_NMT_PRE_OPERATIONAL = 0x7F,
} co_nmt_state_t;

/** NMT command specifiers (first byte of the frame on COB-ID 0x000). */
typedef enum co_nmt_cmd {
    CO_NMT_CMD_START = 0x01,
    CO_NMT_CMD_STOP = 0x02,
    CO_NMT_CMD_ENTER_PRE_OPERATIONAL = 0x80,
    CO_NMT_CMD_RESET_NODE = 0x81,
    CO_NMT_CMD_RESET_COMMUNICATION = 0x82,
} co_nmt_cmd_t;

/** What a reset restored, as told to the application's on_reset callback. */
typedef enum co_reset {
    CO_RESET_APPLICATION = 1,   /**< 0x2000..0x9FFF restored */
    CO_RESET_COMMUNICATION = 2, /**< 0x1000..0x1FFF restored */
} co_reset_t;

/** Services, as bits for co_nmt_allows(). */
typedef enum co_service {
    CO_SVC_BOOTUP = 1u << 0,
    CO_SVC_NMT = 1u << 1,
    CO_SVC_ERROR_CONTROL = 1u << 2,
    CO_SVC_SDO = 1u << 3,
    CO_SVC_SYNC = 1u << 4,
    CO_SVC_TIME = 1u << 5,
    CO_SVC_EMCY = 1u << 6,
    CO_SVC_PDO = 1u << 7,
    CO_SVC_LSS = 1u << 8,
} co_service_t;

/** True when `service` may receive or transmit in `state` (the table above; LSS runs in
 *  every state). O(1). */
bool co_nmt_allows(co_nmt_state_t state, co_service_t service);

/** The co_service_t bits allowed in `state`. O(1). */
uint16_t co_nmt_services(co_nmt_state_t state);

/** Human-readable state name ("pre-operational", ...); "unknown" for other values. */
const char *co_nmt_state_name(uint8_t state);

/** The node's current NMT state. */
co_nmt_state_t co_nmt_state(const co_node_t *node);

/** Send an NMT command to `target` (1..127, or 0 for all nodes) as an NMT master.
 *  When the target is this node's own ID or 0 the command applies to this node too
 *  (after the frame is sent). Returns CO_ERR_ARG for an unknown command or target > 127,
 *  else CO_OK (a busy driver queues the frame). */
co_err_t co_nmt_send(co_node_t *node, co_nmt_cmd_t cmd, uint8_t target);

/** Apply an NMT command to this node as if it had been received (the application's own
 *  way to stop, start or reset itself). Returns CO_ERR_ARG for an unknown command. */
co_err_t co_nmt_apply(co_node_t *node, co_nmt_cmd_t cmd);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_NMT_H */
