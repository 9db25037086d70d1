/* SPDX-License-Identifier: Apache-2.0 */
/* test_od_compact.c -- the compact form of the dictionary (CO_CONFIG_OD_COMPACT 1, the core
 * built so: tests/CMakeLists.txt): 8-byte entries (values by offset into one struct, sizes
 * from the type or the side table), power-on values from the image without zeros (numbers
 * as their storage's little-endian bytes, strings, the node-ID, index ranges, DOMAINs
 * kept), limits referred to by position, the checks co_od_validate makes of all of them
 * (none in a core built to trust its dictionary, CO_CONFIG_OD_VALIDATE 0), and look-ups
 * through a hash that compares the entries (no key array). */
#include "canola/od.h"
#include "check.h"

#include <stddef.h>

#if !CO_CONFIG_OD_COMPACT
#error "test_od_compact.c needs the core built with CO_CONFIG_OD_COMPACT 1"
#endif

typedef struct values {
    uint32_t device_type;
    int16_t offset;
    int32_t i24;
    float gain;
    uint32_t cob;
    char name[8];
    uint8_t log_data[4];
    co_od_domain_t log;
    uint8_t level;
} values_t;

static values_t v;

static const co_od_limits_t k_limits[] = {
    {.low = {.i = -100}, .high = {.i = 100}},
    {.low = {.u = 1}, .high = {.u = 9}},
};

/* Records: a head (bits 0-4 entries skipped, bits 5-7 the length), the bytes (a number's
 * storage, little-endian); trailing zeros left out. */
static const uint8_t k_image[] = {
    0x40, 0x91, 0x01,             /* 0x1000: 0x191 */
    0x40, 0xFB, 0xFF,             /* 0x2000: -5 as INTEGER16 */
    0x80, 0x00, 0x00, 0x80, 0xFF, /* 0x2001: INTEGER24 -8388608 (its int32_t's 4 bytes) */
    0x80, 0x00, 0x00, 0xAC, 0x41, /* 0x2002: REAL32 21.5 */
    0x40, 0x80, 0x01,             /* 0x2003: 0x180 (+ node-ID) */
    0x40, 'h',  'i',              /* 0x2004: "hi" */
    0x40, 0xAB, 0xCD,             /* 0x2005: a DOMAIN's default */
    0,                            /* end */
};

/* Capacities of the string (1) and the DOMAIN (2). */
static const uint32_t k_sizes[] = {8, 4};

static const co_od_tables_t k_tables = {
    .defaults = k_image, .limits = k_limits, .sizes = k_sizes, .limits_count = 2, .sizes_count = 2};

/* The rows the entries name (co_od_entry_t.row), one each here (tests change them): type,
 * attributes, side table position. */
static co_od_row_t rows[] = {
    {.type = CO_TYPE_UNSIGNED32, .attr = CO_OD_RO},
    {.type = CO_TYPE_INTEGER16, .attr = CO_OD_RW, .side = 1}, /* limits 1 */
    {.type = CO_TYPE_INTEGER24, .attr = CO_OD_RW},
    {.type = CO_TYPE_REAL32, .attr = CO_OD_RW},
    {.type = CO_TYPE_UNSIGNED32, .attr = CO_OD_RW | CO_OD_NODEID},
    {.type = CO_TYPE_VISIBLE_STRING, .attr = CO_OD_RW, .side = 1}, /* capacity 1: 8 */
    {.type = CO_TYPE_DOMAIN, .attr = CO_OD_RW, .side = 2},         /* capacity 2: 4 */
    {.type = CO_TYPE_UNSIGNED8, .attr = CO_OD_RW, .side = 2},      /* limits 2 */
};

/* An entry whose value is member `m` of values_t, of row `r`. */
#define ENTRY(idx, m, r)                                                                           \
    {                                                                                              \
        .index = (idx), .sub = 0, .offset = (uint16_t)offsetof(values_t, m), .row = (r)            \
    }

static co_od_entry_t entries[] = {
    ENTRY(0x1000, device_type, 0), ENTRY(0x2000, offset, 1), ENTRY(0x2001, i24, 2),
    ENTRY(0x2002, gain, 3),        ENTRY(0x2003, cob, 4),    ENTRY(0x2004, name, 5),
    ENTRY(0x2005, log, 6),         ENTRY(0x2006, level, 7),
};

#define COUNT ((uint32_t)(sizeof entries / sizeof entries[0]))

