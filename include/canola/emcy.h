/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/emcy.h -- emergency objects: the EMCY producer of a device (with its
 * error register 0x1001 and error history 0x1003) and the EMCY consumer (0x1028).
 *
 * Producer. The application (and the stack itself, for communication errors)
 * raises and clears errors by their CiA 301 error code. Each raise sends one EMCY
 * frame on the COB-ID of 0x1014 (default 0x80 + node-ID; bit 31 = EMCY off):
 * 8 bytes: error code (u16), error register (0x1001), 5 manufacturer bytes. The
 * error register is derived from the errors active now: bit 0 (generic) whenever
 * any error is active, bit 1 current (0x2xxx), bit 2 voltage (0x3xxx), bit 3
 * temperature (0x4xxx), bit 4 communication (0x81xx..0x8Fxx), bit 7 manufacturer
 * (0xFFxx); other codes set bit 0 only (co_emcy_register_bit). When the
 * last active error clears, an "error reset" EMCY (code 0x0000) is sent. Every
 * raise is recorded in 0x1003 (newest at sub1, sub0 = number recorded; writing 0 to
 * sub0 clears the history; writing anything else is refused with 0x06090030).
 * Frames respect the inhibit time 0x1015 (units of 100 us): raises that come
 * faster wait in a queue of CO_EMCY_QUEUE_LEN and leave one inhibit time apart; a
 * full queue drops the newest and counts it. EMCY is sent only in pre-operational
 * and operational; raised in another state it is recorded and sent on entering
 * one of those states.
 *
 * Codes the stack raises itself: 0x8130 heartbeat/life guarding lost, 0x8110 CAN
 * overrun, 0x8120 error passive, 0x8140 recovered from bus-off (reported by the
 * driver through co_node_bus_event).
 *
 * Consumer. 0x1028 subN holds COB-IDs to watch (bit 31 = unused); each EMCY frame
 * received on one of them is decoded and handed to on_emcy with the sender's
 * COB-ID. Frames shorter than 8 bytes are ignored and counted as malformed.
 *
 * Left out by configuration (canola/config.h): the history with CO_CONFIG_EMCY_HISTORY 0
 * (nothing recorded, 0x1003 a plain entry), the inhibit time and its queue with
 * CO_EMCY_QUEUE_LEN 0 (every frame leaves at once; a frame raised while the NMT state holds
 * EMCY back, before boot-up or in stopped, is not sent), the consumer with
 * CO_EMCY_CONSUMERS_MAX 0 (no 0x1028 COB-ID routed, on_emcy never called).
 *
 * Memory: 8 bytes per queued frame, 2 per active error, 4 per consumer entry.
 */
#ifndef CANOLA_EMCY_H
#define CANOLA_EMCY_H

#include "canola/config.h"
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

/** Data bytes of an EMCY frame: error code (2), error register (1), manufacturer (5). */
#define CO_EMCY_FRAME_LEN 8u

/** One emergency message as received (or sent). */
typedef struct co_emcy_msg {
    uint32_t cob_id; /**< COB-ID it arrived on (consumer) */
    uint16_t code;   /**< CiA 301 error code */
    uint8_t reg;     /**< the sender's error register */
    uint8_t manufacturer[5];
} co_emcy_msg_t;

/** EMCY state of a node (embedded in co_node_t; fields are internal). The queue exists
 *  with CO_EMCY_QUEUE_LEN > 0 (the inhibit time), the consumer entries with
 *  CO_EMCY_CONSUMERS_MAX > 0. */
typedef struct co_emcy {
#if CO_EMCY_QUEUE_LEN > 0
    uint64_t last_us; /**< inhibit: time of the latest frame sent, CO_TIME_NEVER: none */
    uint8_t queue[CO_EMCY_QUEUE_LEN][CO_EMCY_FRAME_LEN]; /**< frames waiting for the inhibit time */
    uint8_t queue_count;
    uint32_t dropped; /**< frames lost to a full queue */
#endif
    uint16_t active[CO_EMCY_ACTIVE_MAX]; /**< error codes active now */
    uint8_t active_count;
#if CO_EMCY_CONSUMERS_MAX > 0
    uint8_t consumer_count; /**< 0x1028 sub-indices bound */
    uint32_t consumer_cob[CO_EMCY_CONSUMERS_MAX];
#endif
} co_emcy_t;

/** Bus events a driver reports (co_node_bus_event). */
typedef enum co_bus_event {
    CO_BUS_RX_OVERRUN = 1, /**< frames were lost in reception -> EMCY 0x8110 */
    CO_BUS_ERROR_PASSIVE,  /**< the controller is error passive -> EMCY 0x8120 */
    CO_BUS_ERROR_ACTIVE,   /**< back to error active: clears 0x8120 */
    CO_BUS_OFF,            /**< bus-off: communication error behaviour (0x1029) */
    CO_BUS_OFF_RECOVERED,  /**< back on the bus -> EMCY 0x8140 */
} co_bus_event_t;

/** The error register bit (0x1001) an error code sets besides bit 0 (generic). */
uint8_t co_emcy_register_bit(uint16_t code);

/** Raise error `code` (not 0) with 5 manufacturer-specific bytes (may be NULL = zeros):
 *  send an EMCY, record it in 0x1003, update 0x1001. Raising an active code again sends
 *  it again. Returns CO_ERR_ARG for code 0, CO_ERR_FULL when CO_EMCY_ACTIVE_MAX errors
 *  are active (the frame is still sent and recorded), CO_OK otherwise. */
co_err_t co_emcy_raise(co_node_t *node, uint16_t code, const uint8_t *manufacturer);

/** Clear error `code`: update 0x1001; when it was the last active error, send the error
 *  reset EMCY (code 0x0000). Returns CO_ERR_NOT_FOUND when the code was not active. */
co_err_t co_emcy_clear(co_node_t *node, uint16_t code);

/** True while `code` is active. */
bool co_emcy_active(const co_node_t *node, uint16_t code);

/** Report a bus event from the driver (see co_bus_event_t). */
void co_node_bus_event(co_node_t *node, co_bus_event_t event);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_EMCY_H */
