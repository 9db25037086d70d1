/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/od.h -- the object dictionary: a sorted, constant table of entries.
 *
 * Purpose: every value a CANopen device exposes lives in one table of entries
 * addressed by (index, sub-index). The table itself is const (it can live in
 * flash); each entry points at the RAM that holds its value and at a const
 * default (its power-on value), or in the compact form gives its value's offset in one
 * values struct (co_od_t.values) and finds its default in one image. Look-up is a binary search,
 * O(log n), or with the optional hash table (co_od_t.hash) O(1) expected.
 *
 * Values are stored in native form (uint16_t, float, ...); reads and writes
 * through this API speak wire form: little-endian bytes, as SDO and PDO carry
 * them. Storage width per type: BOOLEAN/INTEGER8/UNSIGNED8 -> 1 byte,
 * 16-bit -> 2, INTEGER24/UNSIGNED24/32-bit/REAL32 -> 4 (int32_t, uint32_t, float),
 * 40/48/56/64-bit and REAL64 -> 8; TIME_OF_DAY/TIME_DIFFERENCE -> 6 raw bytes;
 * VISIBLE_STRING/OCTET_STRING/UNICODE_STRING -> `size` bytes of buffer;
 * DOMAIN -> a co_od_domain_t (buffer + current length) or no storage at all
 * when hooks stream it. `size` is the length on the wire (for strings and
 * domains: the capacity). A core built without some of the dictionary's features
 * (canola/config.h: CO_CONFIG_OD_64BIT, CO_CONFIG_OD_LIMITS, CO_CONFIG_REAL_LIMITS,
 * CO_CONFIG_OD_DOMAIN, CO_CONFIG_OD_UNICODE) refuses a dictionary using them
 * (co_od_validate).
 *
 * Hooks let the application compute a value on read, validate or veto a write
 * with an abort code, stream large values (DOMAIN, long strings) in pieces, and
 * be told after a write. They run in the caller's context (whoever called
 * co_node_ingest() / the access function); they must not block.
 *
 * Threading: none inside. One OD belongs to one node; guard it with the node.
 * Memory: 28 bytes of const data per entry on 32-bit targets (48 on 64-bit hosts), plus
 * the values themselves; in the compact form (CO_CONFIG_OD_COMPACT, see co_od_entry) 6 on
 * every target, plus 4 per distinct (type, attributes, side) row, the power-on values'
 * image, the limits that entries have and the capacities of strings and domains
 * (co_od_tables_t).
 *
 * Reading an entry: co_od_value(od, entry) is its storage, co_od_size(od, entry) its size,
 * co_od_type and co_od_attr its type and attributes (both forms; the compact entry holds
 * none of them itself).
 */
#ifndef CANOLA_OD_H
#define CANOLA_OD_H

#include "canola/config.h" /* CO_CONFIG_OD_COMPACT, CO_CONFIG_OD_HASH */
#include "canola/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Version of the entry layout below. Generated dictionaries (canola.odgen) check it and
 *  refuse to compile against a library whose layout differs. 2: co_od_t.keys;
 *  3: co_od_t.hash; 4: the compact form (CO_CONFIG_OD_COMPACT); 5: its 8-byte entries
 *  (value offsets, co_od_tables_t); 6: numbers in its power-on image as their storage's
 *  bytes; 7: its 6-byte entries (type, attributes and side in co_od_t.rows). */
#ifndef CO_OD_FORMAT
#define CO_OD_FORMAT 7
#endif

