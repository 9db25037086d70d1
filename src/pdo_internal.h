/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/pdo_internal.h -- the PDO family (see canola/pdo.h): what the node and SYNC call, and what
 * pdo.c, pdo_map.c, pdo_rx.c, pdo_tx.c and pdo_timers.c tell each other. Not installed.
 */
#ifndef CANOLA_PDO_INTERNAL_H
#define CANOLA_PDO_INTERNAL_H

#include <string.h>

#include "kernel.h"
#include "od_plain.h"
#include "standin.h"

/* ---- what the node and SYNC call */
void co_pdo_reset_comm(co_node_t *node);
void co_pdo_state_entered(co_node_t *node);
void co_pdo_rx(co_node_t *node, uint8_t rpdo, const co_frame_t *frame);
void co_pdo_rtr(co_node_t *node, uint8_t tpdo, const co_frame_t *frame);
void co_pdo_sync(co_node_t *node, uint8_t counter); /* a SYNC taken, sync.last_us its time */
co_abort_t co_pdo_check_write(co_node_t *node, const co_od_entry_t *entry, const uint8_t *data,
                              uint32_t len);
void co_pdo_written(co_node_t *node, const co_od_entry_t *entry); /* 0x1400..0x1BFF */
void co_pdo_changed(co_node_t *node, const co_od_entry_t *entry); /* any value written */
/* co_pdo_poll: pdo_timers.h */

/* The PDOs' objects (node_od.c): communication and mapping parameters, 0x1400..0x1BFF. */
#define CO_PDO_OBJECT_ROWS                                                                         \
    CO_OBJECT_ROW(0x1400, 0x1BFF, CO_COB_NONE, co_pdo_check_write, co_pdo_written)

/* ---- inside the family */

/* co_pdo_t.flags */
#define PDO_F_PRESENT 0x01u   /* the dictionary has this PDO's communication object */
#define PDO_F_PENDING 0x02u   /* TPDO: an event waits (inhibit end, or SYNC for type 0) */
#define PDO_F_SAMPLED 0x04u   /* TPDO 252: data[] holds the sample of the last SYNC */
#define PDO_F_STARTED 0x08u   /* TPDO 1..240 with a SYNC start value: counting has begun */
#define PDO_F_WAITING 0x10u   /* RPDO 0..240: data[] waits for the next SYNC */
#define PDO_F_TIMED_OUT 0x20u /* RPDO: deadline missed and reported, until the next RPDO */
#define PDO_F_LEN_ERROR 0x40u /* RPDO: raised 0x8210/0x8220, until a frame of the right length */
#define PDO_RTR_NOT_ALLOWED 0x40000000u /* TPDO COB-ID bit 30 */
#define PDO_VALUE_MAX 8u                /* bytes of the widest mappable value (64 bits) */

static inline void pdo_set(co_pdo_t *p, unsigned f) { p->flags = (uint8_t)(p->flags | f); }
static inline void pdo_clear(co_pdo_t *p, unsigned f) { p->flags = (uint8_t)(p->flags & ~f); }
static inline bool pdo_has(const co_pdo_t *p, unsigned f) { return (p->flags & f) != 0; }

/* A PDO that runs: present, valid (COB-ID bit 31 clear) and mapping something. A PDO
 * mapping nothing (also one whose mapping failed to resolve) does nothing. */
static CO_SIZE_INLINE bool pdo_active(const co_pdo_t *p)
{
    return pdo_has(p, PDO_F_PRESENT) && !(p->cob_id & CO_COB_INVALID) && p->count > 0;
}

/* The node's RPDO and TPDO slots (slot n: PDO n + 1; the ones the dictionary lacks stay
 * not present): constants the loops and bounds need not load. */
static inline unsigned pdo_rx_count(const co_node_t *node)
{
    (void)node;
    return CO_RPDO_MAX;
}
static inline unsigned pdo_tx_count(const co_node_t *node)
{
    (void)node;
    return CO_TPDO_MAX;
}

/* PDOs run in operational only. */
static inline bool pdo_running(const co_node_t *node)
{
    return node->nmt_state == CO_NMT_OPERATIONAL;
}

/* Slot i's entry, for a slot that is no dummy entry (a plain or direct one, or any slot
 * without bit-granular mapping). */
static inline const co_od_entry_t *pdo_mapped(const co_od_t *od, const co_pdo_t *p, unsigned i)
{
#if CO_CONFIG_OD_COMPACT
    return &od->entries[p->map_entry[i]];
#else
    (void)od;
    return p->map_entry[i];
#endif
}

