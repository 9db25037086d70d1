/* SPDX-License-Identifier: Apache-2.0 */
/* test_dictionaries.c -- nodes on dictionaries other than the example's: more heartbeat
 * consumer entries than the node can watch, none at all, SDO client parameters 0x1280 kept
 * in step with the channel, stored parameters next to hook-served objects. Each dictionary
 * is the example's with entries left out and others merged in (sorted). */
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define MAX_ENTRIES (EXAMPLE_OD_MAX_ENTRIES + 16)

typedef struct dict {
    test_node_t t;
    co_od_entry_t entries[MAX_ENTRIES];
    uint32_t extra_u32[16];
} dict_t;

static dict_t g;

static bool before(const co_od_entry_t *a, const co_od_entry_t *b)
{
    return a->index < b->index || (a->index == b->index && a->sub < b->sub);
}

/* The example dictionary without entries of index `drop` (0: none), with `extra` merged in. */
static co_err_t build(uint16_t hb_ms, uint16_t drop, const co_od_entry_t *extra, uint32_t n_extra)
{
    memset(&g, 0, sizeof g);
    test_node_init(&g.t, 5, hb_ms);
    co_od_t base = g.t.cfg.od;
    uint32_t n = 0;
    uint32_t k = 0;
    for (uint32_t i = 0; i < base.count; i++) {
        while (k < n_extra && before(&extra[k], &base.entries[i])) {
            g.entries[n++] = extra[k++];
        }
        if (base.entries[i].index != drop) {
            g.entries[n++] = base.entries[i];
        }
    }
    while (k < n_extra) {
        g.entries[n++] = extra[k++];
    }
    g.t.cfg.od.entries = g.entries;
    g.t.cfg.od.count = n;
    return co_node_init(&g.t.node, &g.t.cfg);
}

static co_od_entry_t u32_entry(uint16_t index, uint8_t sub, uint32_t *value)
{
    return (co_od_entry_t){index, sub, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, value, NULL, NULL, NULL};
}

static void test_more_consumer_entries_than_the_node_watches(void)
{
    co_od_entry_t extra[CO_HB_CONSUMERS_MAX];
    uint32_t n = 0;
    for (uint8_t sub = EXAMPLE_HB_CONSUMERS + 1; sub <= CO_HB_CONSUMERS_MAX + 1; sub++) {
        extra[n] = u32_entry(0x1016, sub, &g.extra_u32[n]);
        n++;
    }
    CHECK_EQ(build(0, 0, extra, n), CO_ERR_CONFIG);
    CHECK_EQ(build(0, 0, extra, n - 1), CO_OK); /* exactly CO_HB_CONSUMERS_MAX: fine */
}

static void test_boot_time_without_consumers(void)
{
    CHECK_EQ(build(0, 0x1016, NULL, 0), CO_OK);
    g.t.node.cfg.boot_time_ms = 100;
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    co_node_poll(&g.t.node, 1000 * MS);
    CHECK_EQ(g.t.event_count, 0); /* nobody to miss */
}

/* 0x1280: sub1 COB-ID client -> server, sub2 server -> client, sub3 server node-ID. */
static uint32_t g_tx, g_rx;
static uint8_t g_server;

static void client_params(co_od_entry_t extra[3])
{
    extra[0] = u32_entry(0x1280, 1, &g_tx);
    extra[1] = u32_entry(0x1280, 2, &g_rx);
    extra[2] =
        (co_od_entry_t){0x1280, 3, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &g_server, NULL, NULL, NULL};
}