/** CiA 301 data types; the value is the type's index (EDS `DataType=`). */
typedef enum co_type {
    CO_TYPE_BOOLEAN = 0x01,
    CO_TYPE_INTEGER8 = 0x02,
    CO_TYPE_INTEGER16 = 0x03,
    CO_TYPE_INTEGER32 = 0x04,
    CO_TYPE_UNSIGNED8 = 0x05,
    CO_TYPE_UNSIGNED16 = 0x06,
    CO_TYPE_UNSIGNED32 = 0x07,
    CO_TYPE_REAL32 = 0x08,
    CO_TYPE_VISIBLE_STRING = 0x09,
    CO_TYPE_OCTET_STRING = 0x0A,
    CO_TYPE_UNICODE_STRING = 0x0B,
    CO_TYPE_TIME_OF_DAY = 0x0C,
    CO_TYPE_TIME_DIFFERENCE = 0x0D,
    CO_TYPE_DOMAIN = 0x0F,
    CO_TYPE_INTEGER24 = 0x10,
    CO_TYPE_REAL64 = 0x11,
    CO_TYPE_INTEGER40 = 0x12,
    CO_TYPE_INTEGER48 = 0x13,
    CO_TYPE_INTEGER56 = 0x14,
    CO_TYPE_INTEGER64 = 0x15,
    CO_TYPE_UNSIGNED24 = 0x16,
    CO_TYPE_UNSIGNED40 = 0x18,
    CO_TYPE_UNSIGNED48 = 0x19,
    CO_TYPE_UNSIGNED56 = 0x1A,
    CO_TYPE_UNSIGNED64 = 0x1B,
} co_type_t;

/* ---- Entry attributes (co_od_entry_t.attr). */
#define CO_OD_READ 0x01u   /**< readable from the network */
#define CO_OD_WRITE 0x02u  /**< writable from the network */
#define CO_OD_CONST 0x04u  /**< value never changes (EDS `const`) */
#define CO_OD_TPDO 0x08u   /**< may be mapped into a TPDO */
#define CO_OD_RPDO 0x10u   /**< may be mapped into an RPDO */
#define CO_OD_NODEID 0x20u /**< power-on value is the default plus the node-ID ($NODEID) */

/* The EDS AccessType values. rwr/rww only say which PDO direction suits the entry. */
#define CO_OD_RO CO_OD_READ
#define CO_OD_WO CO_OD_WRITE
#define CO_OD_RW (CO_OD_READ | CO_OD_WRITE)
#define CO_OD_RWR (CO_OD_READ | CO_OD_WRITE)
#define CO_OD_RWW (CO_OD_READ | CO_OD_WRITE)
#define CO_OD_CO (CO_OD_READ | CO_OD_CONST)

/** Returned as `total` by a read hook that does not know the size in advance. */
#define CO_OD_SIZE_UNKNOWN UINT32_MAX

/** A numeric limit; which member counts follows the entry's type (signed, unsigned, real). */
typedef union co_od_num {
    int64_t i;
    uint64_t u;
    double f;
} co_od_num_t;

/** Inclusive limits of a numeric entry: below low -> 0x06090032, above high -> 0x06090031. */
typedef struct co_od_limits {
    co_od_num_t low;
    co_od_num_t high;
} co_od_limits_t;

/** Storage of a DOMAIN entry that keeps its data in RAM. */
typedef struct co_od_domain {
    uint8_t *data;
    uint32_t len; /**< current length in bytes; capacity is the entry's `size` */
} co_od_domain_t;

typedef struct co_od_entry co_od_entry_t;

/**
 * Application hooks of one entry; any member may be NULL. `ctx` is co_od_t.hook_ctx.
 * Hooks returning co_abort_t return CO_ABORT_NONE to go on or an abort code to fail.
 */
typedef struct co_od_hooks {
    /** Produce the value instead of reading storage: copy up to `cap` bytes of the wire
     *  value from `offset` into `buf`, set `*n` to the bytes copied and `*total` to the
     *  whole size (or CO_OD_SIZE_UNKNOWN). Called once per piece. */
    co_abort_t (*read)(void *ctx, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                       uint32_t cap, uint32_t *n, uint32_t *total);
    /** Validate or veto a whole new value (wire bytes) before it is stored. */
    co_abort_t (*check)(void *ctx, const co_od_entry_t *entry, const uint8_t *data, uint32_t len);
    /** Take the value instead of storage, in pieces: `offset` of this piece, `total` the
     *  announced size or CO_OD_SIZE_UNKNOWN, `last` true on the final piece. */
    co_abort_t (*write)(void *ctx, const co_od_entry_t *entry, uint32_t offset, const uint8_t *data,
                        uint32_t n, uint32_t total, bool last);
    /** Told after a new value was stored. */
    void (*written)(void *ctx, const co_od_entry_t *entry);
} co_od_hooks_t;

