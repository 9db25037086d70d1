/* SPDX-License-Identifier: Apache-2.0 */
/* test_node.c -- node lifecycle, transmit queue, receive routes, OD access through the node. */
#include "check.h"
#include "harness.h"
#include "kernel.h" /* the routes */

#define MS 1000ull

static char dump[4096];

static void test_init_rejects_bad_config(void)
{
    test_node_t t;
    CHECK_EQ(test_node_init(&t, 0, 0), CO_ERR_ARG);
    CHECK_EQ(test_node_init(&t, 128, 0), CO_ERR_ARG);
    CHECK_EQ(test_node_init(&t, 127, 0), CO_OK);
    CHECK_EQ(test_node_init(&t, 1, 0), CO_OK);
    CHECK_EQ(co_node_init(NULL, &t.cfg), CO_ERR_ARG);
    CHECK_EQ(co_node_init(&t.node, NULL), CO_ERR_ARG);
    co_node_config_t cfg = t.cfg;
    cfg.driver.tx = NULL;
    CHECK_EQ(co_node_init(&t.node, &cfg), CO_ERR_ARG);
    /* An unsorted dictionary is a configuration error. */
    co_od_entry_t swapped = t.od.entries[0];
    t.od.entries[0] = t.od.entries[1];
    t.od.entries[1] = swapped;
    CHECK_EQ(co_node_init(&t.node, &t.cfg), CO_ERR_CONFIG);
}

static void test_poll_before_start_and_when_idle(void)
{
    test_node_t t;
    test_node_init(&t, 3, 0);
    CHECK_EQ(co_node_poll(&t.node, 0), CO_TIME_NEVER);
    co_frame_t nmt = frm(0x000, "01 03");
    co_node_ingest(&t.node, 0, &nmt); /* a node not started listens to nothing */
    CHECK_EQ(co_node_stats(&t.node)->rx_unrouted, 1);
    CHECK_EQ(t.bus.count, 0);
    /* The application's own frame, left waiting by a busy driver before the start: poll
     * hands it over, and runs no service. */
    t.bus.busy = true;
    co_frame_t own = frm(0x123, "AA");
    CHECK_EQ(co_node_send(&t.node, &own), CO_OK);
    CHECK_EQ(t.bus.count, 0);
    t.bus.busy = false;
    CHECK_EQ(co_node_poll(&t.node, 0), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 1);
    CHECK_EQ(t.bus.frames[0].id, 0x123);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_INITIALISING);
    co_node_start(&t.node, 0);
    CHECK_EQ(co_node_poll(&t.node, 1), CO_TIME_NEVER);
    CHECK_EQ(co_node_poll(&t.node, 2), CO_TIME_NEVER);
}

static void test_busy_driver_queues_and_poll_sends_by_priority(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    t.bus.busy = true;
    co_frame_t a = frm(0x700, "01");
    co_frame_t b = frm(0x080, "02");
    co_frame_t c = frm(0x700, "03");
    co_frame_t d = frm(0x000, "04");
    co_frame_t ext = frm(0x00100000, "05"); /* 29-bit, base ID 0x004 */
    co_frame_t std4 = frm(0x004, "06");
    CHECK_EQ(co_node_send(&t.node, &a), CO_OK);
    CHECK_EQ(co_node_send(&t.node, &b), CO_OK);
    CHECK_EQ(co_node_send(&t.node, &c), CO_OK);
    CHECK_EQ(co_node_send(&t.node, &d), CO_OK);
    CHECK_EQ(co_node_send(&t.node, &ext), CO_OK);
    CHECK_EQ(co_node_send(&t.node, &std4), CO_OK);
    CHECK_EQ(t.bus.count, 0);
    CHECK_EQ(co_node_stats(&t.node)->tx_queued, 6);
    /* Still busy: poll keeps them. */
    co_node_poll(&t.node, 1);
    CHECK_EQ(t.bus.count, 0);
    t.bus.busy = false;
    co_node_poll(&t.node, 2);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump),
              "000#04 004#06 00100000#05 080#02 700#01 700#03");
    CHECK_EQ(co_node_stats(&t.node)->tx_frames, 7); /* with the boot-up */
}