static void test_client_parameters_in_the_dictionary(void)
{
    co_od_entry_t extra[3];
    client_params(extra);
    CHECK_EQ(build(0, 0, extra, 3), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    /* Setup writes the parameters; a write to them re-points the channel. */
    CHECK_EQ(co_sdo_client_setup(&g.t.node, 0, 7), CO_OK);
    CHECK_EQ(g_tx, 0x607);
    CHECK_EQ(g_server, 7);
    CHECK_EQ(write_u32(&g.t, 0x1280, 1, 0x608), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&g.t, 0x1280, 2, 0x588), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&g.t, 0x1280, 3, 8), CO_ABORT_NONE);
    uint8_t buf[4];
    sdo_result_t r = {0};
    fake_clear(&g.t.bus);
    CHECK_EQ(co_sdo_upload(&g.t.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, 4, sdo_result_done, &r),
             CO_OK);
    CHECK_EQ(fake_count_id(&g.t.bus, 0x608), 1);
    /* Changing the server under an open transfer ends it, with an abort to the old one. */
    CHECK_EQ(write_u8(&g.t, 0x1280, 3, 9), CO_ABORT_NONE);
    CHECK_EQ(r.calls, 1);
    CHECK_EQ(r.abort, CO_ABORT_GENERAL);
    CHECK_EQ(fake_count_id(&g.t.bus, 0x608), 2);
    /* Pointed at the node itself: served locally, nothing routed for responses. */
    CHECK_EQ(write_u8(&g.t, 0x1280, 3, 5), CO_ABORT_NONE);
    r.calls = 0;
    fake_clear(&g.t.bus);
    CHECK_EQ(co_sdo_upload(&g.t.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, 4, sdo_result_done, &r),
             CO_OK);
    CHECK_EQ(r.calls, 1);
    CHECK_EQ(r.abort, CO_ABORT_NONE);
    CHECK_EQ(co_get_u32(buf), g.t.od.device_type);
    CHECK_EQ(g.t.bus.count, 0);
}

/* A dictionary with 0x1280 sub1 only is not a client parameter set: the channel keeps the
 * setup the application gave it. */
static void test_incomplete_client_parameters_are_ignored(void)
{
    co_od_entry_t extra[1] = {u32_entry(0x1280, 1, &g_tx)};
    CHECK_EQ(build(0, 0, extra, 1), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&g.t.node, 0, 7), CO_OK);
    co_nmt_apply(&g.t.node, CO_NMT_CMD_RESET_COMMUNICATION);
    uint8_t buf[4];
    sdo_result_t r = {0};
    fake_clear(&g.t.bus);
    CHECK_EQ(co_sdo_upload(&g.t.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, 4, sdo_result_done, &r),
             CO_OK);
    CHECK_EQ(fake_count_id(&g.t.bus, 0x607), 1);
}

/* ---- what a save records */

static uint16_t g_saved[256];
static uint32_t g_saved_count;

static co_err_t st_begin(void *ctx, co_param_group_t group)
{
    (void)ctx;
    (void)group;
    return CO_OK;
}

static co_err_t st_write(void *ctx, const uint8_t *data, uint32_t len)
{
    (void)ctx;
    (void)len;
    if (g_saved_count < 256) {
        g_saved[g_saved_count++] = co_get_u16(data);
    }
    return CO_OK;
}

static co_err_t st_commit(void *ctx)
{
    (void)ctx;
    return CO_OK;
}

static co_err_t st_read(void *ctx, co_param_group_t group, uint32_t offset, uint8_t *buf,
                        uint32_t cap, uint32_t *n)
{
    (void)ctx;
    (void)group;
    (void)offset;
    (void)buf;
    (void)cap;
    (void)n;
    return CO_ERR_NOT_FOUND;
}

static co_err_t st_erase(void *ctx, co_param_group_t group)
{
    (void)ctx;
    (void)group;
    return CO_OK;
}

static const co_storage_t k_recorder = {
    .begin = st_begin, .write = st_write, .commit = st_commit, .read = st_read, .erase = st_erase};

static bool saved(uint16_t index)
{
    for (uint32_t i = 0; i < g_saved_count; i++) {
        if (g_saved[i] == index) {
            return true;
        }
    }
    return false;
}

static co_abort_t refuse_read(void *ctx, const co_od_entry_t *e, uint32_t offset, uint8_t *buf,
                              uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    (void)e;
    (void)offset;
    (void)buf;
    (void)cap;
    (void)n;
    (void)total;
    return CO_ABORT_HARDWARE;
}

static co_abort_t take_write(void *ctx, const co_od_entry_t *e, uint32_t offset,
                             const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    (void)ctx;
    (void)e;
    (void)offset;
    (void)data;
    (void)n;
    (void)total;
    (void)last;
    return CO_ABORT_NONE;
}

static const co_od_hooks_t k_unreadable = {.read = refuse_read};
static const co_od_hooks_t k_hooks_only = {.read = refuse_read, .write = take_write};
static char g_long[100];
static uint32_t g_plain;
static uint32_t g_const_rw;