/* Slot i's entry, NULL for a dummy entry (only bit-granular mapping has them). */
static inline const co_od_entry_t *pdo_entry(const co_od_t *od, const co_pdo_t *p, unsigned i)
{
    if (!CO_CONFIG_PDO_BIT_MAPPING) {
        return pdo_mapped(od, p, i); /* no dummies */
    }
    return p->map_entry[i] != CO_PDO_NO_ENTRY ? pdo_mapped(od, p, i) : NULL;
}

/* Slot i's storage, for a slot that is no dummy entry. */
static inline void *pdo_value(const co_od_t *od, const co_pdo_t *p, unsigned i)
{
    return co_od_value(od, pdo_mapped(od, p, i));
}

/* Bits slot i maps: without bit-granular mapping always the whole value (no dummies). */
static inline uint8_t pdo_item_bits(const co_od_t *od, const co_pdo_t *p, unsigned i)
{
#if CO_CONFIG_PDO_BIT_MAPPING
    (void)od;
    return p->map_bits[i];
#else
    /* (a mapped object's size is its type's: mappable, pdo_map.c) */
    return (uint8_t)(8u * co_type_size((co_type_t)co_od_type(od, pdo_mapped(od, p, i))));
#endif
}

/* Slot i of a frame: its entry, and the bytes of a whole number it maps that is stored as it
 * travels (copied between the frame and the storage, as co_od_read and co_od_store would do,
 * without their type table), else 0. Returns the slot's bits. */
static inline uint8_t pdo_item(const co_od_t *od, const co_pdo_t *p, unsigned i,
                               const co_od_entry_t **entry, uint32_t *whole)
{
    const co_od_entry_t *e = pdo_entry(od, p, i);
    uint32_t n = e != NULL && co_od_hooks_of(e) == NULL ? co_native_size(co_od_type(od, e)) : 0u;
    uint8_t bits =
        CO_CONFIG_PDO_BIT_MAPPING || n == 0 ? pdo_item_bits(od, p, i) : (uint8_t)(8u * n);
    *entry = e;
    *whole = bits == 8u * n ? n : 0u;
    return bits;
}

/* Bytes the mapping fills. */
static inline uint8_t pdo_bytes(const co_pdo_t *p) { return (uint8_t)((p->bits + 7u) / 8u); }

/* pdo_map.c: resolving mappings into co_pdo_t, checking a new one; copying `n` bits from bit
 * `spos` of src to bit `dpos` of dst (LSB first). */
void pdo_load_mapping(co_node_t *node, co_pdo_t *p, bool tpdo, uint16_t num);
#if CO_CONFIG_PDO_BIT_MAPPING
void pdo_copy_bits(uint8_t *dst, uint32_t dpos, const uint8_t *src, uint32_t spos, uint32_t n);
#endif
#if CO_CONFIG_PDO_DYNAMIC
/* A write to mapping object sub `sub` of PDO `num` (the re-mapping procedure). */
co_abort_t pdo_check_mapping(const co_node_t *node, bool tpdo, uint16_t num, uint8_t sub,
                             const uint8_t *data, uint32_t len);
#else
static inline co_abort_t pdo_check_mapping(const co_node_t *node, bool tpdo, uint16_t num,
                                           uint8_t sub, const uint8_t *data, uint32_t len)
{
    (void)node;
    (void)tpdo;
    (void)num;
    (void)sub;
    (void)data;
    (void)len;
    return CO_ABORT_READ_ONLY; /* the dictionary's mapping is fixed in this build */
}
#endif
static inline uint16_t pdo_comm_index(bool tpdo, uint16_t num)
{
    return (uint16_t)((tpdo ? 0x1800u : 0x1400u) + num);
}
static inline uint16_t pdo_map_index(bool tpdo, uint16_t num)
{
    return (uint16_t)((tpdo ? 0x1A00u : 0x1600u) + num);
}

/* pdo_tx.c */
bool tpdo_event(co_node_t *node, co_pdo_t *p); /* true when the event marked it */
void tpdo_sync(co_node_t *node, co_pdo_t *p, uint8_t counter);
void tpdo_send_event(co_node_t *node, co_pdo_t *p); /* an event-driven transmission */

/* pdo.c: another RPDO than `self` has `flag` set. */
bool rpdo_other_has(const co_node_t *node, const co_pdo_t *self, unsigned flag);

/* pdo_timers.c (its header uses the helpers above) */
#include "pdo_timers.h"

#endif /* CANOLA_PDO_INTERNAL_H */