/* The side tables a test changes (a copy of k_tables). */
static co_od_tables_t tables;

static co_od_t make_od(void)
{
    tables = k_tables;
    co_od_t od = {.entries = entries,
                  .count = COUNT,
                  .values = &v,
                  .rows = rows,
                  .rows_count = (uint16_t)(sizeof rows / sizeof rows[0]),
                  .tables = &tables};
    memset(&v, 0x5A, sizeof v);
    v.log.data = v.log_data;
    v.log.len = 0;
    return od;
}

static void test_entry_is_compact(void)
{
    /* index, offset, sub-index and a row: no pointer at all */
    CHECK_EQ(sizeof(co_od_entry_t), 6u);
    co_od_t od = make_od();
    CHECK(co_od_hooks_of(&entries[0]) == NULL);
    CHECK(!co_od_has_limits(&od, &entries[0]));
    CHECK(co_od_has_limits(&od, &entries[1]));
    CHECK(!co_od_has_limits(&od, &entries[5])); /* a string's side is its capacity */
    CHECK_EQ(co_od_type(&od, &entries[2]), CO_TYPE_INTEGER24);
    CHECK_EQ(co_od_attr(&od, &entries[4]), CO_OD_RW | CO_OD_NODEID);
    CHECK_EQ(co_od_access(&od, &entries[0], true), CO_ABORT_READ_ONLY);
}