static void test_queue_overflow_is_counted_and_reported(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    t.bus.busy = true;
    co_frame_t f = frm(0x181, "00");
    for (int i = 0; i < CO_TX_QUEUE_LEN; i++) {
        CHECK_EQ(co_node_send(&t.node, &f), CO_OK);
    }
    CHECK_EQ(co_node_send(&t.node, &f), CO_ERR_FULL);
    CHECK_EQ(co_node_stats(&t.node)->tx_overflow, 1);
    CHECK_EQ(t.error_count, 1);
    CHECK_EQ(t.errors[0], CO_NODE_ERR_TX_OVERFLOW);
}

static co_err_t failing_tx(void *ctx, const co_frame_t *frame)
{
    (void)ctx;
    (void)frame;
    return CO_ERR_ARG;
}

static void test_driver_error_drops_frame(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    t.node.cfg.driver.tx = failing_tx;
    co_node_start(&t.node, 0);
    CHECK_EQ(co_node_stats(&t.node)->tx_dropped, 1); /* the boot-up */
    CHECK_EQ(t.errors[0], CO_NODE_ERR_TX_DRIVER);
    CHECK_EQ(t.node.txq_count, 0);
}

static void test_routes_and_acceptance(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    co_frame_t nmt = frm(0x000, "01 05");
    co_frame_t guard = frm(0x705, "R1");
    co_frame_t sdo = frm(0x605, "40 00 10 00 00 00 00 00");
    co_frame_t pdo = frm(0x185, "00");
    co_frame_t ext = frm(0x00000705 | 0x10000000, "00");
    CHECK(co_node_accepts(&t.node, &nmt));
    CHECK(co_node_accepts(&t.node, &guard));
    CHECK(co_node_accepts(&t.node, &sdo));
    CHECK(!co_node_accepts(&t.node, &pdo)); /* TPDO1 (type 255) takes no RTR: no route */
    CHECK(!co_node_accepts(&t.node, &ext));
    /* NMT, SYNC (0x1005), TIME (0x1012 consumes), RPDO1 (the only PDO that maps
     * something), the SDO server, guarding, LSS requests: sorted. */
    CHECK_EQ(co_node_route_count(&t.node), 7);
    CHECK_EQ(co_node_route_id(&t.node, 0), 0x000);
    CHECK_EQ(co_node_route_id(&t.node, 1), 0x080);
    CHECK_EQ(co_node_route_id(&t.node, 2), 0x100);
    CHECK_EQ(co_node_route_id(&t.node, 3), 0x205);
    CHECK_EQ(co_node_route_id(&t.node, 4), 0x605);
    CHECK_EQ(co_node_route_id(&t.node, 5), 0x705);
    CHECK_EQ(co_node_route_id(&t.node, 6), 0x7E5);
    CHECK(t.bus.routes_changed >= 1);
    co_node_ingest(&t.node, 1, &pdo);
    CHECK_EQ(co_node_stats(&t.node)->rx_unrouted, 1);
    co_frame_t too_long = nmt;
    too_long.len = 9;
    co_node_ingest(&t.node, 1, &too_long);
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 1);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
}

/* A COB-ID with two owners (a configuration may make one): both routes are kept and listed,
 * the one of the lower kind (src/kernel.h orders them: TIME before the PDOs) takes the
 * frames, whichever was set first, and the other takes over while it is gone. */