static void test_save_records_parameters_only(void)
{
    const co_od_entry_t extra[] = {
        {0x2100, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, NULL, NULL, NULL, &k_hooks_only},
        {0x2101, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &g_plain, NULL, NULL, &k_unreadable},
        {0x2102, 0, CO_TYPE_VISIBLE_STRING, CO_OD_RW, sizeof g_long, g_long, NULL, NULL, NULL},
        {0x2103, 0, CO_TYPE_UNSIGNED32, CO_OD_RW | CO_OD_CONST, 4, &g_const_rw, NULL, NULL, NULL},
        {0x2104, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &g_plain, NULL, NULL, NULL},
    };
    CHECK_EQ(build(0, 0, extra, sizeof extra / sizeof extra[0]), CO_OK);
    g.t.node.cfg.storage = &k_recorder;
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    memset(g_long, 'x', sizeof g_long - 1); /* 99 characters */
    g_saved_count = 0;
    CHECK_EQ(co_storage_save(&g.t.node, 3), CO_OK);
    CHECK(saved(0x2000));  /* a plain parameter */
    CHECK(saved(0x2104));  /* another */
    CHECK(!saved(0x2100)); /* no storage: the hooks own the value */
    CHECK(!saved(0x2101)); /* unreadable */
    CHECK(!saved(0x2102)); /* longer than CO_STORE_VALUE_MAX */
    CHECK(!saved(0x2103)); /* constant */
    CHECK(!saved(0x2003)); /* a DOMAIN */
    /* A read of the unreadable one gets its hook's abort code. */
    uint8_t buf[4];
    uint32_t len = 0;
    CHECK_EQ(co_node_read_net(&g.t.node, 0x2101, 0, buf, sizeof buf, &len), CO_ABORT_HARDWARE);
}

/* A parameter whose read hook answers differently each time (a counter): the two passes
 * of a save disagree, and the save fails rather than store an image that would not load. */
static uint32_t g_ticks;
static int g_commits;
static int g_discards;

static co_abort_t read_ticks(void *ctx, const co_od_entry_t *e, uint32_t offset, uint8_t *buf,
                             uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    (void)e;
    (void)offset;
    (void)cap;
    co_put_u32(buf, ++g_ticks);
    *n = 4;
    *total = 4;
    return CO_ABORT_NONE;
}

static co_err_t count_commit(void *ctx)
{
    (void)ctx;
    g_commits++;
    return CO_OK;
}

static void count_discard(void *ctx)
{
    (void)ctx;
    g_discards++;
}

static void test_value_changing_during_a_save_fails_it(void)
{
    static const co_od_hooks_t k_ticking = {.read = read_ticks};
    static const co_storage_t k_counting = {.begin = st_begin,
                                            .write = st_write,
                                            .commit = count_commit,
                                            .read = st_read,
                                            .erase = st_erase,
                                            .discard = count_discard};
    const co_od_entry_t extra[] = {
        {0x2105, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &g_plain, NULL, NULL, &k_ticking},
    };
    CHECK_EQ(build(0, 0, extra, 1), CO_OK);
    g.t.node.cfg.storage = &k_counting;
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    g_commits = 0;
    CHECK_EQ(co_storage_save(&g.t.node, 2), CO_OK); /* the communication group is steady */
    CHECK_EQ(g_commits, 1);
    CHECK_EQ(co_storage_save(&g.t.node, 3), CO_ERR_STATE);
    CHECK_EQ(g_commits, 1);
    CHECK_EQ(g_discards, 1);
    CHECK_EQ(write_u32(&g.t, 0x1010, 3, CO_STORE_SIGNATURE), CO_ABORT_HARDWARE);
}

/* ---- streamed values */

static uint32_t g_streamed;

static co_abort_t unknown_read(void *ctx, const co_od_entry_t *e, uint32_t offset, uint8_t *buf,
                               uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    (void)e;
    if (offset >= CO_SDO_BUF_SIZE) {
        return CO_ABORT_HARDWARE; /* the source fails after the first buffer */
    }
    for (*n = 0; *n < cap; (*n)++) {
        buf[*n] = (uint8_t)(offset + *n);
    }
    *total = CO_OD_SIZE_UNKNOWN;
    return CO_ABORT_NONE;
}