#if !CO_CONFIG_OD_COMPACT
/** One (index, sub-index) of the dictionary. Tables are sorted by index, then sub-index.
 *  The general form (CO_CONFIG_OD_COMPACT 0): every entry carries its own pointers. */
struct co_od_entry {
    uint16_t index;
    uint8_t sub;
    uint8_t type;     /**< co_type_t */
    uint8_t attr;     /**< CO_OD_* attributes */
    uint32_t size;    /**< bytes on the wire; capacity for strings and domains */
    void *value;      /**< native storage, or NULL when hooks produce/take the value */
    const void *dflt; /**< power-on value (same form as value), or NULL: reset leaves it */
    const co_od_limits_t *limits; /**< numeric limits, or NULL */
    const co_od_hooks_t *hooks;   /**< application hooks, or NULL */
};
#else
/** One (index, sub-index) of the dictionary. Tables are sorted by index, then sub-index.
 *  The compact form (CO_CONFIG_OD_COMPACT 1, what a generated dictionary is made for): 6
 *  bytes, no pointer. The value lives `offset` bytes into co_od_t.values (one struct of
 *  every value; co_od_value); type, attributes and side table position are a row of
 *  co_od_t.rows that every entry alike shares (co_od_type, co_od_attr). The size follows
 *  from the type (co_type_size), except for strings and domains (CO_OD_VARIABLE_TYPES),
 *  whose capacity is in the side table co_od_tables_t.sizes. Power-on values are one image
 *  for the whole table (co_od_tables_t.defaults), limits a table of their own that only
 *  entries with limits refer to, and there are no hooks. */
struct co_od_entry {
    uint16_t index;
    uint16_t offset; /**< of the value in co_od_t.values */
    uint8_t sub;
    uint8_t row; /**< its type, attributes and side: co_od_t.rows[row] */
};

/** What entries of the compact form share: type, attributes, side table position. */
typedef struct co_od_row {
    uint8_t type; /**< co_type_t */
    uint8_t attr; /**< CO_OD_* attributes */
    /** 0, or 1 + a position in a side table (co_od_tables_t): a number's limits in
     *  `limits`; a string's or domain's capacity in `sizes` (never 0 for them). */
    uint8_t side;
    uint8_t unused; /**< 0 (4 bytes a row: one shift finds it) */
} co_od_row_t;
#endif

/** The types of variable length (strings, DOMAIN) as bits of a mask indexed by type code:
 *  the compact form keeps their capacity in co_od_tables_t.sizes. */
#define CO_OD_VARIABLE_TYPES                                                                       \
    ((1u << CO_TYPE_VISIBLE_STRING) | (1u << CO_TYPE_OCTET_STRING) |                               \
     (1u << CO_TYPE_UNICODE_STRING) | (1u << CO_TYPE_DOMAIN))

/** Whether a type code is one of CO_OD_VARIABLE_TYPES. */
static inline bool co_type_is_variable(unsigned type)
{
    return type < 32u && ((CO_OD_VARIABLE_TYPES >> type) & 1u) != 0;
}

/** The hooks of an entry, or NULL (a compact dictionary has none). */
static inline const co_od_hooks_t *co_od_hooks_of(const co_od_entry_t *entry)
{
#if CO_CONFIG_OD_COMPACT
    (void)entry;
    return NULL;
#else
    return entry->hooks;
#endif
}

/** Key of (index, sub) in co_od_t.keys. */
#define CO_OD_KEY(index, sub) (((uint32_t)(index) << 8) | (uint32_t)(sub))

/** Home slot of a key in a hash of mask + 1 slots (co_od_t.hash): bits 16.. of
 *  key * 0x9E3779B1 (Fibonacci hashing, modulo 2^32), as many as the mask has. */
#define CO_OD_HASH_HOME(key, mask) ((((uint32_t)(key)*0x9E3779B1u) >> 16) & (uint32_t)(mask))

