/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/sync.h -- the SYNC object: producer and consumer.
 *
 * 0x1005 COB-ID SYNC (default 0x80; bit 30 = this node produces SYNC, bit 29 =
 * 29-bit identifier). 0x1006 communication cycle period (UNSIGNED32, us; 0 = the
 * producer is idle). 0x1007 synchronous window length (UNSIGNED32, us; 0 = no
 * window). 0x1019 synchronous counter overflow value (UNSIGNED8: 0 = SYNC carries
 * no data; 2..240 = it carries one byte counting 1..value and wrapping to 1).
 * Changes to any of them take effect at once.
 *
 * Producer: one SYNC every period, the first one period after the producer was
 * enabled (or after the node entered pre-operational). Consumer: every node,
 * producer or not, handles the SYNC it receives (the producer its own, as sent)
 * and reports it to on_sync with the counter (0 when the SYNC carries none). A SYNC
 * whose length does not match 0x1019 (0 bytes expected and got some, or 1 expected
 * and got another length) raises EMCY 0x8240 and is otherwise ignored. SYNC runs
 * in pre-operational and operational only.
 *
 * Without the producer (CO_CONFIG_SYNC_PRODUCER 0) the node consumes SYNC only: 0x1005
 * bit 30 and 0x1006 have no effect.
 *
 * The synchronous window: co_sync_in_window() tells whether `now` lies within the
 * window after the latest SYNC (synchronous PDOs outside it are neither sent nor
 * applied).
 */
#ifndef CANOLA_SYNC_H
#define CANOLA_SYNC_H

#include "canola/config.h"
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

/** SYNC state of a node (embedded in co_node_t; fields are internal). */
typedef struct co_sync {
    uint64_t last_us; /**< time of the latest SYNC, CO_TIME_NEVER before the first */
#if CO_CONFIG_SYNC_PRODUCER
    uint64_t next_us;                 /**< producer: next SYNC */
    const struct co_od_entry *period; /**< 0x1006, or NULL */
    uint8_t counter;                  /**< producer: counter of the next SYNC */
#endif
    uint8_t last_counter;               /**< counter of the latest SYNC */
    uint32_t cob_id;                    /**< 0x1005 */
    const struct co_od_entry *window;   /**< 0x1007, or NULL */
    const struct co_od_entry *overflow; /**< 0x1019, or NULL */
} co_sync_t;

/** True when the synchronous window (0x1007) after the latest SYNC is still open at
 *  `now_us`, or when no window is configured. False before the first SYNC. */
bool co_sync_in_window(const co_node_t *node, uint64_t now_us);

/** The counter of the latest SYNC (0 when SYNCs carry none or none was seen). */
uint8_t co_sync_counter(const co_node_t *node);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_SYNC_H */
