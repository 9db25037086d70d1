/* SPDX-License-Identifier: Apache-2.0 */
/*
 * od.c -- the object dictionary: look-up, wire conversion, checks, hooks, reset.
 *
 * Values live in native form; everything that crosses this API is wire form
 * (little-endian). Numbers always pass through a bit pattern (bits_t: 64 bits, or 32
 * without the types wider than 32 bits, CO_CONFIG_OD_64BIT 0):
 * native storage <-> bits_t <-> wire bytes, built with shifts, so the code never
 * depends on the host's byte order.
 */
#include "canola/od.h"

#include "canola/config.h"

#include <string.h>

#include "build.h"
#include "od_plain.h" /* co_copy_number */

/* REAL32/REAL64 are copied bit for bit through uint32_t/uint64_t. */
_Static_assert(sizeof(float) == 4, "REAL32 needs a 4-byte float");
_Static_assert(sizeof(double) == 8, "REAL64 needs an 8-byte double");

/* How a type's value is stored and checked. K_NONE: an unknown type code (validate rejects
 * it; otherwise handled as raw bytes). K_RAW: TIME_OF_DAY and TIME_DIFFERENCE, 6 bytes kept in
 * wire order. */
enum kind {
    K_NONE,
    K_BOOL,
    K_SIGNED,
    K_UNSIGNED,
    K_REAL,
    K_RAW,
    K_VSTRING,
    K_OSTRING,
    K_USTRING,
    K_DOMAIN
};

typedef struct type_info {
    uint8_t wire;  /* bytes on the wire; 0 = variable length */
    uint8_t width; /* bytes of native storage (fixed types only) */
    uint8_t kind;  /* enum kind */
} type_info_t;

/* Indexed by type code; the gaps (0x00, 0x0E, 0x17) are zero: K_NONE. */
static const type_info_t k_types[] = {
    [CO_TYPE_BOOLEAN] = {1, 1, K_BOOL},
    [CO_TYPE_INTEGER8] = {1, 1, K_SIGNED},
    [CO_TYPE_INTEGER16] = {2, 2, K_SIGNED},
    [CO_TYPE_INTEGER32] = {4, 4, K_SIGNED},
    [CO_TYPE_UNSIGNED8] = {1, 1, K_UNSIGNED},
    [CO_TYPE_UNSIGNED16] = {2, 2, K_UNSIGNED},
    [CO_TYPE_UNSIGNED32] = {4, 4, K_UNSIGNED},
    [CO_TYPE_REAL32] = {4, 4, K_REAL},
    [CO_TYPE_VISIBLE_STRING] = {0, 0, K_VSTRING},
    [CO_TYPE_OCTET_STRING] = {0, 0, K_OSTRING},
#if CO_CONFIG_OD_UNICODE /* without it: an unknown type, refused by co_od_validate */
    [CO_TYPE_UNICODE_STRING] = {0, 0, K_USTRING},
#endif
    [CO_TYPE_TIME_OF_DAY] = {6, 6, K_RAW},
    [CO_TYPE_TIME_DIFFERENCE] = {6, 6, K_RAW},
    [CO_TYPE_DOMAIN] = {0, 0, K_DOMAIN},
    [CO_TYPE_INTEGER24] = {3, 4, K_SIGNED},
    [CO_TYPE_UNSIGNED24] = {3, 4, K_UNSIGNED},
#if CO_CONFIG_OD_64BIT /* without them: unknown types, refused by co_od_validate */
    [CO_TYPE_REAL64] = {8, 8, K_REAL},
    [CO_TYPE_INTEGER40] = {5, 8, K_SIGNED},
    [CO_TYPE_INTEGER48] = {6, 8, K_SIGNED},
    [CO_TYPE_INTEGER56] = {7, 8, K_SIGNED},
    [CO_TYPE_INTEGER64] = {8, 8, K_SIGNED},
    [CO_TYPE_UNSIGNED40] = {5, 8, K_UNSIGNED},
    [CO_TYPE_UNSIGNED48] = {6, 8, K_UNSIGNED},
    [CO_TYPE_UNSIGNED56] = {7, 8, K_UNSIGNED},
    [CO_TYPE_UNSIGNED64] = {8, 8, K_UNSIGNED},
#endif
};

static const type_info_t k_unknown = {0, 0, K_NONE};

static CO_SIZE_NOINLINE const type_info_t *type_info(unsigned type)
{
    return type < sizeof k_types / sizeof k_types[0] ? &k_types[type] : &k_unknown;
}

/* The type information of an entry. */
static CO_SIZE_NOINLINE const type_info_t *entry_info(const co_od_t *od, const co_od_entry_t *e)
{
    return type_info(co_od_type(od, e));
}

static bool is_number(const type_info_t *t) { return t->kind >= K_BOOL && t->kind <= K_REAL; }

