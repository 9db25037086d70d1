/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/emcy_internal.h -- the EMCY family (see canola/emcy.h): the producer (emcy.c), its
 * inhibit time and queue (emcy_queue.c, CO_EMCY_QUEUE_LEN > 0), the error history 0x1003
 * (emcy_history.c, CO_CONFIG_EMCY_HISTORY) and the consumer 0x1028 (emcy_consumer.c,
 * CO_EMCY_CONSUMERS_MAX > 0). Other services raise and clear errors through canola/emcy.h.
 * Not installed.
 */
#ifndef CANOLA_EMCY_INTERNAL_H
#define CANOLA_EMCY_INTERNAL_H

#include "kernel.h"
#include "standin.h"

/* emcy.c */
void co_emcy_reset_comm(co_node_t *node);
void co_emcy_written(co_node_t *node, const co_od_entry_t *entry); /* 0x1003, 0x1014.., 0x1028 */
bool co_emcy_producer_off(const co_node_t *node);                  /* 0x1014 bit 31 */
co_abort_t co_emcy_cob_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                                   uint32_t len); /* 0x1014: valid to valid refused */
void co_emcy_frame_send(co_node_t *node, const uint8_t data[CO_EMCY_FRAME_LEN]);

/* emcy_queue.c: without it frames leave at once. */
#if CO_EMCY_QUEUE_LEN > 0
void co_emcy_queue_emit(co_node_t *node, const uint8_t data[CO_EMCY_FRAME_LEN]);
void co_emcy_queue_reset(co_node_t *node);
void co_emcy_queue_clear(co_node_t *node);
uint64_t co_emcy_poll(co_node_t *node, uint64_t now_us);
void co_emcy_state_entered(co_node_t *node);
#else
static inline void co_emcy_queue_emit(co_node_t *node, const uint8_t data[CO_EMCY_FRAME_LEN])
{
    co_emcy_frame_send(node, data);
}
#define co_emcy_queue_reset co_none_node
#define co_emcy_queue_clear co_none_node
#define co_emcy_poll co_none_poll
#define co_emcy_state_entered co_none_node
#endif

/* emcy_history.c */
#if CO_CONFIG_EMCY_HISTORY
void co_emcy_history_record(co_node_t *node, uint16_t code, const uint8_t mfr[5]);
void co_emcy_history_clear(co_node_t *node);
co_abort_t co_emcy_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                               uint32_t len);
#else
static inline void co_emcy_history_record(co_node_t *node, uint16_t code, const uint8_t mfr[5])
{
    (void)node;
    (void)code;
    (void)mfr;
}
#define co_emcy_history_clear co_none_node
#define co_emcy_check_write co_none_check
#endif

/* emcy_consumer.c: its routes follow 0x1028 (bind, at reset communication and on writes). */
#if CO_EMCY_CONSUMERS_MAX > 0
void co_emcy_consumers_bind(co_node_t *node);
void co_emcy_ingest(co_node_t *node, uint8_t slot, const co_frame_t *frame);
#else
#define co_emcy_consumers_bind co_none_node
#define co_emcy_ingest co_none_slot_frame
#endif

/* EMCY's objects (node_od.c): 0x1014 its COB-ID, 0x1015 the inhibit time (with the queue),
 * 0x1003 the history, 0x1028 the consumer's COB-IDs. */
#if CO_CONFIG_EMCY_HISTORY
#define CO_EMCY_HISTORY_ROWS                                                                       \
    CO_OBJECT_ROW(0x1003, 0x1003, CO_COB_NONE, co_emcy_check_write, co_emcy_written)
#else
#define CO_EMCY_HISTORY_ROWS
#endif
#if CO_EMCY_QUEUE_LEN > 0
#define CO_EMCY_QUEUE_ROWS CO_OBJECT_ROW(0x1015, 0x1015, CO_COB_NONE, NULL, co_emcy_written)
#else
#define CO_EMCY_QUEUE_ROWS
#endif
#define CO_EMCY_OBJECT_ROWS                                                                        \
    CO_EMCY_HISTORY_ROWS                                                                           \
    CO_OBJECT_ROW(0x1014, 0x1014, CO_COB_SUB0, co_emcy_cob_check_write,                            \
                  CO_EMCY_QUEUE_LEN > 0 ? co_emcy_written : NULL)                                  \
    CO_EMCY_QUEUE_ROWS                                                                             \
    CO_OBJECT_ROW(0x1028, 0x1028, CO_COB_SUB1_UP, NULL,                                            \
                  CO_EMCY_CONSUMERS_MAX > 0 ? co_emcy_written : NULL)

#endif /* CANOLA_EMCY_INTERNAL_H */