static co_abort_t veto_late(void *ctx, const co_od_entry_t *e, uint32_t offset, const uint8_t *data,
                            uint32_t n, uint32_t total, bool last)
{
    (void)ctx;
    (void)e;
    (void)data;
    (void)total;
    (void)last;
    g_streamed = offset + n;
    return offset + n > 500 ? CO_ABORT_DATA_LOCAL : CO_ABORT_NONE;
}

static const co_od_hooks_t k_stream = {.read = unknown_read, .write = veto_late};

static void test_streamed_values(void)
{
    const co_od_entry_t extra[] = {
        {0x2100, 0, CO_TYPE_DOMAIN, CO_OD_RW, CO_OD_SIZE_UNKNOWN, NULL, NULL, NULL, &k_stream},
    };
    CHECK_EQ(build(0, 0, extra, 1), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    /* A local read of a value of unknown size takes what fits. */
    uint8_t buf[4];
    uint32_t len = 0;
    CHECK_EQ(co_node_read_net(&g.t.node, 0x2100, 0, buf, sizeof buf, &len), CO_ABORT_NONE);
    CHECK_EQ(len, 4);
    CHECK_EQ(buf[3], 3);
    /* A write hook's veto in the middle of a stream reaches the client. */
    ingest(&g.t, 0, 0x605, "21 00 21 00 E8 03 00 00"); /* 1000 bytes */
    uint8_t toggle = 0;
    for (int i = 0; i < 200; i++, toggle ^= 1u) {
        ingest(&g.t, 0, 0x605, toggle ? "10 00 00 00 00 00 00 00" : "00 00 00 00 00 00 00 00");
        if (g.t.bus.frames[g.t.bus.count - 1].data[0] == 0x80) {
            break;
        }
    }
    const co_frame_t *f = &g.t.bus.frames[g.t.bus.count - 1];
    CHECK_EQ(f->data[0], 0x80);
    CHECK_EQ(co_get_u32(&f->data[4]), CO_ABORT_DATA_LOCAL);
    CHECK(g_streamed > 500);
    /* A read hook that fails in the middle of a block upload: its code reaches the client. */
    ingest(&g.t, 0, 0x605, "A0 00 21 00 7F 00 00 00");
    CHECK_EQ(g.t.bus.frames[g.t.bus.count - 1].data[0], 0xC4); /* size not indicated */
    ingest(&g.t, 0, 0x605, "A3 00 00 00 00 00 00 00");
    ingest(&g.t, 0, 0x605, "A2 7F 7F 00 00 00 00 00");
    f = &g.t.bus.frames[g.t.bus.count - 1];
    CHECK_EQ(f->data[0], 0x80);
    CHECK_EQ(co_get_u32(&f->data[4]), CO_ABORT_HARDWARE);
}

/* 0x1010 sub4 (manufacturer-specific groups) is not a group this node stores. */
static void test_store_sub_index_beyond_the_groups(void)
{
    static uint32_t store4;
    const co_od_entry_t extra[] = {
        {0x1010, 4, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &store4, NULL, NULL, NULL},
    };
    CHECK_EQ(build(0, 0, extra, 1), CO_OK);
    g.t.node.cfg.storage = &k_recorder;
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(write_u32(&g.t, 0x1010, 4, CO_STORE_SIGNATURE), CO_ABORT_DATA_STORE);
}

/* Parameters of SDO channels the node does not have (one server, one client channel by
 * default) are plain values: writing them changes no channel; COB-ID values are checked. */
static void test_parameters_of_channels_the_node_lacks(void)
{
    static uint32_t srv[3] = {0x605, 0x585, 0};
    static uint32_t srv1 = 0x80000000u;
    static uint8_t cli_count = 3;
    static uint32_t cli1 = 0x80000000u;
    static uint8_t diff[6];
    const co_od_entry_t extra[] = {
        u32_entry(0x1200, 1, &srv[0]),
        u32_entry(0x1200, 2, &srv[1]),
        {0x1200, 3, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &srv[2], NULL, NULL, NULL},
        u32_entry(0x1201, 1, &srv1),
        {0x1280, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &cli_count, NULL, NULL, NULL},
        u32_entry(0x1280, 1, &g_tx),
        u32_entry(0x1280, 2, &g_rx),
        {0x1280, 3, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &g_server, NULL, NULL, NULL},
        u32_entry(0x1280, 4, &g.extra_u32[0]),
        u32_entry(0x1281, 1, &cli1),
        {0x2100, 0, CO_TYPE_TIME_DIFFERENCE, CO_OD_RW, 6, diff, NULL, NULL, NULL},
    };
    CHECK_EQ(build(0, 0, extra, sizeof extra / sizeof extra[0]), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&g.t.node, 0, 7), CO_OK);
    CHECK_EQ(write_u8(&g.t, 0x1200, 3, 9), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&g.t, 0x1201, 1, 0x80000606u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&g.t, 0x1201, 1, 0x800u), CO_ABORT_VALUE); /* not an 11-bit ID */
    CHECK_EQ(write_u8(&g.t, 0x1280, 0, 4), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&g.t, 0x1280, 4, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&g.t, 0x1281, 1, 0x609), CO_ABORT_NONE);
    /* The server still answers on 0x605, the client still talks to node 7. */
    fake_clear(&g.t.bus);
    ingest(&g.t, 0, 0x605, "40 00 10 00 00 00 00 00");
    CHECK_EQ(fake_count_id(&g.t.bus, 0x585), 1);
    uint8_t buf[4];
    sdo_result_t r = {0};
    CHECK_EQ(co_sdo_upload(&g.t.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, 4, sdo_result_done, &r),
             CO_OK);
    CHECK_EQ(fake_count_id(&g.t.bus, 0x607), 1);
    /* A TIME_DIFFERENCE is not read as an integer, nor set as one. */
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&g.t.node, 0x2100, 0, &v), CO_ERR_ARG);
    diff[0] = 0x5A;
    CHECK_EQ(co_node_set_uint(&g.t.node, 0x2100, 0, 1), CO_ABORT_TYPE_MISMATCH);
    CHECK_EQ(diff[0], 0x5A);
}