static void test_values_and_sizes(void)
{
    co_od_t od = make_od();
    CHECK(co_od_value(&od, &entries[0]) == (void *)&v.device_type);
    CHECK(co_od_value(&od, &entries[5]) == (void *)v.name);
    CHECK(co_od_value(&od, &entries[7]) == (void *)&v.level);
    /* sizes from the type, strings and domains from the side table */
    CHECK_EQ(co_od_size(&od, &entries[0]), 4u);
    CHECK_EQ(co_od_size(&od, &entries[1]), 2u);
    CHECK_EQ(co_od_size(&od, &entries[2]), 3u); /* INTEGER24: 3 on the wire */
    CHECK_EQ(co_od_size(&od, &entries[5]), 8u);
    CHECK_EQ(co_od_size(&od, &entries[6]), 4u);
    CHECK_EQ(co_od_size(&od, &entries[7]), 1u);
    co_od_reset(&od, 0x0000, 0xFFFF, 0);
    CHECK_EQ(co_od_entry_uint(&od, &entries[1]), (uint64_t)-5);
    CHECK_EQ(co_od_set_uint(&od, 0x2006, 0, 7), CO_OK);
    CHECK_EQ(v.level, 7u);
    /* reads and writes reach the value at its offset, strings up to their capacity */
    uint8_t buf[9];
    uint32_t n = 0;
    uint32_t total = 0;
    CHECK_EQ(co_od_read(&od, &entries[5], 0, buf, sizeof buf, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(total, 2u);
    CHECK(memcmp(buf, "hi", 2) == 0);
    CHECK_EQ(co_od_write(&od, &entries[5], (const uint8_t *)"abcdefgh", 8), CO_ABORT_NONE);
    CHECK(memcmp(v.name, "abcdefgh", 8) == 0);
    CHECK_EQ(co_od_write(&od, &entries[5], (const uint8_t *)"abcdefghi", 9), CO_ABORT_LEN_HIGH);
    CHECK_EQ(co_od_write(&od, &entries[6], (const uint8_t *)"wxyz!", 5), CO_ABORT_LEN_HIGH);
    CHECK_EQ(co_od_write(&od, &entries[6], (const uint8_t *)"wxy", 3), CO_ABORT_NONE);
    CHECK_EQ(v.log.len, 3u);
    CHECK_EQ(co_od_value_len(&od, &entries[6]), 3u);
}

static void test_reset_from_image(void)
{
    co_od_t od = make_od();
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    co_od_reset(&od, 0x0000, 0xFFFF, 5);
    CHECK_EQ(v.device_type, 0x191u);
    CHECK_EQ(v.offset, -5);
    CHECK_EQ(v.i24, -8388608);
    CHECK(v.gain == 21.5f);
    CHECK_EQ(v.cob, 0x185u); /* the node-ID added */
    CHECK_STR(v.name, "hi");
    CHECK_EQ(v.name[7], 0); /* the rest of the string zeroed */
    CHECK_EQ(v.level, 0);   /* no record: zero */
    CHECK_EQ(v.log.len, 2u);
    CHECK_EQ(v.log_data[1], 0xCDu);
}

static void test_reset_range(void)
{
    co_od_t od = make_od();
    co_od_reset(&od, 0x2001, 0x2003, 1);
    CHECK_EQ(v.device_type, 0x5A5A5A5Au); /* outside the range: as it was */
    CHECK_EQ((uint16_t)v.offset, 0x5A5Au);
    CHECK_EQ(v.i24, -8388608);
    CHECK_EQ(v.cob, 0x181u);
    CHECK_EQ(v.name[0], 0x5A);
    CHECK_EQ(v.level, 0x5Au);
}

static void test_domain_without_record_kept(void)
{
    static const uint8_t empty[] = {0};
    co_od_t od = make_od();
    tables.defaults = empty;
    v.log.len = 3;
    co_od_reset(&od, 0x0000, 0xFFFF, 0);
    CHECK_EQ(v.log.len, 3u); /* a DOMAIN without a power-on value keeps its own */
    CHECK_EQ(v.offset, 0);   /* every other value: zero */
    CHECK_EQ(v.name[0], 0);
    tables.defaults = NULL; /* no image at all: zeros */
    v.device_type = 7;
    co_od_reset(&od, 0x0000, 0xFFFF, 0);
    CHECK_EQ(v.device_type, 0u);
}

static void test_image_skips_and_positions(void)
{
    /* entry 1 (one skipped), then entry 7 by its position, 1 byte each */
    static const uint8_t image[] = {0x21, 0x07, 0x3F, 7, 0, 0x09, 0};
    co_od_t od = make_od();
    tables.defaults = image;
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    co_od_reset(&od, 0x0000, 0xFFFF, 0);
    CHECK_EQ(v.device_type, 0u);
    CHECK_EQ(v.offset, 7);
    CHECK_EQ(v.i24, 0);
    CHECK_EQ(v.level, 9u);
    co_od_reset(&od, 0x2006, 0x2006, 0); /* a range that starts past the first record */
    CHECK_EQ(v.level, 9u);
}

static void test_limits_by_position(void)
{
    co_od_t od = make_od();
    co_od_reset(&od, 0x0000, 0xFFFF, 0);
    const co_od_entry_t *e = co_od_find(&od, 0x2000, 0, NULL);
    uint8_t high[2] = {101, 0};
    uint8_t low[2] = {0x9B, 0xFF}; /* -101 */
    uint8_t ok[2] = {100, 0};
    CHECK_EQ(co_od_write(&od, e, high, 2), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(co_od_write(&od, e, low, 2), CO_ABORT_VALUE_LOW);
    CHECK_EQ(co_od_write(&od, e, ok, 2), CO_ABORT_NONE);
    CHECK_EQ(v.offset, 100);
    e = co_od_find(&od, 0x2006, 0, NULL);
    uint8_t zero = 0;
    CHECK_EQ(co_od_write(&od, e, &zero, 1), CO_ABORT_VALUE_LOW);
    e = co_od_find(&od, 0x2001, 0, NULL); /* no limits */
    uint8_t any[3] = {0xFF, 0xFF, 0x7F};
    CHECK_EQ(co_od_write(&od, e, any, 3), CO_ABORT_NONE);
}

static void test_validate_limits_and_image(void)
{
    co_od_t od = make_od();
    uint32_t bad = 0;
    tables.limits_count = 1; /* 0x2006 refers to limits 2 */
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 7u);
    od = make_od();
    tables.limits = NULL;
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 1u);
    od = make_od();
    tables.sizes_count = 1; /* the DOMAIN refers to capacity 2 */
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 6u);
    od = make_od();
    tables.sizes = NULL;
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 5u);
    static const uint32_t zero_size[] = {0, 4};
    od = make_od();
    tables.sizes = zero_size; /* a string of no capacity */
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 5u);
    od = make_od();
    od.rows_count = 7; /* 0x2006 names row 7 */
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 7u);
    od = make_od();
    od.values = NULL; /* the entries' values are nowhere */
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 0u);
    od = make_od();
    od.tables = NULL; /* the entries refer to tables there are none of */
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 1u);

    /* a string without a capacity, a number past the limits, a TIME_OF_DAY with a side */
    static co_od_row_t odd_row[] = {{.type = CO_TYPE_VISIBLE_STRING, .attr = CO_OD_RW}};
    static co_od_entry_t odd[] = {ENTRY(0x2004, name, 0)};
    od = make_od();
    od.entries = odd;
    od.count = 1;
    od.rows = odd_row;
    od.rows_count = 1;
    od.tables = NULL;
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 0u);
    odd[0] = (co_od_entry_t)ENTRY(0x2006, level, 0);
    odd_row[0] = (co_od_row_t){.type = CO_TYPE_UNSIGNED8, .attr = CO_OD_RW, .side = 3};
    od.tables = &tables;
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    odd[0] = (co_od_entry_t)ENTRY(0x2006, name, 0);
    odd_row[0] = (co_od_row_t){.type = CO_TYPE_TIME_OF_DAY, .attr = CO_OD_RW, .side = 1};
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    odd_row[0].side = 0; /* the same without a side: fine (and without the others' image) */
    tables.defaults = NULL;
    CHECK_EQ(co_od_validate(&od, &bad), CO_OK);

    static const uint8_t too_long[] = {0x61, 1, 2, 3, 0}; /* 3 bytes for the INTEGER16 */
    /* entry 3, then entry 1 by its position (head 31: the position follows) */
    static const uint8_t out_of_order[] = {0x23, 1, 0x3F, 1, 0, 1, 0};
    static const uint8_t past_table[] = {0x28, 1, 0}; /* entry 8 of 8 */
    /* head 7: the length follows (9: more than the string's capacity) */
    static const uint8_t string_cap[] = {0xE5, 9, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0};
    static const uint8_t long_form[] = {0xE5, 8, 0, 'a', 'b', 'c', 'd', 'e', 'f', 'g', 'h', 0};
    od = make_od();
    tables.defaults = too_long;
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 1u);
    tables.defaults = out_of_order;
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 1u);
    tables.defaults = past_table;
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, COUNT);
    tables.defaults = string_cap;
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 5u);
    tables.defaults = long_form; /* a length of 255 or more: in the 2 bytes after 255 */
    CHECK_EQ(co_od_validate(&od, &bad), CO_OK);
    co_od_reset(&od, 0x2004, 0x2004, 0);
    CHECK(memcmp(v.name, "abcdefgh", 8) == 0);
}