static void test_two_owners_of_one_cob_id(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    co_nmt_apply(&t.node, CO_NMT_CMD_START);
    CHECK_EQ(write_u32(&t, 0x1400, 1, 0x80000205u), CO_ABORT_NONE); /* RPDO1 off, then moved */
    CHECK_EQ(write_u32(&t, 0x1400, 1, 0x100u), CO_ABORT_NONE);      /* onto TIME's 0x100 */
    CHECK_EQ(co_node_route_count(&t.node), 7);
    uint32_t listed = 0;
    for (uint32_t i = 0; i < 7; i++) {
        listed += co_node_route_id(&t.node, i) == 0x100;
    }
    CHECK_EQ(listed, 2);
    ingest(&t, 1, 0x100, "11 22 33 44"); /* to TIME, for which 4 bytes are malformed */
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 1);
    CHECK_EQ(t.od.outputs[0], 0);

    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x100u), CO_ABORT_NONE); /* TIME stops consuming */
    CHECK_EQ(co_node_route_count(&t.node), 6);
    ingest(&t, 2, 0x100, "11 22 33 44");
    CHECK_EQ(t.od.outputs[0], 0x11);
    CHECK_EQ(t.od.outputs[3], 0x44);

    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x80000100u), CO_ABORT_NONE); /* and starts again */
    ingest(&t, 3, 0x100, "55 66 77 88");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 2);
    CHECK_EQ(t.od.outputs[0], 0x11);

    CHECK_EQ(write_u32(&t, 0x1400, 1, 0x80000100u), CO_ABORT_NONE); /* the waiting one goes */
    CHECK_EQ(co_node_route_count(&t.node), 6);
    ingest(&t, 4, 0x100, "55 66 77 88");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 3);
    CHECK_EQ(t.od.outputs[0], 0x11);
}

/* The routes' own order: the owners of one key, set in any order, are ranked by kind, then
 * slot; the first takes the frames, the next takes over when it goes or moves, and the
 * table stays sorted by key for the search. */
static bool routes_sorted(const co_node_t *node)
{
    for (uint32_t i = 1; i < node->route_count; i++) {
        if (node->route_keys[i - 1] > node->route_keys[i]) {
            return false;
        }
    }
    return true;
}

static bool owner_is(const co_node_t *node, uint32_t key, uint8_t kind, uint8_t slot)
{
    uint16_t i = co_routes_find(node, key);
    return i < node->route_count && node->route_kind[i] == kind && node->route_slot[i] == slot;
}

static void test_route_owners_ranked_by_kind_then_slot(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    uint32_t count = co_node_route_count(&t.node);
    co_route_set(&t.node, CO_ROUTE_MGR_BOOTUP, 7, 0x123);
    co_route_set(&t.node, CO_ROUTE_MGR_BOOTUP, 3, 0x123); /* a lower slot, set later */
    CHECK(owner_is(&t.node, 0x123, CO_ROUTE_MGR_BOOTUP, 3));
    co_route_set(&t.node, CO_ROUTE_SYNC, 1, 0x123); /* a lower kind */
    CHECK(owner_is(&t.node, 0x123, CO_ROUTE_SYNC, 1));
    CHECK_EQ(co_node_route_count(&t.node), count + 3);
    uint32_t listed = 0;
    for (uint32_t i = 0; i < count + 3; i++) {
        listed += co_node_route_id(&t.node, i) == 0x123;
    }
    CHECK_EQ(listed, 3);
    CHECK(routes_sorted(&t.node));

    co_route_set(&t.node, CO_ROUTE_SYNC, 1, CO_ROUTE_OFF);
    CHECK(owner_is(&t.node, 0x123, CO_ROUTE_MGR_BOOTUP, 3));
    co_route_set(&t.node, CO_ROUTE_MGR_BOOTUP, 3, 0x124); /* moves: alone on its new key */
    CHECK(owner_is(&t.node, 0x123, CO_ROUTE_MGR_BOOTUP, 7));
    CHECK(owner_is(&t.node, 0x124, CO_ROUTE_MGR_BOOTUP, 3));
    CHECK(routes_sorted(&t.node));
    co_route_set(&t.node, CO_ROUTE_MGR_BOOTUP, 7, CO_ROUTE_OFF);
    CHECK_EQ(co_routes_find(&t.node, 0x123), t.node.route_count);
    CHECK_EQ(co_node_route_count(&t.node), count + 1);
    CHECK(routes_sorted(&t.node));
}