/* The default SDO server's COB-IDs are fixed (CiA 301): a dictionary (a DCF such as
 * OreSat's battery card's) that sets 0x1200 sub1/sub2 to 0x80000000, not valid, does not
 * silence the node. It serves on 0x605/0x585, 0x1200 reads so, the application hears of
 * the deviation at each reset communication, and other values cannot be written. */
static void test_default_sdo_server_cob_ids_are_fixed(void)
{
    static const uint8_t two = 2;
    static const uint32_t invalid = 0x80000000u;
    static uint8_t count;
    static uint32_t cob[2];
    const co_od_entry_t extra[] = {
        {0x1200, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, &count, &two, NULL, NULL},
        {0x1200, 1, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &cob[0], &invalid, NULL, NULL},
        {0x1200, 2, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &cob[1], &invalid, NULL, NULL},
    };
    CHECK_EQ(build(0, 0, extra, 3), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(g.t.error_count, 1);
    CHECK_EQ(g.t.errors[0], CO_NODE_ERR_SDO_COB_FIXED);
    CHECK_EQ(cob[0], 0x605u);
    CHECK_EQ(cob[1], 0x585u);
    fake_clear(&g.t.bus);
    ingest(&g.t, 0, 0x605, "40 00 12 01 00 00 00 00"); /* upload 0x1200 sub1 */
    char dump[128];
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "585#4300120105060000");
    /* Read-only in CiA 301, whatever the dictionary says: only the fixed value goes in. */
    CHECK_EQ(write_u32(&g.t, 0x1200, 1, 0x80000605u), CO_ABORT_READ_ONLY);
    CHECK_EQ(write_u32(&g.t, 0x1200, 2, 0x586u), CO_ABORT_READ_ONLY);
    CHECK_EQ(co_node_set_uint(&g.t.node, 0x1200, 1, 0x606u), CO_ABORT_READ_ONLY);
    CHECK_EQ(write_u32(&g.t, 0x1200, 1, 0x605u), CO_ABORT_NONE);
    CHECK_EQ(cob[0], 0x605u);
    /* Reset communication loads the dictionary's values again, and overrules them again. */
    co_nmt_apply(&g.t.node, CO_NMT_CMD_RESET_COMMUNICATION);
    CHECK_EQ(g.t.error_count, 2);
    fake_clear(&g.t.bus);
    ingest(&g.t, 0, 0x605, "40 00 10 00 00 00 00 00");
    CHECK_EQ(fake_count_id(&g.t.bus, 0x585), 1);
}