/** An object dictionary: the entry table and the context its hooks receive. `keys` and
 *  `hash` make look-ups faster: the bisection walks the keys when given, and a core with
 *  CO_CONFIG_OD_HASH (canola/config.h: by default in the general form) looks up through
 *  the hash; a core without it neither reads nor checks the hash. */
typedef struct co_od {
    const co_od_entry_t *entries;
    uint32_t count;
    void *hook_ctx;
#if CO_CONFIG_OD_COMPACT
    /** The values of the compact form (co_od_entry_t.offset counts from here): one struct
     *  in RAM, the one a generator writes (canola.odgen's <name>_values). Not NULL (unless
     *  there are no entries): co_od_value never returns NULL in this form. */
    void *values;
    /** The rows the entries name (co_od_entry_t.row), rows_count of them. */
    const co_od_row_t *rows;
    /** Its const side tables (co_od_tables_t), or NULL: no power-on values but zeros, no
     *  limits, no strings or domains. */
    const struct co_od_tables *tables;
#else
    /** Optional (NULL: look-up searches the entries): keys[i] = CO_OD_KEY of entries[i].
     *  A dense array of 4 bytes per entry that the binary search walks instead of the
     *  28/48-byte entries: about a third of the instructions per look-up, and fewer cache
     *  lines. The generator (canola.odgen) emits it; co_od_validate checks it. */
    const uint32_t *keys;
#endif
    /** Optional (NULL: no hash; in the general form it needs `keys`, the compact form
     *  compares the entries' own index and sub-index): an open-addressing hash table of
     *  hash_mask + 1 slots, each 0 (empty) or 1 + the position of an entry. An entry sits in the
     * first slot that is free from its home (CO_OD_HASH_HOME) on, wrapping around; at least one
     *  slot is empty. With about twice as many slots as entries a look-up reads one or two
     *  slots instead of log2(count) keys: ~25 instructions instead of ~95 (x86-64, the
     *  172 entries of examples/example_od.c), for 2 bytes per slot. The generator (canola.odgen)
     * emits it; co_od_hash_build builds one at run time; co_od_validate checks it. */
    const uint16_t *hash;
    uint16_t hash_mask; /**< slots - 1: 2^bits - 1 with 1 <= bits <= 16 */
#if CO_CONFIG_OD_COMPACT
    uint16_t rows_count; /**< rows in `rows` (co_od_validate checks the entries' against it) */
#endif
} co_od_t;

#if CO_CONFIG_OD_COMPACT
/** The const tables of a compact dictionary (co_od_t.tables), apart from the entries. */
typedef struct co_od_tables {
    /** The power-on values, one record per entry whose power-on value is not all zeros, in
     *  entry order, ended by a 0 byte. A record: a head byte, then the entry's position if
     *  the head says so, the length if the head says so, then the value's bytes (trailing
     *  zero bytes may be left out): a number's native storage as little-endian bytes (an
     *  INTEGER24 as its int32_t, sign-extended), the wire bytes of the others. The head's
     *  bits 0-4: the entries skipped since the previous record's (since position 0 for the
     *  first), 0..30, or 31: the position follows (2 bytes, little-endian); bits 5-7: the
     *  value's length, 1..6, or 7: the length follows (2 bytes, little-endian). co_od_reset
     *  gives every entry in its range but a DOMAIN its record's bytes and zeros after them
     *  (a little-endian host copies them as they are; a big-endian one converts numbers,
     *  so the image does not depend on the target's byte order). NULL: every value resets
     *  to zero. */
    const uint8_t *defaults;
    /** The limits that numbers refer to (co_od_entry_t.side: 1 + position), or NULL. */
    const co_od_limits_t *limits;
    /** The capacities that strings and domains refer to (co_od_entry_t.side: 1 +
     *  position), or NULL. */
    const uint32_t *sizes;
    uint8_t limits_count; /**< limits in `limits` */
    uint8_t sizes_count;  /**< capacities in `sizes` */
} co_od_tables_t;
#endif

/** The type (co_type_t) of an entry: its own in the general form, its row's in the
 *  compact form. O(1). */
static inline unsigned co_od_type(const co_od_t *od, const co_od_entry_t *entry)
{
#if CO_CONFIG_OD_COMPACT
    return od->rows[entry->row].type;
#else
    (void)od;
    return entry->type;
#endif
}

