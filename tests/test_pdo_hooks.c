/* SPDX-License-Identifier: Apache-2.0 */
/* test_pdo_hooks.c -- PDOs that map objects served by application hooks: a TPDO reads
 * through the read hook, an RPDO hands its bytes to the write hook and runs the written
 * hook of a stored value; partial (bit-level) mapping goes through the same hooks. RPDO
 * data is not validated: neither limits nor the check hook apply (the fast path; see
 * docs/security.md), which the last check pins down. */
#include "check.h"
#include "harness.h"

#define NODE 5

typedef struct rig {
    test_node_t t;
    co_od_entry_t entries[EXAMPLE_OD_MAX_ENTRIES + 9];
    uint16_t u16;     /* 0x2101: storage with check and written hooks */
    uint16_t plain16; /* 0x2102 */
    uint64_t plain64; /* 0x2103 */
    double real64;    /* 0x2104 */
    uint8_t tod[6];   /* 0x2105 TIME_OF_DAY */
    char text[8];     /* 0x2106 VISIBLE_STRING, marked mappable */
    int32_t i24;      /* 0x2107 INTEGER24 */
    bool flag;        /* 0x2108 BOOLEAN */
    uint32_t produced;
    uint8_t taken[8];
    uint32_t taken_len;
    int writes, checks, written;
    bool refuse; /* the write hook refuses what it is given */
} rig_t;

static rig_t g; /* the hooks' context */

static co_abort_t h_read(void *ctx, const co_od_entry_t *e, uint32_t offset, uint8_t *buf,
                         uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)e;
    rig_t *r = ctx;
    uint8_t v[4];
    co_put_u32(v, r->produced);
    *n = 0;
    for (uint32_t i = offset; i < 4 && *n < cap; i++) {
        buf[(*n)++] = v[i];
    }
    *total = 4;
    return CO_ABORT_NONE;
}

static co_abort_t h_write(void *ctx, const co_od_entry_t *e, uint32_t offset, const uint8_t *data,
                          uint32_t n, uint32_t total, bool last)
{
    (void)e;
    (void)total;
    (void)last;
    rig_t *r = ctx;
    r->writes++;
    if (r->refuse) {
        return CO_ABORT_DATA_LOCAL;
    }
    memcpy(&r->taken[offset], data, n);
    r->taken_len = offset + n;
    return CO_ABORT_NONE;
}

static co_abort_t h_check(void *ctx, const co_od_entry_t *e, const uint8_t *data, uint32_t len)
{
    (void)e;
    (void)len;
    rig_t *r = ctx;
    r->checks++;
    return co_get_u16(data) == 0xFFFF ? CO_ABORT_VALUE : CO_ABORT_NONE;
}

static void h_written(void *ctx, const co_od_entry_t *e)
{
    (void)e;
    ((rig_t *)ctx)->written++;
}

static const co_od_hooks_t k_stream = {.read = h_read, .write = h_write};
static const co_od_hooks_t k_guarded = {.check = h_check, .written = h_written};

/* The example dictionary plus 0x2100 (u32, hooks only), 0x2101 (u16, checked), plain
 * mappable 0x2102 (u16) and 0x2103 (u64), 0x2104 REAL64, 0x2105 TIME_OF_DAY, 0x2106, a
 * string wrongly marked mappable, and mappable 0x2107 INTEGER24 and 0x2108 BOOLEAN. */
