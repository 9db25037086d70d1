/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/time.h -- the TIME object (time stamp): producer and consumer.
 *
 * 0x1012 COB-ID TIME (default 0x100; bit 31 = this node consumes TIME, bit 30 =
 * it produces TIME, bit 29 = 29-bit identifier). The frame carries TIME_OF_DAY,
 * 6 bytes: milliseconds after midnight in bits 0..27 of the first four bytes (bits
 * 28..31 reserved, sent as 0, ignored on reception), then the days since
 * 1984-01-01 (u16). A consumer reports each TIME frame of 6 bytes to on_time;
 * other lengths are ignored and counted as malformed. TIME runs in pre-operational
 * and operational only.
 */
#ifndef CANOLA_TIME_H
#define CANOLA_TIME_H

#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

/** A TIME_OF_DAY value. */
typedef struct co_time_of_day {
    uint32_t ms;   /**< milliseconds after midnight, 0..86399999 */
    uint16_t days; /**< days since 1984-01-01 */
} co_time_of_day_t;

/** TIME state of a node (embedded in co_node_t; fields are internal). */
typedef struct co_time {
    uint32_t cob_id; /**< 0x1012 */
} co_time_t;

/** Encode into 6 wire bytes / decode from them (reserved bits dropped). */
void co_time_encode(const co_time_of_day_t *t, uint8_t out[6]);
co_time_of_day_t co_time_decode(const uint8_t in[6]);

/** Convert between TIME_OF_DAY and microseconds since 1984-01-01 00:00. */
uint64_t co_time_to_us(const co_time_of_day_t *t);
co_time_of_day_t co_time_from_us(uint64_t us_since_1984);

/** Send a TIME frame with `t` as a producer (0x1012 bit 30 set). Returns CO_ERR_STATE
 *  when this node is not a TIME producer or the NMT state does not allow TIME, CO_ERR_ARG
 *  when ms is 86400000 or more. */
co_err_t co_time_send(co_node_t *node, const co_time_of_day_t *t);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_TIME_H */