/* A core that trusts its dictionary (CO_CONFIG_OD_VALIDATE 0) checks nothing of it: what
 * test_validate_limits_and_image refuses passes (the generator's tests validate what it
 * generates), NULL excepted. */
static void test_validation_left_out(void)
{
    co_od_t od = make_od();
    uint32_t bad = 99;
    tables.limits_count = 1; /* 0x2006 refers to limits 2 */
    static const uint8_t past_table[] = {0x28, 1, 0};
    tables.defaults = past_table;
    CHECK_EQ(co_od_validate(&od, &bad), CO_OK);
    CHECK_EQ(bad, 99u);
    CHECK_EQ(co_od_validate(NULL, &bad), CO_ERR_ARG);
}

static void test_hash_compares_entries(void)
{
    co_od_t od = make_od();
    uint16_t slots[16];
    CHECK_EQ(co_od_hash_build(&od, slots, co_od_hash_bits(od.count)), CO_OK);
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    for (uint32_t i = 0; i < COUNT; i++) {
        CHECK(co_od_find(&od, entries[i].index, 0, NULL) == &entries[i]);
    }
    co_abort_t abort = CO_ABORT_NONE;
    CHECK(co_od_find(&od, 0x2003, 1, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_SUB);
    CHECK(co_od_find(&od, 0x3000, 0, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_OBJECT);
#if CO_CONFIG_OD_HASH
    slots[CO_OD_HASH_HOME(CO_OD_KEY(0x2003, 0), od.hash_mask)] = 0; /* 0x2003 lost */
    CHECK_EQ(co_od_validate(&od, NULL), CO_ERR_CONFIG);
#endif
}

int main(void)
{
    RUN(test_entry_is_compact);
    RUN(test_values_and_sizes);
    RUN(test_reset_from_image);
    RUN(test_reset_range);
    RUN(test_domain_without_record_kept);
    RUN(test_image_skips_and_positions);
    RUN(test_limits_by_position);
    if (CO_CONFIG_OD_VALIDATE) {
        RUN(test_validate_limits_and_image);
    } else {
        RUN(test_validation_left_out);
    }
    RUN(test_hash_compares_entries);
    return check_summary();
}