static void rig_up(void)
{
    memset(&g, 0, sizeof g);
    CHECK_EQ(test_node_init(&g.t, NODE, 0), CO_OK);
    co_od_t base = g.t.cfg.od;
    uint8_t map = CO_OD_RW | CO_OD_TPDO | CO_OD_RPDO;
    co_od_entry_t stream = {0x2100, 0, CO_TYPE_UNSIGNED32, map, 4, NULL, NULL, NULL, &k_stream};
    co_od_entry_t guarded = {0x2101, 0, CO_TYPE_UNSIGNED16, map, 2, &g.u16, NULL, NULL, &k_guarded};
    const co_od_entry_t extra[] = {
        {0x2102, 0, CO_TYPE_UNSIGNED16, map, 2, &g.plain16, NULL, NULL, NULL},
        {0x2103, 0, CO_TYPE_UNSIGNED64, map, 8, &g.plain64, NULL, NULL, NULL},
        {0x2104, 0, CO_TYPE_REAL64, CO_OD_RW, 8, &g.real64, NULL, NULL, NULL},
        {0x2105, 0, CO_TYPE_TIME_OF_DAY, CO_OD_RW, 6, g.tod, NULL, NULL, NULL},
        {0x2106, 0, CO_TYPE_VISIBLE_STRING, map, sizeof g.text, g.text, NULL, NULL, NULL},
        {0x2107, 0, CO_TYPE_INTEGER24, map, 3, &g.i24, NULL, NULL, NULL},
        {0x2108, 0, CO_TYPE_BOOLEAN, map, 1, &g.flag, NULL, NULL, NULL},
    };
    uint32_t n = 0;
    for (uint32_t i = 0; i < base.count; i++) {
        if (base.entries[i].index > 0x2108 && n == i) {
            g.entries[n++] = stream;
            g.entries[n++] = guarded;
            for (size_t k = 0; k < sizeof extra / sizeof extra[0]; k++) {
                g.entries[n++] = extra[k];
            }
        }
        g.entries[n++] = base.entries[i];
    }
    g.t.cfg.od = (co_od_t){.entries = g.entries, .count = n, .hook_ctx = &g};
    CHECK_EQ(co_node_init(&g.t.node, &g.t.cfg), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
}

/* The re-mapping procedure for PDO comm `comm`, mapping `map`, with `count` entries. */
static void remap(uint16_t comm, uint16_t map, uint32_t cob, const uint32_t *entries, uint8_t count)
{
    CHECK_EQ(write_u32(&g.t, comm, 1, cob | 0x80000000u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&g.t, map, 0, 0), CO_ABORT_NONE);
    for (uint8_t i = 0; i < count; i++) {
        CHECK_EQ(write_u32(&g.t, map, (uint8_t)(i + 1), entries[i]), CO_ABORT_NONE);
    }
    CHECK_EQ(write_u8(&g.t, map, 0, count), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&g.t, comm, 1, cob), CO_ABORT_NONE);
}

/* RPDO1 (0x205) and TPDO1 (0x185) both mapping the `count` entries `m`, the node
 * operational, nothing sent so far. */
static void map_both_and_start(const uint32_t *m, uint8_t count)
{
    remap(0x1400, 0x1600, 0x205, m, count);
    remap(0x1800, 0x1A00, 0x185, m, count);
    ingest(&g.t, 0, 0x000, "01 05");
    fake_clear(&g.t.bus);
}

static void test_rpdo_into_hooked_objects(void)
{
    rig_up();
    const uint32_t m[] = {0x21000020, 0x21010010, 0x21010008};
    remap(0x1400, 0x1600, 0x205, m, 3);
    ingest(&g.t, 0, 0x000, "01 05");
    ingest(&g.t, 1000, 0x205, "11 22 33 44 55 66 77");
    CHECK_EQ(g.writes, 1);
    CHECK_EQ(g.taken_len, 4);
    CHECK_EQ(co_get_u32(g.taken), 0x44332211u);
    /* 0x2101 whole (0x6655), then its low 8 bits again (0x77): told twice. */
    CHECK_EQ(g.u16, 0x6677);
    CHECK_EQ(g.written, 2);
    /* Not validated: a value the check hook would veto over SDO is stored from an RPDO. */
    CHECK_EQ(write_u16(&g.t, 0x2101, 0, 0xFFFF), CO_ABORT_VALUE);
    CHECK_EQ(g.checks, 1);
    ingest(&g.t, 2000, 0x205, "11 22 33 44 FF FF FF");
    CHECK_EQ(g.checks, 1);
    CHECK_EQ(g.u16, 0xFFFF);
    CHECK_EQ(g.written, 4);
}