/* co_node_write_app: no access rights, everything else of a network write (length, limits,
 * the services' checks and effects). */
static void test_app_write_through_node(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    uint8_t reg = 0x11;
    CHECK_EQ(co_node_write_app(&t.node, 0x1001, 0, &reg, 1), CO_ABORT_NONE); /* read-only */
    CHECK_EQ(t.od.error_register, 0x11);
    uint8_t v4[4] = {1, 2, 3, 4};
    CHECK_EQ(co_node_write_app(&t.node, 0x2000, 0, v4, 3), CO_ABORT_LEN_LOW);
    CHECK_EQ(co_node_write_app(&t.node, 0x2000, 0, v4, 4), CO_ABORT_NONE);
    CHECK_EQ(t.od.app_u32, 0x04030201);
    uint8_t i16[2];
    co_put_u16(i16, (uint16_t)101);
    CHECK_EQ(co_node_write_app(&t.node, 0x2001, 0, i16, 2), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(co_node_write_app(&t.node, 0x2FFF, 0, v4, 4), CO_ABORT_NO_OBJECT);
    CHECK_EQ(co_node_write_app(&t.node, 0x1000, 7, v4, 4), CO_ABORT_NO_SUB);
    uint8_t period[2] = {0xE8, 0x03}; /* 0x1017 = 1000 ms: the producer takes it at once */
    CHECK_EQ(co_node_write_app(&t.node, 0x1017, 0, period, 2), CO_ABORT_NONE);
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&t.node, 0x1017, 0, &v), CO_OK);
    CHECK_EQ(v, 1000);
    CHECK(co_node_poll(&t.node, 1) <= 1000 * 1000u);
}

static void test_od_access_through_node(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    uint8_t buf[32];
    uint32_t len = 0;
    CHECK_EQ(co_node_read_net(&t.node, 0x1000, 0, buf, sizeof buf, &len), CO_ABORT_NONE);
    CHECK_EQ(len, 4);
    CHECK_EQ(co_get_u32(buf), 0x191);
    CHECK_EQ(co_node_read_net(&t.node, 0x1234, 0, buf, sizeof buf, &len), CO_ABORT_NO_OBJECT);
    CHECK_EQ(co_node_read_net(&t.node, 0x1000, 1, buf, sizeof buf, &len), CO_ABORT_NO_SUB);
    CHECK_EQ(co_node_read_net(&t.node, 0x2004, 0, buf, sizeof buf, &len), CO_ABORT_WRITE_ONLY);
    CHECK_EQ(co_node_read_net(&t.node, 0x1008, 0, buf, sizeof buf, &len), CO_ABORT_NONE);
    CHECK_EQ(len, 14);
    CHECK(memcmp(buf, "canola example", 14) == 0);
    CHECK_EQ(co_node_read_net(&t.node, 0x1008, 0, buf, 4, &len), CO_ABORT_LEN_HIGH);
    uint8_t v4[4] = {1, 2, 3, 4};
    CHECK_EQ(co_node_write_net(&t.node, 0x1000, 0, v4, 4), CO_ABORT_READ_ONLY);
    CHECK_EQ(co_node_write_net(&t.node, 0x1008, 0, v4, 4), CO_ABORT_READ_ONLY);
    CHECK_EQ(co_node_write_net(&t.node, 0x2000, 0, v4, 3), CO_ABORT_LEN_LOW);
    CHECK_EQ(co_node_write_net(&t.node, 0x2000, 0, v4, 5), CO_ABORT_LEN_HIGH);
    CHECK_EQ(co_node_write_net(&t.node, 0x2000, 0, v4, 4), CO_ABORT_NONE);
    CHECK_EQ(t.od.app_u32, 0x04030201);
    uint8_t i16[2];
    co_put_u16(i16, (uint16_t)101);
    CHECK_EQ(co_node_write_net(&t.node, 0x2001, 0, i16, 2), CO_ABORT_VALUE_HIGH);
    co_put_u16(i16, (uint16_t)-101);
    CHECK_EQ(co_node_write_net(&t.node, 0x2001, 0, i16, 2), CO_ABORT_VALUE_LOW);
    co_put_u16(i16, (uint16_t)-100);
    CHECK_EQ(co_node_write_net(&t.node, 0x2001, 0, i16, 2), CO_ABORT_NONE);
    CHECK_EQ(t.od.app_i16, -100);
    /* The application may write what the network may not. */
    CHECK_EQ(co_node_set_uint(&t.node, 0x1001, 0, 0x11), CO_ABORT_NONE);
    CHECK_EQ(t.od.error_register, 0x11);
    uint64_t v = 0;
    CHECK_EQ(co_node_get_uint(&t.node, 0x1001, 0, &v), CO_OK);
    CHECK_EQ(v, 0x11);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2002, 0, 1), CO_ABORT_TYPE_MISMATCH);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2001, 0, 500), CO_ABORT_VALUE_HIGH);
    /* An integer is no REAL32; entries that do not exist are named as such. */
    float real_before = t.od.app_real;
    CHECK_EQ(co_node_set_uint(&t.node, 0x2006, 0, 1), CO_ABORT_TYPE_MISMATCH);
    CHECK(memcmp(&t.od.app_real, &real_before, sizeof real_before) == 0);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2FFF, 0, 1), CO_ABORT_NO_OBJECT);
    CHECK_EQ(co_node_set_uint(&t.node, 0x1000, 7, 1), CO_ABORT_NO_SUB);
}