/* A dictionary that gives the fixed COB-IDs (or none) is no deviation: nothing reported. */
static void test_default_sdo_server_as_cia_301_says_is_quiet(void)
{
    static const uint32_t rx = 0x605u;
    static const uint32_t tx = 0x585u;
    static uint32_t cob[2];
    const co_od_entry_t extra[] = {
        {0x1200, 1, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, &cob[0], &rx, NULL, NULL},
        {0x1200, 2, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, &cob[1], &tx, NULL, NULL},
    };
    CHECK_EQ(build(0, 0, extra, 2), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(g.t.error_count, 0);
    CHECK_EQ(build(0, 0, NULL, 0), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(g.t.error_count, 0);
}

/* ---- EMCY without an error history, and more consumer entries than the node binds */

static co_emcy_msg_t g_emcy[4];
static uint32_t g_emcy_count;

static void rec_emcy(void *user, const co_emcy_msg_t *msg)
{
    (void)user;
    if (g_emcy_count < 4) {
        g_emcy[g_emcy_count] = *msg;
    }
    g_emcy_count++;
}

static void test_emcy_without_error_history(void)
{
    CHECK_EQ(build(0, 0x1003, NULL, 0), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    fake_clear(&g.t.bus);
    /* Nothing to record in, but the error is active, registered and sent. */
    CHECK_EQ(co_emcy_raise(&g.t.node, 0x4210, NULL), CO_OK);
    CHECK(co_emcy_active(&g.t.node, 0x4210));
    CHECK_EQ(g.t.od.error_register, 0x09);
    CHECK_EQ(g.t.od.error_count, 0);
    CHECK_EQ(g.t.od.error_history[0], 0);
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&g.t.node, 0x1003, 0, &v), CO_ERR_NOT_FOUND);
    CHECK_EQ(co_emcy_clear(&g.t.node, 0x4210), CO_OK);
    char dump[128];
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "085#1042090000000000 085#0000000000000000");
}

static void test_more_emcy_consumer_entries_than_the_node_binds(void)
{
    /* 0x1028 sub5..sub(CO_EMCY_CONSUMERS_MAX + 1) next to the example's sub1..4. */
    co_od_entry_t extra[CO_EMCY_CONSUMERS_MAX];
    uint32_t n = 0;
    for (uint8_t sub = EXAMPLE_EMCY_CONSUMERS + 1; sub <= CO_EMCY_CONSUMERS_MAX + 1; sub++) {
        g.extra_u32[n] = 0x80000000u;
        extra[n] = u32_entry(0x1028, sub, &g.extra_u32[n]);
        n++;
    }
    CHECK_EQ(build(0, 0, extra, n), CO_OK);
    for (uint32_t i = 0; i < n; i++) {
        g.extra_u32[i] = 0x80000000u; /* no default: unused from the start */
    }
    g.t.node.cfg.on_emcy = rec_emcy;
    g_emcy_count = 0;
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(g.t.node.emcy.consumer_count, CO_EMCY_CONSUMERS_MAX);
    /* The last bound entry consumes; the one past it is a plain value. */
    CHECK_EQ(write_u32(&g.t, 0x1028, CO_EMCY_CONSUMERS_MAX, 0x0A1), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&g.t, 0x1028, CO_EMCY_CONSUMERS_MAX + 1, 0x0A2), CO_ABORT_NONE);
    co_frame_t bound = frm(0x0A1, "30 81 11 00 00 00 00 00");
    co_frame_t past = frm(0x0A2, "30 81 11 00 00 00 00 00");
    CHECK(co_node_accepts(&g.t.node, &bound));
    CHECK(!co_node_accepts(&g.t.node, &past));
    co_node_ingest(&g.t.node, 1 * MS, &past);
    CHECK_EQ(g_emcy_count, 0);
    co_node_ingest(&g.t.node, 2 * MS, &bound);
    CHECK_EQ(g_emcy_count, 1);
    CHECK_EQ(g_emcy[0].cob_id, 0x0A1);
    CHECK_EQ(g_emcy[0].code, 0x8130);
    /* A COB-ID whose identifier is not of its format (bits 11..28 of an 11-bit one) is
     * refused at every sub-index, bound or not, below 7 and above (node_od.c). */
    CHECK_EQ(write_u32(&g.t, 0x1028, 1, 0x8A1u), CO_ABORT_VALUE);
    CHECK_EQ(write_u32(&g.t, 0x1028, CO_EMCY_CONSUMERS_MAX + 1, 0x8A2u), CO_ABORT_VALUE);
    CHECK_EQ(g.extra_u32[n - 1], 0x0A2u); /* unchanged */
}