static void test_tpdo_from_hooked_objects(void)
{
    rig_up();
    const uint32_t m[] = {0x21000020, 0x21010004, 0x21010010};
    remap(0x1800, 0x1A00, 0x185, m, 3);
    ingest(&g.t, 0, 0x000, "01 05");
    fake_clear(&g.t.bus);
    g.produced = 0xA1B2C3D4u;
    g.u16 = 0x1234;
    CHECK_EQ(co_tpdo_request(&g.t.node, 0), CO_OK);
    char dump[64];
    /* 32 bits from the read hook, 4 bits (0x4) of 0x2101, then 0x2101 whole from bit 36. */
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "185#D4C3B2A1442301");
}

/* Whole 16- and 64-bit values travel by the direct path both ways. */
static void test_plain_values_of_every_width(void)
{
    rig_up();
    const uint32_t rx1[] = {0x21020010, 0x21000020};
    const uint32_t rx2[] = {0x21030040};
    remap(0x1400, 0x1600, 0x205, rx1, 2);
    remap(0x1401, 0x1601, 0x305, rx2, 1);
    const uint32_t tx[] = {0x21030040};
    remap(0x1800, 0x1A00, 0x185, tx, 1);
    ingest(&g.t, 0, 0x000, "01 05");
    ingest(&g.t, 1000, 0x205, "34 12 01 02 03 04");
    CHECK_EQ(g.plain16, 0x1234);
    CHECK_EQ(co_get_u32(g.taken), 0x04030201u);
    fake_clear(&g.t.bus);
    ingest(&g.t, 2000, 0x305, "01 02 03 04 05 06 07 08");
    CHECK_EQ(g.plain64, 0x0807060504030201ull);
    /* The TPDO maps 0x2103, changed by the RPDO: an event-driven TPDO goes out. */
    char dump[64];
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "185#0102030405060708");
    /* A string cannot be mapped, whatever its attributes say. */
    CHECK_EQ(write_u32(&g.t, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&g.t, 0x1A00, 0, 0), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&g.t, 0x1A00, 1, 0x21060008), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&g.t, 0x1A00, 0, 1), CO_ABORT_NO_MAP);
}

/* A value the write hook refuses is not taken: it is no change, so the event-driven TPDO
 * mapping the object stays silent. */
static void test_rpdo_value_refused_by_the_write_hook(void)
{
    rig_up();
    const uint32_t m[] = {0x21000020};
    map_both_and_start(m, 1);
    g.refuse = true;
    ingest(&g.t, 1000, 0x205, "11 22 33 44");
    CHECK_EQ(g.writes, 1);
    CHECK_EQ(g.taken_len, 0);
    CHECK_EQ(g.t.bus.count, 0);
    g.refuse = false;
    g.produced = 0x55667788u;
    ingest(&g.t, 2000, 0x205, "11 22 33 44");
    CHECK_EQ(g.writes, 2);
    CHECK_EQ(co_get_u32(g.taken), 0x44332211u);
    char dump[64];
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "185#88776655");
}

/* An RPDO stores all its values before TPDOs hear of the changes, also when a value goes
 * through hooks (not the plain copy): the event-driven TPDO mapping both objects never
 * carries the new first value with the old second one. */
static void test_rpdo_values_stored_before_tpdo_events(void)
{
    rig_up();
    const uint32_t m[] = {0x21010010, 0x21020010};
    map_both_and_start(m, 2);
    ingest(&g.t, 1000, 0x205, "34 12 78 56");
    CHECK_EQ(g.u16, 0x1234);
    CHECK_EQ(g.plain16, 0x5678);
    CHECK_EQ(g.written, 1);
    char dump[64];
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "185#34127856 185#34127856");
}

/* Whole values whose storage is not their wire form, in both directions: an INTEGER24
 * (sign-extended into its int32_t) and a BOOLEAN (any non-zero byte stored as 1). */
static void test_values_converted_on_the_way(void)
{
    rig_up();
    const uint32_t m[] = {0x21070018, 0x21080008};
    map_both_and_start(m, 2);
    g.i24 = 0x7FFFFFFF;
    ingest(&g.t, 1000, 0x205, "FE FF FF 05");
    CHECK_EQ(g.i24, -2);
    CHECK_EQ(g.flag, true);
    char dump[64];
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "185#FEFFFF01 185#FEFFFF01");
}

