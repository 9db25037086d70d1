/* SPDX-License-Identifier: Apache-2.0 */
/*
 * pattern_domain.h -- a DOMAIN that is never stored: uploads produce a pattern, downloads
 * are checked against it.
 *
 * It shows how OD hooks stream values of any size through a small buffer: the entry has
 * no storage (value NULL, size 0xFFFFFFFF); the read hook computes each piece an upload
 * asks for, and the write hook looks at each piece of a download as it arrives and keeps
 * nothing but a few counters. The tests and benches use it to move megabytes without
 * keeping them: the client holds the only copy.
 *
 * The pattern is a pseudo-random byte sequence chosen by a seed: byte i of pattern `seed`
 * is pattern_byte(seed, i). pattern_fill() writes one into a buffer (what a client sends),
 * pattern_matches() compares a buffer with one (what a client received).
 *
 * Use: put pattern_domain_entry(index) into a dictionary, point co_od_t.hook_ctx at a
 * pattern_domain_t (the hooks' context), and set its length and seeds before a transfer.
 * Uploads and downloads have a seed each, so both can run at once (on two SDO channels)
 * with different data. After a download, pattern_domain_received() says whether it
 * arrived whole, in order and right.
 *
 * Threading: none; the hooks run in whatever calls co_node_ingest(). Memory: the struct.
 */
#ifndef CANOLA_PATTERN_DOMAIN_H
#define CANOLA_PATTERN_DOMAIN_H

#include "canola/od.h"

/** One streamed DOMAIN: the hooks' context (co_od_t.hook_ctx). */
typedef struct pattern_domain {
    /* Set by the application before a transfer. */
    uint32_t length;    /**< bytes an upload produces */
    uint32_t up_seed;   /**< the pattern an upload produces */
    uint32_t down_seed; /**< the pattern a download must carry */
    /* Kept by the write hook; reset when a download starts (a piece at offset 0). */
    uint32_t received; /**< end of the latest piece: bytes delivered when all came in order */
    uint32_t pieces;   /**< write hook calls of this download */
    bool mismatch;     /**< a byte differed from the pattern, or a piece came out of order */
    bool complete;     /**< the last piece arrived */
} pattern_domain_t;

/** Byte `i` of pattern `seed`. */
uint8_t pattern_byte(uint32_t seed, uint32_t i);

/** Write the first `len` bytes of pattern `seed` into `buf`. */
void pattern_fill(uint8_t *buf, uint32_t seed, uint32_t len);

/** True when `buf` holds the first `len` bytes of pattern `seed`. */
bool pattern_matches(const uint8_t *buf, uint32_t seed, uint32_t len);

/** The hooks: read produces `length` bytes of pattern `up_seed`; write checks each piece
 *  against pattern `down_seed` and its offset against the bytes received so far. Neither
 *  ever aborts. Context: the pattern_domain_t. */
extern const co_od_hooks_t pattern_domain_hooks;

/** The entry: `index` sub 0, DOMAIN, rw, no storage, size 0xFFFFFFFF, pattern_domain_hooks. */
co_od_entry_t pattern_domain_entry(uint16_t index);

/** True when a download of exactly `len` bytes arrived: in order, matching pattern
 *  `down_seed`, last piece included. */
bool pattern_domain_received(const pattern_domain_t *d, uint32_t len);

#endif /* CANOLA_PATTERN_DOMAIN_H */