/* A DOMAIN kept in RAM (a co_od_domain_t), a UNICODE_STRING: each a switch (config.h). */
static bool is_domain(const type_info_t *t) { return CO_CONFIG_OD_DOMAIN && t->kind == K_DOMAIN; }
static bool is_ustring(const type_info_t *t)
{
    return CO_CONFIG_OD_UNICODE && t->kind == K_USTRING;
}

static bool is_integer(const type_info_t *t)
{
    return t->kind == K_SIGNED || t->kind == K_UNSIGNED;
}

static uint32_t key_of(uint16_t index, uint8_t sub) { return ((uint32_t)index << 8) | sub; }

static uint32_t entry_key(const co_od_entry_t *e) { return key_of(e->index, e->sub); }

static uint32_t min_u32(uint32_t a, uint32_t b) { return a < b ? a : b; }

/* On a little-endian host a number whose storage is as wide as its wire form (8, 16, 32,
 * 64 bits, REAL32/64) already is its wire form: reads and writes copy it as it is. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define LITTLE_ENDIAN_HOST 1
static bool wire_is_native(const type_info_t *t)
{
    return t->wire == t->width && t->kind >= K_SIGNED && t->kind <= K_REAL;
}
#else
#define LITTLE_ENDIAN_HOST 0
static bool wire_is_native(const type_info_t *t)
{
    (void)t;
    return false;
}
#endif

static bool has_read_hook(const co_od_entry_t *e)
{
    const co_od_hooks_t *h = co_od_hooks_of(e);
    return h && h->read;
}

static bool has_write_hook(const co_od_entry_t *e)
{
    const co_od_hooks_t *h = co_od_hooks_of(e);
    return h && h->write;
}

/* Whether an entry of type `t` has limits (co_od_has_limits, its type at hand). */
static bool has_limits(const co_od_t *od, const co_od_entry_t *e, const type_info_t *t)
{
#if CO_CONFIG_OD_COMPACT /* a side of a number: its limits (of a string: its capacity) */
    return co_od_side(od, e) != 0 && t->wire != 0;
#else
    (void)od;
    (void)t;
    return e->limits != NULL;
#endif
}

/* The limits of an entry, or NULL (none, or left out of the build). */
static const co_od_limits_t *limits_of(const co_od_t *od, const co_od_entry_t *e,
                                       const type_info_t *t)
{
    if (!CO_CONFIG_OD_LIMITS || !has_limits(od, e, t)) {
        return NULL;
    }
#if CO_CONFIG_OD_COMPACT
    return &od->tables->limits[co_od_side(od, e) - 1u];
#else
    (void)od;
    return e->limits;
#endif
}

/* ---- Bit patterns. */

/* The widest number the build stores: 64 bits, or 32 (no 64-bit arithmetic at all). */
#if CO_CONFIG_OD_64BIT
typedef uint64_t bits_t;
#else
typedef uint32_t bits_t;
#endif
#define BITS_WIDTH (8u * (unsigned)sizeof(bits_t))

/* Sign-extend the low `nbits` bits of `bits` to the pattern's width (unsigned arithmetic
 * only). */
static CO_SIZE_NOINLINE bits_t sign_extend(bits_t bits, unsigned nbits)
{
    if (nbits == 0 || nbits >= BITS_WIDTH) {
        return bits; /* no bits, or nothing to extend */
    }
    bits_t sign = (bits_t)1 << (nbits - 1u);
    bits &= (bits_t)((sign << 1) - 1u);
    return (bits_t)((bits ^ sign) - sign);
}

/* Two's-complement pattern to int64_t without an implementation-defined conversion. */
static int64_t to_signed(bits_t bits)
{
    if (bits <= (bits_t) ~(bits_t)0 / 2u) {
        return (int64_t)bits;
    }
    return -(int64_t)(bits_t)~bits - 1;
}

/* A number's wire bytes as a bit pattern, signed types sign-extended from the wire width. */
static bits_t wire_number(const type_info_t *t, const uint8_t *data)
{
    bits_t bits = 0;
    for (unsigned n = t->wire; n-- > 0u;) {
        bits = (bits_t)(bits << 8) | data[n];
    }
    return t->kind == K_SIGNED ? sign_extend(bits, 8u * t->wire) : bits;
}

/* Storage read and written as the unsigned integer of its width. That may alias the
 * signed integers and BOOLEAN, but not a REAL32/REAL64: GCC and clang have a type
 * attribute that allows it; other compilers copy reals with memcpy. */
#if defined(__GNUC__) || defined(__clang__)
#define REALS_ALIASED 1
typedef uint16_t __attribute__((may_alias)) any_u16;
typedef uint32_t __attribute__((may_alias)) any_u32;
typedef uint64_t __attribute__((may_alias)) any_u64;
#else
#define REALS_ALIASED 0
typedef uint16_t any_u16;
typedef uint32_t any_u32;
typedef uint64_t any_u64;
#endif