/* ---- edges: the documented answers to inputs seldom seen */

static co_err_t no_tx(void *ctx, const co_frame_t *f)
{
    (void)ctx;
    (void)f;
    return CO_OK;
}

static co_err_t busy_tx(void *ctx, const co_frame_t *f)
{
    (void)ctx;
    (void)f;
    return CO_ERR_BUSY;
}

static int g_sent;
static co_err_t counting_tx(void *ctx, const co_frame_t *f)
{
    (void)ctx;
    (void)f;
    g_sent++;
    return CO_OK;
}

static void test_node_init_arguments(void)
{
    static example_od_t od;
    static co_node_t node;
    co_node_config_t cfg = {.node_id = 5, .od = example_od_init(&od, 0)};
    CHECK_EQ(co_node_init(&node, &cfg), CO_ERR_ARG); /* no tx */
    cfg.driver.tx = no_tx;
    CHECK_EQ(co_node_init(NULL, &cfg), CO_ERR_ARG);
    CHECK_EQ(co_node_init(&node, NULL), CO_ERR_ARG);
    co_node_config_t no_od = cfg;
    no_od.od.entries = NULL;
    CHECK_EQ(co_node_init(&node, &no_od), CO_ERR_ARG);
    cfg.node_id = 0;
    CHECK_EQ(co_node_init(&node, &cfg), CO_ERR_ARG);
    cfg.node_id = 5;
    CHECK_EQ(co_node_init(&node, &cfg), CO_OK);
    /* Nothing runs before start. */
    CHECK_EQ(co_node_poll(&node, 10 * MS), CO_TIME_NEVER);
}