/* A cyclic TPDO that is not all plain values (a hook-served one first) counts its SYNCs
 * all the same, and samples each value when it is due. */
static void test_cyclic_tpdo_with_a_hooked_object(void)
{
    rig_up();
    const uint32_t m[] = {0x21000020, 0x21020010};
    remap(0x1800, 0x1A00, 0x185, m, 2);
    CHECK_EQ(write_u8(&g.t, 0x1800, 2, 2), CO_ABORT_NONE); /* every second SYNC */
    ingest(&g.t, 0, 0x000, "01 05");
    fake_clear(&g.t.bus);
    for (uint32_t i = 1; i <= 4; i++) {
        g.produced = 0x01020300u + i;
        g.plain16 = (uint16_t)(0xA0 + i);
        ingest(&g.t, i * 1000, 0x080, "");
    }
    char dump[64];
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "185#02030201A200 185#04030201A400");
}

/* A 16-bit value alone takes the short paths: received at once, sent at every SYNC. */
static void test_plain_16_bit_value_on_the_short_paths(void)
{
    rig_up();
    const uint32_t m[] = {0x21020010};
    remap(0x1400, 0x1600, 0x205, m, 1);
    remap(0x1800, 0x1A00, 0x185, m, 1);
    CHECK_EQ(write_u8(&g.t, 0x1800, 2, 1), CO_ABORT_NONE);
    ingest(&g.t, 0, 0x000, "01 05");
    fake_clear(&g.t.bus);
    ingest(&g.t, 1000, 0x205, "34 12");
    CHECK_EQ(g.plain16, 0x1234);
    ingest(&g.t, 2000, 0x080, "");
    char dump[64];
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "185#3412");
}

/* Local access to entries that are not plain integers, and hooks on local writes. */
static void test_local_access_to_other_kinds(void)
{
    rig_up();
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&g.t.node, 0x2104, 0, &v), CO_ERR_ARG); /* REAL64 */
    CHECK_EQ(co_node_get_uint(&g.t.node, 0x2105, 0, &v), CO_ERR_ARG); /* TIME_OF_DAY */
    CHECK_EQ(co_node_get_uint(&g.t.node, 0x2100, 0, &v), CO_ERR_ARG); /* no storage */
    CHECK_EQ(co_node_get_uint(&g.t.node, 0x2103, 0, &v), CO_OK);
    /* Nor are they set as one. */
    double real_before = g.real64;
    CHECK_EQ(co_node_set_uint(&g.t.node, 0x2104, 0, 1), CO_ABORT_TYPE_MISMATCH);
    CHECK(memcmp(&g.real64, &real_before, sizeof real_before) == 0);
    g.tod[0] = 0x5A;
    CHECK_EQ(co_node_set_uint(&g.t.node, 0x2105, 0, 1), CO_ABORT_TYPE_MISMATCH);
    CHECK_EQ(g.tod[0], 0x5A);
    CHECK_EQ(co_node_set_uint(&g.t.node, 0x2101, 0, 7), CO_ABORT_NONE);
    CHECK_EQ(g.checks, 1);
    CHECK_EQ(g.written, 1);
    /* A read hook's value that does not fit the caller's buffer. */
    uint8_t buf[2];
    uint32_t len = 0;
    CHECK_EQ(co_node_read_net(&g.t.node, 0x2100, 0, buf, sizeof buf, &len), CO_ABORT_LEN_HIGH);
}

int main(void)
{
    RUN(test_rpdo_into_hooked_objects);
    RUN(test_tpdo_from_hooked_objects);
    RUN(test_plain_values_of_every_width);
    RUN(test_local_access_to_other_kinds);
    RUN(test_rpdo_value_refused_by_the_write_hook);
    RUN(test_cyclic_tpdo_with_a_hooked_object);
    RUN(test_rpdo_values_stored_before_tpdo_events);
    RUN(test_values_converted_on_the_way);
    RUN(test_plain_16_bit_value_on_the_short_paths);
    return check_summary();
}
