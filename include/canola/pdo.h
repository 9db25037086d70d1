/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/pdo.h -- process data objects: RPDOs received and applied to the object
 * dictionary, TPDOs packed from it and sent, with every CiA 301 transmission type.
 *
 * Objects (n = PDO number - 1): RPDO communication 0x1400+n (sub1 COB-ID: bit 31 =
 * not valid, bit 30 = no RTR allowed (TPDO), bit 29 = 29-bit; sub2 transmission type;
 * sub5 event timer, ms: RPDO deadline monitoring), RPDO mapping 0x1600+n, TPDO
 * communication 0x1800+n (sub1, sub2, sub3 inhibit time in 100 us, sub5 event timer
 * in ms, sub6 SYNC start value), TPDO mapping 0x1A00+n. Mapping: sub0 = number of
 * entries, subK = index << 16 | sub << 8 | length in bits. The node handles the
 * first CO_RPDO_MAX / CO_TPDO_MAX of each that its dictionary has; default COB-IDs
 * come from the dictionary's $NODEID defaults (0x200/0x300/0x400/0x500 + ID for
 * RPDO1..4, 0x180/0x280/0x380/0x480 + ID for TPDO1..4).
 *
 * Mapping is resolved once, when it becomes valid (reset communication, sub0
 * written): each entry to its object's storage and a bit length, so frames are
 * packed and unpacked without dictionary look-ups. An entry may map fewer bits than
 * its object has (bit-level mapping: the low bits); RPDOs may map the data types
 * 0x0001..0x0007 (dummy entries) to skip bits. Total at most 64 bits.
 *
 * The re-mapping procedure is enforced: mapping entries (subK >= 1) may be written only
 * while the PDO is not valid (COB-ID bit 31) and sub0 is 0, else abort 0x06010000;
 * writing sub0 = N checks entries 1..N: the object must exist and be mappable in that
 * direction (CO_OD_RPDO / CO_OD_TPDO; dummy types for RPDOs only), else 0x06040041; the
 * total must fit 64 bits, else 0x06040042; sub0 above the entries the dictionary has is
 * 0x06090031. A valid PDO's COB-ID may only become not valid (another valid value:
 * 0x06090030); transmission types 241..251 are 0x06090030; a COB-ID with bits above an
 * 11-bit ID is 0x06090030.
 *
 * TPDO transmission types: 0 synchronous acyclic (sent at the next SYNC after an
 * event), 1..240 every n-th SYNC (counted from the SYNC whose counter equals the SYNC
 * start value when that is not 0), 252 sampled at SYNC and sent on RTR, 253 sent on
 * RTR (sampled then), 254/255 event-driven: sent on an event, on the event timer
 * (sub5, a period restarted by every transmission) and when the application changes a
 * mapped object through the node (co_node_set_uint, co_node_write_net, or co_pdo_event),
 * never closer than the inhibit time (sub3) after the previous one: an event inside
 * the inhibit time is sent when it ends. Synchronous TPDOs outside the synchronous
 * window (0x1007) are not sent.
 *
 * RPDO transmission types: 0..240 synchronous (the data received is applied at the
 * next SYNC, inside the window), 254/255 applied at once. A frame shorter than the
 * mapping is not applied: EMCY 0x8210; longer: applied, EMCY 0x8220. With an event
 * timer, an RPDO not received within it after the previous one (monitoring starts
 * with the first) raises EMCY 0x8250 and applies the error behaviour (0x1029);
 * on_rpdo tells the application after each applied RPDO.
 *
 * PDOs run in operational only.
 *
 * Left out by configuration (canola/config.h): the timers with CO_CONFIG_PDO_TIMERS 0
 * (sub3 and sub5 without effect: an event-driven TPDO goes at each event, an RPDO is not
 * monitored), re-mapping with CO_CONFIG_PDO_DYNAMIC 0 (the dictionary's mapping, writes
 * to 0x1600.. and 0x1A00.. refused with 0x06010002), bit-granular mapping and dummy
 * entries with CO_CONFIG_PDO_BIT_MAPPING 0 (every entry a whole object: another mapping
 * is 0x06040041, and maps nothing when the dictionary holds it).
 *
 * Cost: an RPDO of two byte-aligned 32-bit entries is a route look-up plus two copies.
 * Memory (32-bit targets): 48 bytes per PDO (28 without the timers) plus 5 per mapping
 * slot (CO_PDO_MAP_MAX) and 1 per 8 slots: 89 bytes per PDO with the default 8 slots.
 */
#ifndef CANOLA_PDO_H
#define CANOLA_PDO_H

#include "canola/config.h"
#include "canola/od.h"
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct co_node co_node_t;

/** A mapped entry of a PDO (internal): the entry itself, NULL for a dummy entry; in the
 *  compact form of the dictionary (CO_CONFIG_OD_COMPACT) its position in co_od_t.entries,
 *  CO_PDO_NO_ENTRY for a dummy entry (2 bytes of RAM per slot instead of a pointer's 4). */
#if CO_CONFIG_OD_COMPACT
typedef uint16_t co_pdo_item_t;
#define CO_PDO_NO_ENTRY UINT16_MAX
#else
typedef const co_od_entry_t *co_pdo_item_t;
#define CO_PDO_NO_ENTRY NULL
#endif

/** One PDO's resolved mapping and state (embedded in the node; fields are internal). The
 *  mapping is kept in parallel arrays: an entry and (with bit-granular mapping; else the
 *  entry's size says it) a bit count per slot. The byte fields come first: Cortex-M
 *  reaches the first 32 bytes of a struct with the short byte loads and stores. */
typedef struct co_pdo {
    uint8_t sync_start;              /**< TPDO sub6: SYNC start value */
    uint8_t count;                   /**< mapped entries */
    uint8_t bits;                    /**< mapped bits in all */
    uint8_t type;                    /**< transmission type */
    uint8_t sync_count;              /**< SYNCs counted towards the next transmission */
    uint8_t flags;                   /**< internal state bits (src/pdo_internal.h) */
    uint8_t data[CO_FRAME_DATA_MAX]; /**< RPDO: data waiting for SYNC; TPDO: sampled for RTR */
#if CO_CONFIG_PDO_BIT_MAPPING
    uint8_t map_bits[CO_PDO_MAP_MAX]; /**< bits mapped per slot */
#endif
    co_pdo_item_t map_entry[CO_PDO_MAP_MAX];
    uint32_t cob_id;
#if CO_CONFIG_PDO_TIMERS
    uint16_t event_ms; /**< sub5: TPDO event timer / RPDO deadline, ms (0 = off) */
    uint16_t inhibit;  /**< TPDO sub3: inhibit time, 100 us */
    uint64_t next_us;  /**< TPDO: event timer; RPDO: deadline */
    uint64_t inhibit_until_us;
#endif
} co_pdo_t;

/** Mark the TPDOs mapping (index, sub) as having an event (as a change of a mapped value
 *  made outside the node's functions would). Returns the number of TPDOs marked. */
uint32_t co_pdo_event(co_node_t *node, uint16_t index, uint8_t sub);

/** Send TPDO `n` (0-based) now if its type is event-driven (254/255) or acyclic (0: at
 *  the next SYNC), respecting the inhibit time. Returns CO_ERR_ARG for a PDO the node does
 *  not have, CO_ERR_STATE when it is not valid or the node not operational. */
co_err_t co_tpdo_request(co_node_t *node, uint8_t n);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_PDO_H */
