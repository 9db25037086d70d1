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

typedef struct result {
    int calls;
    co_abort_t abort;
} result_t;

static void on_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    (void)len;
    result_t *r = ctx;
    r->calls++;
    r->abort = abort;
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
    result_t r = {0};
    fake_clear(&g.t.bus);
    CHECK_EQ(co_sdo_upload(&g.t.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, 4, on_done, &r), CO_OK);
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
    CHECK_EQ(co_sdo_upload(&g.t.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, 4, on_done, &r), CO_OK);
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
    result_t r = {0};
    fake_clear(&g.t.bus);
    CHECK_EQ(co_sdo_upload(&g.t.node, 0, 0x1000, 0, CO_SDO_AUTO, buf, 4, on_done, &r), CO_OK);
    CHECK_EQ(fake_count_id(&g.t.bus, 0x607), 1);
}

int main(void)
{
    RUN(test_more_consumer_entries_than_the_node_watches);
    RUN(test_boot_time_without_consumers);
    RUN(test_client_parameters_in_the_dictionary);
    RUN(test_incomplete_client_parameters_are_ignored);
    return check_summary();
}