/* Native storage of a number as a bit pattern (signed types sign-extended; reals bit for
 * bit). */
static bits_t native_get(const void *value, const type_info_t *t)
{
    bits_t bits;
    if (!REALS_ALIASED && t->kind == K_REAL) {
        uint32_t b32;
#if CO_CONFIG_OD_64BIT
        if (t->width == 8) {
            memcpy(&bits, value, sizeof bits);
            return bits;
        }
#endif
        memcpy(&b32, value, sizeof b32);
        return b32;
    }
    switch (t->width) {
    case 1:
        bits = *(const uint8_t *)value;
        break;
    case 2:
        bits = *(const any_u16 *)value;
        break;
#if CO_CONFIG_OD_64BIT
    case 8:
        bits = *(const any_u64 *)value;
        break;
#endif
    default:
        bits = *(const any_u32 *)value;
        break;
    }
    return t->kind == K_SIGNED ? sign_extend(bits, 8u * t->width) : bits;
}

/* Store a bit pattern truncated to the storage width (exact-width signed types are two's
 * complement, so an unsigned copy of the same width holds the same value). */
static void native_set(void *value, const type_info_t *t, bits_t bits)
{
    if (t->kind == K_BOOL) {
        bits = bits != 0u;
    }
    if (!REALS_ALIASED && t->kind == K_REAL) {
        uint32_t b32 = (uint32_t)bits;
#if CO_CONFIG_OD_64BIT
        if (t->width == 8) {
            memcpy(value, &bits, sizeof bits);
            return;
        }
#endif
        memcpy(value, &b32, sizeof b32);
        return;
    }
    switch (t->width) {
    case 1:
        *(uint8_t *)value = (uint8_t)bits;
        break;
    case 2:
        *(any_u16 *)value = (uint16_t)bits;
        break;
#if CO_CONFIG_OD_64BIT
    case 8:
        *(any_u64 *)value = bits;
        break;
#endif
    default:
        *(any_u32 *)value = (uint32_t)bits;
        break;
    }
}

/* A pattern as the API's 64 bits: signed types sign-extended (already so when the
 * pattern is 64 bits wide). */
static uint64_t widen(const type_info_t *t, bits_t bits)
{
#if CO_CONFIG_OD_64BIT
    (void)t;
    return bits;
#else
    return t->kind == K_SIGNED ? (uint64_t)to_signed(bits) : (uint64_t)bits;
#endif
}

/* ---- Table checks and look-up. */

static bool storage_ok(const co_od_t *od, const co_od_entry_t *e, const type_info_t *t)
{
    const void *value = co_od_value(od, e);
    if (value != NULL) {
        /* a DOMAIN kept in RAM (CO_CONFIG_OD_DOMAIN) needs its buffer */
        if (t->kind == K_DOMAIN) {
            return CO_CONFIG_OD_DOMAIN && ((const co_od_domain_t *)value)->data != NULL;
        }
        return true;
    }
    bool rd = has_read_hook(e);
    bool wr = has_write_hook(e);
    if (((co_od_attr(od, e) & CO_OD_READ) && !rd) || ((co_od_attr(od, e) & CO_OD_WRITE) && !wr)) {
        return false;
    }
    return rd || wr; /* an entry with neither storage nor hooks holds nothing */
}

#if CO_CONFIG_OD_COMPACT
/* co_od_entry_t.side names a position its type's side table has: a capacity for each
 * string and domain (the types of no fixed size), limits or none for a number, none for
 * the others. */
static bool side_ok(const co_od_t *od, const co_od_entry_t *e, const type_info_t *t)
{
    const co_od_tables_t *tab = od->tables;
    if (co_od_side(od, e) == 0) {
        return t->wire != 0;
    }
    if (tab == NULL) {
        return false;
    }
    if (t->wire == 0) {
        return tab->sizes != NULL && co_od_side(od, e) <= tab->sizes_count &&
               tab->sizes[co_od_side(od, e) - 1u] != 0;
    }
    return is_number(t) && tab->limits != NULL && co_od_side(od, e) <= tab->limits_count;
}
#endif

static bool entry_ok(const co_od_t *od, const co_od_entry_t *e)
{
#if CO_CONFIG_OD_COMPACT
    if (od->rows == NULL || e->row >= od->rows_count) {
        return false; /* its type and attributes are nowhere */
    }
#endif
    const type_info_t *t = entry_info(od, e);
    if (t->kind == K_NONE) {
        return false;
    }
#if CO_CONFIG_OD_COMPACT /* the size follows from the type or the side table */
    if (od->values == NULL || !side_ok(od, e, t)) {
        return false; /* refers to a limit or capacity the tables do not have */
    }
#else
    if (t->wire != 0 ? e->size != t->wire : e->size == 0) {
        return false;
    }
#endif
    if (is_ustring(t) && (co_od_size(od, e) & 1u) != 0) {
        return false; /* whole 16-bit code units only */
    }
    if (!CO_CONFIG_OD_LIMITS && has_limits(od, e, t)) {
        return false; /* limits are left out of this build */
    }
    if (!CO_CONFIG_REAL_LIMITS && t->kind == K_REAL && has_limits(od, e, t)) {
        return false; /* REAL limits are left out of this build */
    }
    return storage_ok(od, e, t);
}