/* ---- PDO parameters: a gap, more than the node has, more mapping entries than allowed */

static void test_tpdo_parameters_with_a_gap(void)
{
    CHECK_EQ(build(0, 0x1801, NULL, 0), CO_OK); /* no TPDO2 communication parameters */
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(co_nmt_apply(&g.t.node, CO_NMT_CMD_START), CO_OK);
    fake_clear(&g.t.bus);
    CHECK_EQ(co_tpdo_request(&g.t.node, 1), CO_ERR_ARG);   /* not there at all */
    CHECK_EQ(co_tpdo_request(&g.t.node, 2), CO_ERR_STATE); /* there, mapping nothing */
    CHECK_EQ(co_tpdo_request(&g.t.node, 0), CO_OK);
    char dump[64];
    CHECK_STR(fake_dump(&g.t.bus, dump, sizeof dump), "185#78563412");
}

static void test_pdo_parameters_beyond_the_pdos_the_node_has(void)
{
    static uint32_t rcob = 0x80000000u, tcob = 0x80000000u;
    const co_od_entry_t extra[] = {
        u32_entry((uint16_t)(0x1400 + CO_RPDO_MAX), 1, &rcob),
        u32_entry((uint16_t)(0x1800 + CO_TPDO_MAX), 1, &tcob),
    };
    CHECK_EQ(build(0, 0, extra, 2), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(co_nmt_apply(&g.t.node, CO_NMT_CMD_START), CO_OK);
    /* Plain values: written, but no PDO of the node takes them. */
    CHECK_EQ(write_u32(&g.t, (uint16_t)(0x1400 + CO_RPDO_MAX), 1, 0x606), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&g.t, (uint16_t)(0x1800 + CO_TPDO_MAX), 1, 0x586), CO_ABORT_NONE);
    CHECK_EQ(rcob, 0x606);
    CHECK_EQ(tcob, 0x586);
    co_frame_t f = frm(0x606, "01");
    CHECK(!co_node_accepts(&g.t.node, &f));
    CHECK_EQ(co_tpdo_request(&g.t.node, CO_TPDO_MAX), CO_ERR_ARG);
}

static void test_more_mapping_entries_than_a_pdo_takes(void)
{
    static uint32_t ninth = 0x62000108u;
    const co_od_entry_t extra[] = {u32_entry(0x1600, CO_PDO_MAP_MAX + 1, &ninth)};
    CHECK_EQ(build(0, 0, extra, 1), CO_OK);
    CHECK_EQ(co_node_start(&g.t.node, 0), CO_OK);
    CHECK_EQ(write_u32(&g.t, 0x1400, 1, 0x80000205u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&g.t, 0x1600, 0, 0), CO_ABORT_NONE);
    /* The entry exists, but a PDO takes CO_PDO_MAP_MAX entries at most. */
    CHECK_EQ(write_u8(&g.t, 0x1600, 0, CO_PDO_MAP_MAX + 1), CO_ABORT_MAP_LEN);
    CHECK_EQ(write_u8(&g.t, 0x1600, 0, CO_PDO_MAP_MAX + 2), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(g.t.od.rpdo[0].map_count, 0);
}

int main(void)
{
    RUN(test_more_consumer_entries_than_the_node_watches);
    RUN(test_boot_time_without_consumers);
    RUN(test_client_parameters_in_the_dictionary);
    RUN(test_incomplete_client_parameters_are_ignored);
    RUN(test_save_records_parameters_only);
    RUN(test_value_changing_during_a_save_fails_it);
    RUN(test_streamed_values);
    RUN(test_store_sub_index_beyond_the_groups);
    RUN(test_parameters_of_channels_the_node_lacks);
    RUN(test_default_sdo_server_cob_ids_are_fixed);
    RUN(test_default_sdo_server_as_cia_301_says_is_quiet);
    RUN(test_emcy_without_error_history);
    RUN(test_more_emcy_consumer_entries_than_the_node_binds);
    RUN(test_tpdo_parameters_with_a_gap);
    RUN(test_pdo_parameters_beyond_the_pdos_the_node_has);
    RUN(test_more_mapping_entries_than_a_pdo_takes);
    return check_summary();
}