static void test_local_reads_of_the_wrong_kind(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    uint64_t v = 7;
    CHECK_EQ(co_node_get_uint(&t.node, 0x2FFF, 0, &v), CO_ERR_NOT_FOUND);
    CHECK_EQ(co_node_get_uint(&t.node, 0x2006, 0, &v), CO_ERR_ARG); /* REAL32 */
    CHECK_EQ(co_node_get_uint(&t.node, 0x2002, 0, &v), CO_ERR_ARG); /* a string */
    CHECK_EQ(v, 7);
    /* A network read into a buffer too small for the value. */
    uint8_t buf[2];
    uint32_t len = 0;
    CHECK_EQ(co_node_read_net(&t.node, 0x2000, 0, buf, sizeof buf, &len), CO_ABORT_LEN_HIGH);
}

static void test_queue_overflow_and_driver_errors_without_callback(void)
{
    static example_od_t od;
    static co_node_t node;
    co_node_config_t cfg = {.node_id = 5, .od = example_od_init(&od, 0)};
    cfg.driver.tx = busy_tx;
    CHECK_EQ(co_node_init(&node, &cfg), CO_OK);
    co_node_start(&node, 0); /* the boot-up waits */
    co_frame_t f = {.id = 0x300, .len = 1};
    for (int i = 0; i < CO_TX_QUEUE_LEN; i++) {
        co_node_send(&node, &f);
    }
    CHECK_EQ(co_node_stats(&node)->tx_overflow, 1);
    cfg.driver.tx = failing_tx;
    CHECK_EQ(co_node_init(&node, &cfg), CO_OK);
    co_node_start(&node, 0);
    CHECK_EQ(co_node_stats(&node)->tx_dropped, 1);
    /* An SDO answer the driver refuses for good is dropped as well, not queued. */
    co_frame_t read = {.id = 0x605, .len = 8, .data = {0x40, 0x00, 0x10, 0x00}};
    co_node_ingest(&node, 0, &read);
    CHECK_EQ(co_node_stats(&node)->tx_dropped, 2);
    CHECK_EQ(co_node_stats(&node)->tx_queued, 0);
    /* The application's own frames carry no service: a state change does not purge them,
     * while a service's frame the new state forbids is dropped. */
    cfg.driver.tx = busy_tx;
    CHECK_EQ(co_node_init(&node, &cfg), CO_OK);
    co_node_start(&node, 0);
    co_node_send(&node, &f);
    co_frame_t req = {.id = 0x605, .len = 8, .data = {0x40, 0x00, 0x10, 0x00}};
    co_node_ingest(&node, 0, &req); /* its SDO response waits in the queue */
    co_nmt_apply(&node, CO_NMT_CMD_STOP);
    CHECK_EQ(co_node_stats(&node)->tx_gated, 1);
    node.cfg.driver.tx = counting_tx;
    g_sent = 0;
    co_node_poll(&node, 1 * MS);
    CHECK_EQ(g_sent, 2); /* the boot-up and the application's frame, not the SDO answer */
}

/* An 11-bit frame whose identifier does not fit 11 bits is malformed, not a match for a
 * 29-bit route or anything else. */
static void test_standard_frame_with_an_oversized_id_is_malformed(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    co_frame_t bad = frm(0x000, "01 05");
    bad.id = 0x80000000u; /* no CO_FRAME_EXT */
    co_node_ingest(&t.node, 1, &bad);
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 1);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_PRE_OPERATIONAL);
}

int main(void)
{
    RUN(test_init_rejects_bad_config);
    RUN(test_app_write_through_node);
    RUN(test_poll_before_start_and_when_idle);
    RUN(test_busy_driver_queues_and_poll_sends_by_priority);
    RUN(test_queue_overflow_is_counted_and_reported);
    RUN(test_driver_error_drops_frame);
    RUN(test_routes_and_acceptance);
    RUN(test_two_owners_of_one_cob_id);
    RUN(test_route_owners_ranked_by_kind_then_slot);
    RUN(test_od_access_through_node);
    RUN(test_node_init_arguments);
    RUN(test_local_reads_of_the_wrong_kind);
    RUN(test_queue_overflow_and_driver_errors_without_callback);
    RUN(test_standard_frame_with_an_oversized_id_is_malformed);
    return check_summary();
}