/* Entry i is well formed and comes strictly after entry i - 1. */
static bool entry_fits(const co_od_t *od, uint32_t i)
{
    const co_od_entry_t *entries = od->entries;
    bool sorted = i == 0 || entry_key(&entries[i]) > entry_key(&entries[i - 1u]);
#if !CO_CONFIG_OD_COMPACT
    if (od->keys != NULL && od->keys[i] != entry_key(&entries[i])) {
        return false;
    }
#endif
    return sorted && entry_ok(od, &entries[i]);
}

/* The key of entry i: from the dense key array of the general form, or the entry itself
 * in the compact form (which has none). */
static uint32_t key_at(const co_od_t *od, uint32_t i)
{
#if CO_CONFIG_OD_COMPACT
    return entry_key(&od->entries[i]);
#else
    return od->keys[i];
#endif
}

/* The general form's hash needs the dense keys (the compact form's compares entries). */
static bool key_at_missing(const co_od_t *od)
{
#if CO_CONFIG_OD_COMPACT
    (void)od;
    return false;
#else
    return od->keys == NULL;
#endif
}

/* The hash slot that holds `key` (a validated hash: keys exist, a slot is empty, slots
 * point into the table), or the empty slot where its probe ends. */
static uint32_t hash_probe(const co_od_t *od, uint32_t key)
{
    uint32_t mask = od->hash_mask;
    uint32_t slot = CO_OD_HASH_HOME(key, mask);
    for (uint32_t at; (at = od->hash[slot]) != 0 && key_at(od, at - 1u) != key;) {
        slot = (slot + 1u) & mask;
    }
    return slot;
}

/* The hash (when given) leads every key to its own entry and cannot loop (checked after
 * the entries, whose keys it compares). */
static bool hash_fits(const co_od_t *od)
{
    if (od->hash == NULL) {
        return true;
    }
    uint32_t slots = (uint32_t)od->hash_mask + 1u;
    if (key_at_missing(od)) {
        return false; /* the general form's hash compares the dense keys */
    }
    if ((slots & (slots - 1u)) != 0 || slots < 2u) {
        return false; /* the mask must be 2^bits - 1, bits >= 1 */
    }
    uint32_t empty = 0;
    for (uint32_t i = 0; i < slots; i++) {
        empty += od->hash[i] == 0 ? 1u : 0u;
        if (od->hash[i] > od->count) {
            return false;
        }
    }
    if (empty == 0) {
        return false; /* a missing key would probe forever */
    }
    for (uint32_t i = 0; i < od->count; i++) {
        if (od->hash[hash_probe(od, key_at(od, i))] != i + 1u) {
            return false;
        }
    }
    return true;
}

#if CO_CONFIG_OD_COMPACT
static bool image_fits(const co_od_t *od, uint32_t *bad);
#endif

co_err_t co_od_validate(const co_od_t *od, uint32_t *bad)
{
    if (od == NULL) {
        return CO_ERR_ARG;
    }
    if (!CO_CONFIG_OD_VALIDATE) {
        return CO_OK; /* the table is trusted (canola/config.h) */
    }
    uint32_t i = 0;
    while (od->entries != NULL && i < od->count && entry_fits(od, i)) {
        i++;
    }
    /* A core without CO_CONFIG_OD_HASH does not read the hash: it does not check it either. */
    if (i == od->count && (!CO_CONFIG_OD_HASH || hash_fits(od))) {
#if CO_CONFIG_OD_COMPACT
        if (!image_fits(od, &i)) { /* the power-on values (i: the entry they do not fit) */
            if (bad != NULL) {
                *bad = i;
            }
            return CO_ERR_CONFIG;
        }
#endif
        return CO_OK;
    }
    if (bad != NULL) {
        *bad = i; /* count: the entries are fine, the hash is not */
    }
    return CO_ERR_CONFIG;
}

/* Position of the first entry whose key is >= key (count when there is none): a bisection
 * over the general form's dense keys when given, else over the entries themselves. */
