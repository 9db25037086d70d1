/* SPDX-License-Identifier: Apache-2.0 */
/*
 * emcy.c -- the EMCY producer: the error register 0x1001, the active errors, raise and
 * clear, the frames and bus events (see canola/emcy.h). The inhibit time and its queue
 * (emcy_queue.c), the error history 0x1003 (emcy_history.c) and the consumer 0x1028
 * (emcy_consumer.c) are their own files, each left out by its switch or size.
 */
#include <string.h>

#include "emcy_internal.h"

#define EMCY_COB_BASE 0x80u
#define EMCY_CODE_RESET 0x0000u /* "error reset / no error" */

#define REG_GENERIC 0x01u

/* ---- error register */

uint8_t co_emcy_register_bit(uint16_t code)
{
    unsigned group = code >> 12u;
    if (group - 2u <= 2u) {
        return (uint8_t)(1u << (group - 1u)); /* 2xxx current, 3xxx voltage, 4xxx temperature */
    }
    if (code >= 0x8100u && code <= 0x8FFFu) {
        return 0x10; /* communication */
    }
    if (code >= 0xFF00u) {
        return 0x80; /* manufacturer-specific */
    }
    return 0;
}

/* The register as the active errors make it. */
static uint8_t register_of_active(const co_node_t *node)
{
    const co_emcy_t *e = &node->emcy;
    uint8_t reg = e->active_count ? REG_GENERIC : 0;
    for (uint8_t i = 0; i < e->active_count; i++) {
        reg = (uint8_t)(reg | co_emcy_register_bit(e->active[i]));
    }
    return reg;
}

static CO_SIZE_NOINLINE void register_store(co_node_t *node, uint8_t reg)
{
    (void)co_od_set_uint(&node->cfg.od, 0x1001, 0, reg); /* no 0x1001: nothing to keep */
}

/* ---- active errors */

static CO_SIZE_NOINLINE int active_find(const co_node_t *node, uint16_t code)
{
    for (uint8_t i = 0; i < node->emcy.active_count; i++) {
        if (node->emcy.active[i] == code) {
            return i;
        }
    }
    return -1;
}

bool co_emcy_active(const co_node_t *node, uint16_t code) { return active_find(node, code) >= 0; }

/* ---- producer frames */

/* The COB-ID object 0x1014; without one, the pre-defined 0x80 + node-ID. */
static uint32_t producer_cob(const co_node_t *node)
{
    return co_od_u32(node, 0x1014, 0, EMCY_COB_BASE + node->node_id);
}

bool co_emcy_producer_off(const co_node_t *node)
{
    return (producer_cob(node) & CO_COB_INVALID) != 0;
}

void co_emcy_frame_send(co_node_t *node, const uint8_t data[CO_EMCY_FRAME_LEN])
{
    uint32_t cob = producer_cob(node);
    if (cob & CO_COB_INVALID) {
        return; /* EMCY off: errors and history are kept, nothing is sent */
    }
    /* a full tx queue counts the loss itself */
    (void)co_node_send_cob(node, cob, data, CO_EMCY_FRAME_LEN, CO_SVC_EMCY);
}

/* One EMCY frame: out now, or after the inhibit time (emcy_queue.c). */
static CO_SIZE_NOINLINE void emit(co_node_t *node, uint16_t code, uint8_t reg, const uint8_t mfr[5])
{
    if (CO_EMCY_QUEUE_LEN > 0 && co_emcy_producer_off(node)) {
        return; /* nothing queued either (without a queue, co_emcy_frame_send tells) */
    }
    uint8_t data[CO_EMCY_FRAME_LEN];
    co_put_u16(data, code);
    data[2] = reg;
    co_copy(&data[3], mfr, 5);
    co_emcy_queue_emit(node, data);
}

/* ---- raise and clear */

static const uint8_t k_zeros[5] = {0};

co_err_t co_emcy_raise(co_node_t *node, uint16_t code, const uint8_t *manufacturer)
{
    if (code == EMCY_CODE_RESET) {
        return CO_ERR_ARG;
    }
    const uint8_t *mfr = manufacturer ? manufacturer : k_zeros;
    co_emcy_t *e = &node->emcy;
    co_err_t err = CO_OK;
    if (active_find(node, code) < 0) {
        if (e->active_count < CO_EMCY_ACTIVE_MAX) {
            e->active[e->active_count++] = code;
        } else {
            err = CO_ERR_FULL;
        }
    }
    /* An error the table could not keep still shows in the register until the next
     * change recomputes it from the errors kept. */
    uint8_t reg = (uint8_t)(register_of_active(node) | REG_GENERIC | co_emcy_register_bit(code));
    register_store(node, reg);
    co_emcy_history_record(node, code, mfr);
    emit(node, code, reg, mfr);
    return err;
}

co_err_t co_emcy_clear(co_node_t *node, uint16_t code)
{
    int at = active_find(node, code);
    if (at < 0) {
        return CO_ERR_NOT_FOUND;
    }
    co_emcy_t *e = &node->emcy;
    e->active_count--;
    e->active[at] = e->active[e->active_count]; /* order does not matter */
    uint8_t reg = register_of_active(node);
    register_store(node, reg);
    if (e->active_count == 0) {
        emit(node, EMCY_CODE_RESET, reg, k_zeros);
    }
    return CO_OK;
}

/* ---- node hooks */

void co_emcy_reset_comm(co_node_t *node)
{
    co_emcy_consumers_bind(node);
    co_emcy_queue_reset(node); /* the producer starts afresh: no inhibit pending */
    /* The reset restored 0x1001 (and 0x1003) to power-on values; the errors still
     * active set the register again. */
    register_store(node, register_of_active(node));
    /* Reset communication restarts heartbeat and guarding monitoring: what 0x8130
     * reported is over (the error reset EMCY, if it is the last, leaves after boot-up). */
    (void)co_emcy_clear(node, 0x8130);
}

/* CiA 301 7.5.2.17: the identifier of a valid COB-ID EMCY does not change; a new one goes
 * through "not valid" (bit 31). */
co_abort_t co_emcy_cob_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                                   uint32_t len)
{
    if (len != 4) {
        return CO_ABORT_NONE; /* the length check of the entry answers */
    }
    uint32_t now = (uint32_t)co_od_entry_uint(&node->cfg.od, entry);
    uint32_t next = co_get_u32(data);
    bool both_valid = !(now & CO_COB_INVALID) && !(next & CO_COB_INVALID);
    return (both_valid && next != now) ? CO_ABORT_VALUE : CO_ABORT_NONE;
}

void co_emcy_written(co_node_t *node, const co_od_entry_t *entry)
{
    switch (entry->index) {
    case 0x1003:
        if (entry->sub == 0) {
            co_emcy_history_clear(node);
        }
        break;
    case 0x1014:
        if (co_emcy_producer_off(node)) {
            co_emcy_queue_clear(node); /* EMCY off: nothing waits to be sent */
        }
        break;
    case 0x1015:
        /* a shorter inhibit time may let a waiting frame leave earlier */
        co_emcy_state_entered(node);
        break;
    case 0x1028:
        co_emcy_consumers_bind(node); /* and their routes */
        break;
    default:
        break;
    }
}