/** The attributes (CO_OD_*) of an entry, as co_od_type. O(1). */
static inline unsigned co_od_attr(const co_od_t *od, const co_od_entry_t *entry)
{
#if CO_CONFIG_OD_COMPACT
    return od->rows[entry->row].attr;
#else
    (void)od;
    return entry->attr;
#endif
}

/** The side table position of a compact entry (co_od_row_t.side; 0 in the general form). */
static inline unsigned co_od_side(const co_od_t *od, const co_od_entry_t *entry)
{
#if CO_CONFIG_OD_COMPACT
    return od->rows[entry->row].side;
#else
    (void)od;
    (void)entry;
    return 0;
#endif
}

/** Whether an entry has limits. */
static inline bool co_od_has_limits(const co_od_t *od, const co_od_entry_t *entry)
{
#if CO_CONFIG_OD_COMPACT
    return co_od_side(od, entry) != 0 && !co_type_is_variable(co_od_type(od, entry));
#else
    (void)od;
    return entry->limits != NULL;
#endif
}

/** The native storage of an entry (NULL in the general form when hooks produce and take
 *  the value; never in the compact form, which has no hooks). O(1). */
static inline void *co_od_value(const co_od_t *od, const co_od_entry_t *entry)
{
#if CO_CONFIG_OD_COMPACT
    void *value = (uint8_t *)od->values + entry->offset;
#if defined(__GNUC__) || defined(__clang__)
    if (value == NULL) {
        __builtin_unreachable(); /* the callers' tests for NULL fold away */
    }
#endif
    return value;
#else
    (void)od;
    return entry->value;
#endif
}

#if CO_CONFIG_OD_COMPACT
/** Bytes of an entry's value on the wire; capacity for strings and domains. O(1). */
uint32_t co_od_size(const co_od_t *od, const co_od_entry_t *entry);
#else
static inline uint32_t co_od_size(const co_od_t *od, const co_od_entry_t *entry)
{
    (void)od;
    return entry->size;
}
#endif

/** Check the table: sorted and unique, sizes fitting their types, storage where no hook
 *  replaces it, keys (when given) equal to the entries', the hash (when given) finding
 *  every entry with an empty slot left (keys and hash not in a core built for size, which
 *  does not use them: see co_od_t); in the compact form also every side table position
 *  within co_od_tables_t (a capacity for each string and domain, limits only for numbers)
 *  and the power-on values' records in entry order, each fitting its entry.
 *  Returns CO_OK or CO_ERR_CONFIG (with `*bad` set to the offending entry's position, or
 *  to `count` for a bad hash or a record past the table, when `bad` is not NULL). O(n)
 *  plus O(slots). A core built without validation (CO_CONFIG_OD_VALIDATE 0, canola/config.h)
 *  checks none of this: CO_OK for any dictionary given (CO_ERR_ARG for NULL). */
co_err_t co_od_validate(const co_od_t *od, uint32_t *bad);

/** Bits of hash for `count` entries: the smallest with 2^bits >= 2 * count (at least 1),
 *  or 0 when `count` is too large for a hash (more than 32767 entries). */
uint8_t co_od_hash_bits(uint32_t count);

/** Build the hash of `od` (whose entries and keys are final) into `slots`, 2^bits of them
 *  (bits as co_od_hash_bits gives, or more), and attach it: od->hash = slots,
 *  od->hash_mask = 2^bits - 1. Returns CO_ERR_ARG (and leaves `od` as it was) when `od`
 *  has no keys or 2^bits slots cannot hold its entries with one left empty. O(count)
 *  expected. */
co_err_t co_od_hash_build(co_od_t *od, uint16_t *slots, uint8_t bits);

/** Find an entry. On failure returns NULL and sets `*abort` (when not NULL) to
 *  CO_ABORT_NO_OBJECT (index unknown) or CO_ABORT_NO_SUB (index known, sub-index not).
 *  With a hash O(1) expected (a miss that asks for the abort code also searches), else
 *  O(log n). */
const co_od_entry_t *co_od_find(const co_od_t *od, uint16_t index, uint8_t sub, co_abort_t *abort);