static uint32_t lower_bound(const co_od_t *od, uint32_t key)
{
    uint32_t lo = 0;
    uint32_t hi = od->count;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2u;
#if !CO_CONFIG_OD_COMPACT
        uint32_t at = od->keys != NULL ? od->keys[mid] : entry_key(&od->entries[mid]);
#else
        uint32_t at = entry_key(&od->entries[mid]);
#endif
        if (at < key) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

/* co_od_find by binary search (out of line: the hashed look-up stays a leaf). */
static CO_FAST_NOINLINE const co_od_entry_t *find_sorted(const co_od_t *od, uint32_t key,
                                                         co_abort_t *abort)
{
    uint16_t index = (uint16_t)(key >> 8);
    uint32_t pos = lower_bound(od, key);
    const co_od_entry_t *e = od->entries;
    if (pos < od->count && entry_key(&e[pos]) == key) {
        return &e[pos];
    }
    if (abort != NULL) {
        /* entries of the same index, if any, sit right before or at pos */
        bool known =
            (pos < od->count && e[pos].index == index) || (pos > 0 && e[pos - 1u].index == index);
        *abort = known ? CO_ABORT_NO_SUB : CO_ABORT_NO_OBJECT;
    }
    return NULL;
}

const co_od_entry_t *co_od_find(const co_od_t *od, uint16_t index, uint8_t sub, co_abort_t *abort)
{
    uint32_t key = key_of(index, sub);
    if (CO_CONFIG_OD_HASH && od->hash != NULL) {
        uint32_t at = od->hash[hash_probe(od, key)];
        if (at != 0) {
            return &od->entries[at - 1u];
        }
        if (abort == NULL) {
            return NULL; /* a miss: the search only tells which abort code */
        }
    }
    return find_sorted(od, key, abort);
}

uint32_t co_type_size(co_type_t type) { return type_info((unsigned)type)->wire; }

/* ---- Reading. */

/* Bytes of a string before its first zero code unit: a zero byte (`unit` 1), or two zero
 * bytes (a UNICODE_STRING's 16-bit unit, `unit` 2: zero in either byte order). */
static uint32_t string_len(const uint8_t *s, uint32_t cap, uint32_t unit)
{
    uint32_t n = 0;
    while (n + unit <= cap && (s[n] | s[n + unit - 1u]) != 0) {
        n += unit;
    }
    return n;
}

#if CO_CONFIG_OD_COMPACT
uint32_t co_od_size(const co_od_t *od, const co_od_entry_t *entry)
{
    uint32_t wire = entry_info(od, entry)->wire;
    return wire == 0 && co_od_side(od, entry) != 0 ? od->tables->sizes[co_od_side(od, entry) - 1u]
                                                   : wire;
}
#endif

uint32_t co_od_value_len(const co_od_t *od, const co_od_entry_t *entry)
{
    const uint8_t *value = co_od_value(od, entry);
    uint32_t size = co_od_size(od, entry);
    if (value == NULL) {
        return size;
    }
    const type_info_t *t = entry_info(od, entry);
    if (t->kind == K_VSTRING || is_ustring(t)) {
        return string_len(value, size, is_ustring(t) ? 2u : 1u);
    }
    if (is_domain(t)) {
        return min_u32(((const co_od_domain_t *)(const void *)value)->len, size);
    }
    return size;
}

co_abort_t co_od_access(const co_od_t *od, const co_od_entry_t *entry, bool write)
{
    if (!write) {
        return (co_od_attr(od, entry) & CO_OD_READ) ? CO_ABORT_NONE : CO_ABORT_WRITE_ONLY;
    }
    bool writable = (co_od_attr(od, entry) & CO_OD_WRITE) && !(co_od_attr(od, entry) & CO_OD_CONST);
    return writable ? CO_ABORT_NONE : CO_ABORT_READ_ONLY;
}

/* The wire bytes of a value in storage (`*len` of them, its current length), read where
 * they are: on a little-endian host the wire bytes of every number are the first bytes of
 * its storage (an INTEGER24 is the low three bytes of its int32_t). A big-endian host
 * encodes numbers into tmp (when given; NULL without). */
static const uint8_t *stored_wire(const co_od_t *od, const co_od_entry_t *e, uint8_t *tmp,
                                  uint32_t *len)
{
    const type_info_t *t = entry_info(od, e);
    const void *value = co_od_value(od, e);
    *len = co_od_value_len(od, e);
#if !LITTLE_ENDIAN_HOST
    if (is_number(t)) {
        if (tmp != NULL) {
            bits_t bits = native_get(value, t);
            for (unsigned i = 0; i < t->wire; i++) {
                tmp[i] = (uint8_t)(bits >> (8u * i));
            }
        }
        return tmp;
    }
#else
    (void)tmp;
#endif
    return is_domain(t) ? ((const co_od_domain_t *)value)->data : value;
}

const uint8_t *co_od_wire_data(const co_od_t *od, const co_od_entry_t *entry, uint32_t *len)
{
    if (has_read_hook(entry) || co_od_value(od, entry) == NULL) {
        return NULL;
    }
    return stored_wire(od, entry, NULL, len);
}

co_abort_t co_od_read(const co_od_t *od, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                      uint32_t cap, uint32_t *n, uint32_t *total)
{
    uint32_t whole = CO_OD_SIZE_UNKNOWN;
    *n = 0;
    if (has_read_hook(entry)) {
        /* the hook always gets a place for the total, even when the caller has none */
        co_abort_t abort =
            co_od_hooks_of(entry)->read(od->hook_ctx, entry, offset, buf, cap, n, &whole);
        if (total != NULL) {
            *total = whole;
        }
        return abort;
    }
    const void *value = co_od_value(od, entry);
    if (value == NULL) {
        return CO_ABORT_WRITE_ONLY;
    }
    /* a whole number's storage is its wire form (co_native_size: 0 where it is not) */
    whole = co_native_size(co_od_type(od, entry));
    uint8_t tmp[8];
    const uint8_t *wire = whole != 0 ? value : stored_wire(od, entry, tmp, &whole);
    if (total != NULL) {
        *total = whole;
    }
    if (offset > whole) {
        return CO_ABORT_GENERAL;
    }
    uint32_t count = min_u32(cap, whole - offset);
    co_copy(buf, wire + offset, count);
    *n = count;
    return CO_ABORT_NONE;
}

/* ---- Writing. */

/* Fixed types need exactly their wire size (validate makes it the entry's size);
 * variable ones at most the capacity. */
static co_abort_t check_len(const co_od_t *od, const co_od_entry_t *e, const type_info_t *t,
                            uint32_t len)
{
    uint32_t want = t->wire;
    if (want != 0) {
        return len > want ? CO_ABORT_LEN_HIGH : len < want ? CO_ABORT_LEN_LOW : CO_ABORT_NONE;
    }
    if (len > co_od_size(od, e)) {
        return CO_ABORT_LEN_HIGH;
    }
    return (is_ustring(t) && (len & 1u) != 0) ? CO_ABORT_TYPE_MISMATCH : CO_ABORT_NONE;
}

#if CO_CONFIG_REAL_LIMITS
/* A REAL32/REAL64 bit pattern as double (float and integer byte orders assumed equal). */
static double real_value(const type_info_t *t, bits_t bits)
{
    if (t->wire == 4) {
        uint32_t b = (uint32_t)bits;
        float f;
        memcpy(&f, &b, sizeof f);
        return (double)f;
    }
#if CO_CONFIG_OD_64BIT
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
#else
    return 0.0; /* no REAL64 in this build */
#endif
}
#endif

static co_abort_t check_limits(const co_od_limits_t *lim, const type_info_t *t, bits_t bits)
{
    bool low;
    bool high;
    if (t->kind == K_SIGNED) {
        int64_t v = to_signed(bits);
        low = v < lim->low.i;
        high = v > lim->high.i;
#if CO_CONFIG_REAL_LIMITS
    } else if (t->kind == K_REAL) {
        double v = real_value(t, bits);
        if (v != v) {
            return CO_ABORT_VALUE; /* NaN lies within no range */
        }
        low = v < lim->low.f;
        high = v > lim->high.f;
#endif
    } else {
        low = bits < lim->low.u;
        high = bits > lim->high.u;
    }
    return low ? CO_ABORT_VALUE_LOW : high ? CO_ABORT_VALUE_HIGH : CO_ABORT_NONE;
}

co_abort_t co_od_check(const co_od_t *od, const co_od_entry_t *entry, const uint8_t *data,
                       uint32_t len)
{
    const type_info_t *t = entry_info(od, entry);
    co_abort_t abort = check_len(od, entry, t, len);
    /* a number with limits, or a BOOLEAN (0 or 1), is decoded; others need not be */
    const co_od_limits_t *limits = limits_of(od, entry, t);
    if (abort == CO_ABORT_NONE && is_number(t) && (limits || t->kind == K_BOOL)) {
        bits_t bits = wire_number(t, data);
        if (t->kind == K_BOOL && bits > 1u) {
            abort = CO_ABORT_VALUE;
        } else if (limits) {
            abort = check_limits(limits, t, bits);
        }
    }
    const co_od_hooks_t *hooks = co_od_hooks_of(entry);
    if (abort == CO_ABORT_NONE && hooks && hooks->check) {
        abort = hooks->check(od->hook_ctx, entry, data, len);
    }
    return abort;
}

co_abort_t co_od_store(const co_od_t *od, const co_od_entry_t *entry, const uint8_t *data,
                       uint32_t len)
{
    uint8_t *value = co_od_value(od, entry);
    if (value == NULL) {
        if (has_write_hook(entry)) {
            return co_od_hooks_of(entry)->write(od->hook_ctx, entry, 0, data, len, len, true);
        }
        return CO_ABORT_UNSUPPORTED;
    }
    uint32_t native = co_native_size(co_od_type(od, entry));
    if (native != 0 && len == native) { /* a whole number, stored as it travels */
        co_copy_number(value, data, len);
        return CO_ABORT_NONE;
    }
    const type_info_t *t = entry_info(od, entry);
    co_abort_t abort = check_len(od, entry, t, len); /* never overrun the storage */
    if (abort != CO_ABORT_NONE) {
        return abort;
    }
    if (is_number(t) && !wire_is_native(t)) {
        native_set(value, t, wire_number(t, data));
    } else if (is_domain(t)) {
        co_od_domain_t *d = (void *)value;
        if (d->data != data) { /* an SDO download larger than its buffer came in place */
            co_copy(d->data, data, len);
        }
        d->len = len;
    } else {
        /* the value as it came; strings get their tail zeroed, so that a shorter
         * VISIBLE_STRING ends in NUL (fixed types fill their wire size exactly) */
        if (value != data) {
            co_copy(value, data, len);
        }
        co_zero(value + len, co_od_size(od, entry) - len); /* (a fixed type's: its wire size) */
    }
    return CO_ABORT_NONE;
}

static void notify_written(const co_od_t *od, const co_od_entry_t *entry)
{
    const co_od_hooks_t *hooks = co_od_hooks_of(entry);
    if (hooks && hooks->written) {
        hooks->written(od->hook_ctx, entry);
    }
}

co_abort_t co_od_write(const co_od_t *od, const co_od_entry_t *entry, const uint8_t *data,
                       uint32_t len)
{
    co_abort_t abort = co_od_check(od, entry, data, len);
    if (abort == CO_ABORT_NONE) {
        abort = co_od_store(od, entry, data, len);
    }
    if (abort == CO_ABORT_NONE) {
        notify_written(od, entry);
    }
    return abort;
}

co_abort_t co_od_write_piece(const co_od_t *od, const co_od_entry_t *entry, uint32_t offset,
                             const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    if (!has_write_hook(entry)) {
        return CO_ABORT_UNSUPPORTED;
    }
    co_abort_t abort =
        co_od_hooks_of(entry)->write(od->hook_ctx, entry, offset, data, n, total, last);
    if (abort == CO_ABORT_NONE && last) {
        notify_written(od, entry);
    }
    return abort;
}

/* ---- Power-on values. */

/* The node-ID added to the power-on value of a CO_OD_NODEID integer (`value`: its storage,
 * `t`: its type). */
static void add_node_id(const co_od_t *od, const co_od_entry_t *e, void *value,
                        const type_info_t *t, uint8_t node_id)
{
    if ((co_od_attr(od, e) & CO_OD_NODEID) && is_integer(t)) {
        native_set(value, t, native_get(value, t) + node_id);
    }
}

#if !CO_CONFIG_OD_COMPACT
static void reset_entry(const co_od_t *od, const co_od_entry_t *e, uint8_t node_id)
{
    if (e->dflt == NULL || e->value == NULL) {
        return;
    }
    const type_info_t *t = entry_info(od, e);
    if (is_domain(t)) {
        const co_od_domain_t *src = e->dflt;
        co_od_domain_t *dst = e->value;
        uint32_t n = min_u32(src->len, e->size);
        co_copy(dst->data, src->data, n);
        dst->len = n;
        return;
    }
    co_copy(e->value, e->dflt, t->width != 0 ? t->width : e->size);
    add_node_id(od, e, e->value, t, node_id);
}

void co_od_reset(const co_od_t *od, uint16_t first, uint16_t last, uint8_t node_id)
{
    uint32_t i = lower_bound(od, key_of(first, 0));
    for (; i < od->count && od->entries[i].index <= last; i++) {
        reset_entry(od, &od->entries[i], node_id);
    }
}
#else
/* Bytes of storage an entry's power-on value may fill: a fixed type's storage (the image
 * holds its little-endian bytes), the capacity of the others. */
static uint32_t default_cap(const co_od_t *od, const co_od_entry_t *e, const type_info_t *t)
{
    return t->width != 0 ? t->width : co_od_size(od, e);
}

/* One record of the image (co_od_tables_t.defaults): its entry's position (END_OF_IMAGE
 * past the last record) and value. */
typedef struct record {
    uint32_t pos;
    uint32_t len;
    const uint8_t *data;
} record_t;

#define END_OF_IMAGE UINT32_MAX
#define SKIP_FAR 31u /* a record's head: its position follows */
#define LEN_FAR 7u   /* a record's head: its length follows */

/* The record at `p`, the first one since the entry before `next`; the next record after
 * it. */
static const uint8_t *read_record(const uint8_t *p, uint32_t next, record_t *r)
{
    uint32_t head = *p++;
    r->pos = head == 0 ? END_OF_IMAGE : next + (head & SKIP_FAR);
    r->len = head >> 5;
    if ((head & SKIP_FAR) == SKIP_FAR) {
        r->pos = co_get_u16(p);
        p += 2;
    }
    if (r->len == LEN_FAR) {
        r->len = co_get_u16(p);
        p += 2;
    }
    r->data = p;
    return p + r->len;
}

/* `len` little-endian bytes as a bit pattern. */
static bits_t le_bits(const uint8_t *data, uint32_t len)
{
    bits_t bits = 0;
    for (uint32_t n = len; n-- > 0u;) {
        bits = (bits_t)(bits << 8) | data[n];
    }
    return bits;
}

/* An entry's power-on value: the `len` bytes of its record (none without one), the rest of
 * its storage zeroed, the node-ID added. A DOMAIN kept in RAM takes them as its data; one
 * without a record keeps its own (as the general form keeps one without a default). On a
 * little-endian host a number's storage is its record's bytes as they are. */
static void set_default(const co_od_t *od, const co_od_entry_t *e, const uint8_t *data,
                        uint32_t len, uint8_t node_id)
{
    const type_info_t *t = entry_info(od, e);
    uint8_t *value = co_od_value(od, e);
    if (t->kind == K_DOMAIN) {
        if (is_domain(t) && data != NULL) {
            co_od_domain_t *d = (void *)value;
            co_copy(d->data, data, len);
            d->len = len;
        }
        return;
    }
    if (!LITTLE_ENDIAN_HOST && is_number(t)) {
        native_set(value, t, le_bits(data, len));
    } else {
        co_copy(value, data, len);
        co_zero(value + len, default_cap(od, e, t) - len);
    }
    add_node_id(od, e, value, t, node_id);
}

/* The power-on values' image, or NULL. */
static const uint8_t *image_of(const co_od_t *od)
{
    return od->tables != NULL ? od->tables->defaults : NULL;
}

void co_od_reset(const co_od_t *od, uint16_t first, uint16_t last, uint8_t node_id)
{
    record_t r = {.pos = END_OF_IMAGE, .len = 0, .data = NULL};
    const uint8_t *p = image_of(od);
    if (p != NULL) {
        p = read_record(p, 0, &r);
    }
    /* one pass: each entry in the range given its record if it has one (the records before
     * the range passed over) and zeros after it, its node-ID added */
    for (uint32_t i = lower_bound(od, key_of(first, 0));
         i < od->count && od->entries[i].index <= last; i++) {
        const co_od_entry_t *e = &od->entries[i];
        while (r.pos < i) {
            p = read_record(p, r.pos + 1u, &r);
        }
        set_default(od, e, r.pos == i ? r.data : NULL, r.pos == i ? r.len : 0, node_id);
    }
}

/* The image's records name entries in order and fit them; `*bad` gets the position of the
 * entry whose record does not (or count for a record past the table). */
static bool image_fits(const co_od_t *od, uint32_t *bad)
{
    uint32_t next = 0;
    record_t r;
    for (const uint8_t *p = image_of(od); p != NULL;) {
        p = read_record(p, next, &r);
        if (r.pos == END_OF_IMAGE) {
            return true;
        }
        if (r.pos < next || r.pos >= od->count ||
            r.len > default_cap(od, &od->entries[r.pos], entry_info(od, &od->entries[r.pos]))) {
            *bad = r.pos < od->count ? r.pos : od->count;
            return false;
        }
        next = r.pos + 1u;
    }
    return true;
}
#endif

/* ---- Native integer access. */

static bool has_uint(const co_od_t *od, const co_od_entry_t *e)
{
    const type_info_t *t = entry_info(od, e);
    return co_od_value(od, e) != NULL && (is_integer(t) || t->kind == K_BOOL);
}

static co_err_t find_uint(const co_od_t *od, uint16_t index, uint8_t sub,
                          const co_od_entry_t **entry)
{
    *entry = co_od_find(od, index, sub, NULL);
    if (*entry == NULL) {
        return CO_ERR_NOT_FOUND;
    }
    return has_uint(od, *entry) ? CO_OK : CO_ERR_ARG;
}

co_err_t co_od_get_uint(const co_od_t *od, uint16_t index, uint8_t sub, uint64_t *value)
{
    const co_od_entry_t *e;
    co_err_t err = find_uint(od, index, sub, &e);
    if (err == CO_OK) {
        *value = co_od_entry_uint(od, e);
    }
    return err;
}

co_err_t co_od_set_uint(const co_od_t *od, uint16_t index, uint8_t sub, uint64_t value)
{
    const co_od_entry_t *e;
    co_err_t err = find_uint(od, index, sub, &e);
    if (err == CO_OK) {
        native_set(co_od_value(od, e), entry_info(od, e), (bits_t)value);
    }
    return err;
}

uint64_t co_od_entry_uint(const co_od_t *od, const co_od_entry_t *entry)
{
    if (!has_uint(od, entry)) {
        return 0;
    }
    const type_info_t *t = entry_info(od, entry);
    return widen(t, native_get(co_od_value(od, entry), t));
}