/** Size of a type's value on the wire, or 0 for types of variable length. */
uint32_t co_type_size(co_type_t type);

/** Current length of an entry's value on the wire (strings: up to the terminator;
 *  domains: their length; hook-read entries: `size`). */
uint32_t co_od_value_len(const co_od_t *od, const co_od_entry_t *entry);

/** Network access rule: CO_ABORT_WRITE_ONLY / CO_ABORT_READ_ONLY when the entry may not be
 *  read / written from the network, else CO_ABORT_NONE. */
co_abort_t co_od_access(const co_od_t *od, const co_od_entry_t *entry, bool write);

/** Read a piece of the wire value: up to `cap` bytes from `offset` into `buf`; `*n` gets
 *  the bytes copied, `*total` (may be NULL) the whole length. Access rights are not checked
 *  (see co_od_access). Returns an abort code. */
co_abort_t co_od_read(const co_od_t *od, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                      uint32_t cap, uint32_t *n, uint32_t *total);

/** The wire bytes of an entry whose storage already holds its wire form (strings, domains,
 *  TIME_OF_DAY/TIME_DIFFERENCE, and on little-endian hosts every number: its wire bytes are
 *  the first bytes of its storage), with `*len` set to the current length; NULL for entries
 *  read through a hook, and for numbers on big-endian hosts (converted on read). Lets a reader copy
 * pieces without co_od_read's checks. O(1), except VISIBLE/UNICODE_STRING: O(length) to find the
 * terminator. */
const uint8_t *co_od_wire_data(const co_od_t *od, const co_od_entry_t *entry, uint32_t *len);

/** Check a whole new wire value without storing it: length against the type (0x06070012
 *  too long / 0x06070013 too short), BOOLEAN 0/1 (0x06090030), limits (0x06090031/32),
 *  then the entry's check hook. Access rights are not checked. */
co_abort_t co_od_check(const co_od_t *od, const co_od_entry_t *entry, const uint8_t *data,
                       uint32_t len);

/** Store a whole wire value that co_od_check() accepted (or hand it to the write hook).
 *  Does not call the written hook. */
co_abort_t co_od_store(const co_od_t *od, const co_od_entry_t *entry, const uint8_t *data,
                       uint32_t len);

/** co_od_check + co_od_store + written hook: a complete local write. */
co_abort_t co_od_write(const co_od_t *od, const co_od_entry_t *entry, const uint8_t *data,
                       uint32_t len);

/** Hand one piece of a streamed value to the entry's write hook (CO_ABORT_UNSUPPORTED
 *  when it has none). The written hook runs after the last piece. */
co_abort_t co_od_write_piece(const co_od_t *od, const co_od_entry_t *entry, uint32_t offset,
                             const uint8_t *data, uint32_t n, uint32_t total, bool last);

/** Copy power-on values into every entry with index in [first, last] that has a default
 *  (adding `node_id` to CO_OD_NODEID entries). Entries without a default keep their value.
 *  O(entries in range). The compact form: every entry in the range but a DOMAIN gets its
 *  record of co_od_tables_t.defaults, if any, and zeros after it (O(entries in range +
 *  records before the range's end)); the records are trusted as they are (co_od_validate
 *  checks them, as the general form's power-on values are trusted to match their entries). */
void co_od_reset(const co_od_t *od, uint16_t first, uint16_t last, uint8_t node_id);

/* ---- Native access for the application and the services (no access rules, no hooks,
 * no limits: the caller owns the values). Return CO_ERR_NOT_FOUND when the entry is
 * missing, CO_ERR_ARG when its type does not have that width. */
co_err_t co_od_get_uint(const co_od_t *od, uint16_t index, uint8_t sub, uint64_t *value);
co_err_t co_od_set_uint(const co_od_t *od, uint16_t index, uint8_t sub, uint64_t value);

/** Native unsigned value of a numeric entry's storage (signed types sign-extended to 64
 *  bits and returned as their two's-complement bit pattern). */
uint64_t co_od_entry_uint(const co_od_t *od, const co_od_entry_t *entry);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_OD_H */
