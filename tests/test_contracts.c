/* test_contracts.c -- the documented answers of the node's API and services to the inputs
 * they rarely see: bad arguments, frames of the wrong form on a watched COB-ID, requests at
 * the edges of the SDO block protocol, entries of the wrong type. */
#include "check.h"
#include "harness.h"

#define MS 1000ull

static co_err_t no_tx(void *ctx, const co_frame_t *f)
{
    (void)ctx;
    (void)f;
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

/* ---- node guarding, master side */

static void test_guard_watch_limits_and_replies(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    /* One error control per node: a node consumed by heartbeat is not guarded too. */
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(9, 500)), CO_ABORT_NONE);
    CHECK_EQ(co_guard_watch(&t.node, 9, 100, 3), CO_ERR_STATE);
    CHECK_EQ(co_guard_watch(&t.node, 9, 0, 0), CO_OK); /* removing what is not there */
    for (uint8_t id = 10; id < 10 + CO_GUARD_WATCH_MAX; id++) {
        CHECK_EQ(co_guard_watch(&t.node, id, 100, 3), CO_OK);
    }
    CHECK_EQ(co_guard_watch(&t.node, 100, 100, 3), CO_ERR_FULL);
    CHECK_EQ(co_guard_watch(&t.node, 100, 0, 0), CO_OK);
    t.event_count = 0;
    /* Replies of node 10: a wrong length is malformed, another master's RTR is ignored. */
    uint32_t malformed = co_node_stats(&t.node)->rx_malformed;
    ingest(&t, 1 * MS, 0x70A, "05 00");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, malformed + 1);
    ingest(&t, 1 * MS, 0x70A, "R1");
    CHECK_EQ(t.event_count, 0);
    /* First reply: started; a change of state is reported; a boot-up restarts the toggle. */
    ingest(&t, 2 * MS, 0x70A, "7F");
    ingest(&t, 3 * MS, 0x70A, "85");
    ingest(&t, 4 * MS, 0x70A, "00");
    ingest(&t, 5 * MS, 0x70A, "FF"); /* any toggle is taken after a boot-up */
    CHECK_EQ(t.event_count, 4);
    CHECK_EQ(t.events[0].kind, CO_EC_STARTED);
    CHECK_EQ(t.events[1].kind, CO_EC_STATE_CHANGED);
    CHECK_EQ(t.events[1].state, CO_NMT_OPERATIONAL);
    CHECK_EQ(t.events[2].kind, CO_EC_BOOT);
    CHECK_EQ(t.events[3].kind, CO_EC_STATE_CHANGED);
    CHECK_EQ(t.events[3].previous, CO_NMT_INITIALISING);
}

/* ---- heartbeat */

static void test_unconfigured_node_sends_no_heartbeat(void)
{
    test_node_t t;
    CHECK_EQ(test_node_init(&t, CO_NODE_ID_UNCONFIGURED, 100), CO_OK);
    co_node_start(&t.node, 0);
    co_node_poll(&t.node, 1000 * MS);
    CHECK_EQ(t.bus.count, 0);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_INITIALISING);
    CHECK_EQ(co_hb_remote_state(&t.node, 9), 0xFF); /* not consumed */
}

/* ---- EMCY consumer */

static void test_emcy_consumer_without_callback_or_with_bad_frames(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u32(&t, 0x1028, 1, 0x85), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x085, "10 81 11 00 00 00 00 00"); /* no on_emcy: dropped */
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 0);
    ingest(&t, 1 * MS, 0x085, "10 81 11");
    ingest(&t, 1 * MS, 0x085, "R8");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 2);
    /* The history: only 0 may be written to sub0. */
    CHECK_EQ(write_u8(&t, 0x1003, 0, 1), CO_ABORT_VALUE);
    CHECK_EQ(write_u8(&t, 0x1003, 0, 0), CO_ABORT_NONE);
}

/* ---- SDO server at the edges of block transfer */

static const char *last_frame(const test_node_t *t)
{
    static char buf[40];
    return t->bus.count ? frame_str(&t->bus.frames[t->bus.count - 1], buf, sizeof buf) : "";
}

static void test_block_download_bad_sequence_number(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 0, 0x605, "C6 00 20 00 04 00 00 00");
    CHECK_EQ(t.bus.frames[t.bus.count - 1].data[0], 0xA4);
    ingest(&t, 0, 0x605, "00 01 02 03 04 05 06 07"); /* seqno 0 */
    CHECK_STR(last_frame(&t), "585#8000200003000405");
}

static void test_block_download_of_an_empty_value(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    /* 0x2003 is a DOMAIN: 0 bytes, one segment with nothing in it, n = 7. */
    ingest(&t, 0, 0x605, "C2 03 20 00 00 00 00 00");
    ingest(&t, 0, 0x605, "81 00 00 00 00 00 00 00");
    CHECK_STR(last_frame(&t), "585#A2017F0000000000");
    ingest(&t, 0, 0x605, "DD 00 00 00 00 00 00 00");
    CHECK_STR(last_frame(&t), "585#A100000000000000");
    /* An end claiming more padding than data is refused. */
    ingest(&t, 0, 0x605, "C2 03 20 00 00 00 00 00");
    ingest(&t, 0, 0x605, "81 00 00 00 00 00 00 00");
    ingest(&t, 0, 0x605, "C1 00 00 00 00 00 00 00"); /* n = 0: 7 bytes, but 0 indicated */
    CHECK_EQ(t.bus.frames[t.bus.count - 1].data[0], 0x80);
}

static void test_block_upload_bad_acknowledgements(void)
{
    const char *acks[] = {"A2 05 10 00 00 00 00 00", "A2 01 00 00 00 00 00 00",
                          "A2 01 80 00 00 00 00 00"};
    const co_abort_t codes[] = {CO_ABORT_SEQUENCE, CO_ABORT_BLOCK_SIZE, CO_ABORT_BLOCK_SIZE};
    for (int i = 0; i < 3; i++) {
        test_node_t t;
        test_node_init(&t, 5, 0);
        co_node_start(&t.node, 0);
        ingest(&t, 0, 0x605, "A0 08 10 00 02 00 00 00"); /* 0x1008, 2 per sub-block */
        ingest(&t, 0, 0x605, "A3 00 00 00 00 00 00 00");
        ingest(&t, 0, 0x605, acks[i]);
        const co_frame_t *f = &t.bus.frames[t.bus.count - 1];
        CHECK_EQ(f->data[0], 0x80);
        CHECK_EQ(co_get_u32(&f->data[4]), codes[i]);
    }
}

static void test_expedited_download_without_size(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    /* 0x22: expedited, size not indicated: the object's own size (2 bytes) is taken. */
    ingest(&t, 0, 0x605, "22 01 20 00 F6 FF 55 55");
    CHECK_STR(last_frame(&t), "585#6001200000000000");
    CHECK_EQ(t.od.app_i16, -10);
}

/* ---- PDO */

static void test_pdo_event_and_rtr_of_what_the_node_lacks(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 0, 0x000, "01 05");
    fake_clear(&t.bus);
    CHECK_EQ(co_pdo_event(&t.node, 0x2FFF, 0), 0); /* no such entry: no TPDO */
    CHECK_EQ(co_tpdo_request(&t.node, EXAMPLE_PDOS), CO_ERR_ARG);
    CHECK_EQ(co_tpdo_request(&t.node, 1), CO_ERR_STATE); /* maps nothing: not valid */
    /* TPDO2 maps nothing: not valid, so an RTR for it is not answered. */
    ingest(&t, 0, 0x285, "R0");
    CHECK_EQ(t.bus.count, 0);
}

/* ---- life guarding: a new guard time while monitoring */

static void test_life_time_change_while_guarded(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u16(&t, 0x100C, 0, 100), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x100D, 0, 2), CO_ABORT_NONE);
    ingest(&t, 10 * MS, 0x705, "R1");                    /* monitoring starts: life time 200 ms */
    CHECK_EQ(write_u8(&t, 0x100D, 0, 5), CO_ABORT_NONE); /* from now: 500 ms */
    co_node_poll(&t.node, 250 * MS);
    CHECK_EQ(t.event_count, 0); /* the old 200 ms would have run out at 210 ms */
    co_node_poll(&t.node, 509 * MS);
    CHECK_EQ(t.event_count, 0);
    co_node_poll(&t.node, 510 * MS);
    CHECK_EQ(t.event_count, 1);
    CHECK_EQ(t.events[0].kind, CO_EC_LIFE_GUARD);
    CHECK_EQ(co_node_poll(&t.node, 520 * MS), CO_TIME_NEVER); /* lost: nothing to wait for */
    CHECK_EQ(write_u8(&t, 0x100D, 0, 3), CO_ABORT_NONE);      /* changes nothing while lost */
    co_node_poll(&t.node, 590 * MS);
    CHECK_EQ(t.event_count, 1);
    ingest(&t, 600 * MS, 0x705, "R1"); /* resumed */
    CHECK_EQ(t.event_count, 2);
    CHECK_EQ(write_u16(&t, 0x100C, 0, 0), CO_ABORT_NONE); /* guarding off */
    co_node_poll(&t.node, 5000 * MS);
    CHECK_EQ(t.event_count, 2);
}

/* ---- heartbeat consumer entries of the wrong length */

static void test_consumer_entry_of_the_wrong_length(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u16(&t, 0x1016, 1, 500), CO_ABORT_LEN_LOW);
    CHECK_EQ(co_hb_remote_state(&t.node, 0), 0xFF);
}

/* ---- TIME */

static void test_time_producer_arguments_and_consumer_without_callback(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    co_time_of_day_t tod = {.ms = 1000, .days = 1};
    CHECK_EQ(co_time_send(NULL, &tod), CO_ERR_ARG);
    CHECK_EQ(co_time_send(&t.node, NULL), CO_ERR_ARG);
    CHECK_EQ(co_time_send(&t.node, &tod), CO_ERR_STATE); /* not a producer */
    /* Consumer without on_time: the frame is taken (not malformed) and dropped. */
    ingest(&t, 0, 0x100, "00 00 00 00 00 00");
    CHECK_EQ(co_node_stats(&t.node)->rx_malformed, 0);
    CHECK_EQ(co_node_stats(&t.node)->rx_unrouted, 0);
    /* Producer on: now it sends; a producer keeps consuming nothing of its own. */
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x40000100u), CO_ABORT_NONE);
    fake_clear(&t.bus);
    CHECK_EQ(co_time_send(&t.node, &tod), CO_OK);
    CHECK_EQ(fake_count_id(&t.bus, 0x100), 1);
    tod.ms = 86400000u;
    CHECK_EQ(co_time_send(&t.node, &tod), CO_ERR_ARG);
}

/* ---- SYNC configuration changed behind the node's back (a direct write to the value) */

static void test_sync_producer_follows_values_changed_directly(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u8(&t, 0x1019, 0, 5), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1006, 0, 10000), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1005, 0, 0x40000080u), CO_ABORT_NONE);
    fake_clear(&t.bus);
    for (uint64_t ms = 10; ms <= 40; ms += 10) {
        co_node_poll(&t.node, ms * MS);
    }
    CHECK_EQ(t.bus.count, 4);
    CHECK_EQ(t.bus.frames[3].data[0], 4);
    t.od.sync_overflow = 2; /* the counter (now 5) is past it: starts over at 1 */
    co_node_poll(&t.node, 50 * MS);
    CHECK_EQ(t.bus.frames[4].data[0], 1);
    t.od.sync_period_us = 0; /* period gone: no more SYNC */
    CHECK_EQ(co_node_poll(&t.node, 60 * MS), CO_TIME_NEVER);
    CHECK_EQ(t.bus.count, 5);
}

/* ---- the transmit queue without an on_error callback */

static co_err_t busy_tx(void *ctx, const co_frame_t *f)
{
    (void)ctx;
    (void)f;
    return CO_ERR_BUSY;
}

static co_err_t failing_tx(void *ctx, const co_frame_t *f)
{
    (void)ctx;
    (void)f;
    return CO_ERR_STATE;
}

static int g_sent;
static co_err_t counting_tx(void *ctx, const co_frame_t *f)
{
    (void)ctx;
    (void)f;
    g_sent++;
    return CO_OK;
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

/* A download without size indication is refused once the server's buffer is full: with
 * "too long" for an object of variable size, "out of memory" for a fixed one. */
static void segmented_until_refused(uint16_t index, co_abort_t expected)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    char req[32];
    snprintf(req, sizeof req, "20 %02X %02X 00 00 00 00 00", index & 0xFF, index >> 8);
    ingest(&t, 0, 0x605, req); /* segmented, size not indicated */
    uint32_t segments = 0;
    for (uint8_t toggle = 0; segments < 200; segments++, toggle ^= 1u) {
        ingest(&t, 0, 0x605, toggle ? "10 41 41 41 41 41 41 41" : "00 41 41 41 41 41 41 41");
        if (t.bus.frames[t.bus.count - 1].data[0] == 0x80) {
            break;
        }
    }
    CHECK_EQ(segments, CO_SDO_BUF_SIZE / 7); /* the segment that no longer fits */
    CHECK_EQ(co_get_u32(&t.bus.frames[t.bus.count - 1].data[4]), expected);
}

static void test_unsized_download_beyond_the_buffer(void)
{
    segmented_until_refused(0x2002, CO_ABORT_LEN_HIGH);
    segmented_until_refused(0x2000, CO_ABORT_OUT_OF_MEMORY);
}

static void test_unsized_block_download_beyond_the_buffer(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 0, 0x605, "C0 02 20 00 00 00 00 00"); /* block, no size, no CRC */
    uint8_t blksize = t.bus.frames[t.bus.count - 1].data[4];
    CHECK_EQ(blksize, CO_SDO_BUF_SIZE / 7 < 127 ? CO_SDO_BUF_SIZE / 7 : 127);
    char seg[32];
    for (unsigned i = 1; i <= blksize; i++) {
        snprintf(seg, sizeof seg, "%02X 41 41 41 41 41 41 41", i);
        ingest(&t, 0, 0x605, seg);
    }
    CHECK_EQ(t.bus.frames[t.bus.count - 1].data[0], 0xA2);
    ingest(&t, 0, 0x605, "01 41 41 41 41 41 41 41");
    const co_frame_t *f = &t.bus.frames[t.bus.count - 1];
    CHECK_EQ(f->data[0], 0x80);
    CHECK_EQ(co_get_u32(&f->data[4]), CO_ABORT_LEN_HIGH);
}

/* ---- more edges, each a documented answer */

static void test_collision_report_of_an_empty_frame(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 0, 0x705, "");
    CHECK_EQ(t.event_count, 1);
    CHECK_EQ(t.events[0].kind, CO_EC_ID_COLLISION);
    CHECK_EQ(t.events[0].state, 0xFF); /* nothing heard: no byte was read */
}

static void test_guard_watch_repeats_and_timeouts_once(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(co_guard_watch(&t.node, 9, 100, 2), CO_OK);
    ingest(&t, 1 * MS, 0x709, "7F");
    ingest(&t, 2 * MS, 0x709, "FF"); /* same state: no event */
    CHECK_EQ(t.event_count, 1);
    co_node_poll(&t.node, 500 * MS);
    co_node_poll(&t.node, 900 * MS);
    CHECK_EQ(t.event_count, 2); /* one timeout, not one per poll */
    CHECK_EQ(t.events[1].kind, CO_EC_GUARD_TIMEOUT);
}

static void test_heartbeat_consumer_edges(void)
{
    test_node_t t;
    test_node_init(&t, 1, 0);
    co_node_start(&t.node, 0);
    /* Node-ID 200 is no node: the entry is unused, nothing is routed for it. */
    uint32_t routes = co_node_route_count(&t.node);
    CHECK_EQ(write_u32(&t, 0x1016, 1, hb_consumer_value(200, 100)), CO_ABORT_NONE);
    CHECK_EQ(co_node_route_count(&t.node), routes);
    CHECK_EQ(co_node_route_id(&t.node, routes), 0); /* past the end */
    /* Two boot-ups in a row: two boots, not a remote reset (it never ran in between). */
    CHECK_EQ(write_u32(&t, 0x1016, 2, hb_consumer_value(9, 100)), CO_ABORT_NONE);
    ingest(&t, 1 * MS, 0x709, "00");
    ingest(&t, 2 * MS, 0x709, "00");
    CHECK_EQ(t.event_count, 2);
    CHECK_EQ(t.events[0].kind, CO_EC_BOOT);
    CHECK_EQ(t.events[1].kind, CO_EC_BOOT);
}

static void test_nmt_before_start(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    CHECK_EQ(co_nmt_apply(&t.node, CO_NMT_CMD_START), CO_ERR_STATE);
    CHECK_EQ(t.bus.count, 0);
}

static void test_emcy_producer_off(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x80000085u), CO_ABORT_NONE);
    fake_clear(&t.bus);
    CHECK_EQ(co_emcy_raise(&t.node, 0x5000, NULL), CO_OK);
    CHECK_EQ(t.bus.count, 0);            /* EMCY off: no frame */
    CHECK_EQ(t.od.error_count, 1);       /* but recorded */
    CHECK_EQ(t.od.error_register, 0x01); /* and the register set */
    CHECK_EQ(write_u32(&t, 0x1014, 0, 0x85), CO_ABORT_NONE);
    CHECK_EQ(co_emcy_raise(&t.node, 0x5001, NULL), CO_OK);
    CHECK_EQ(fake_count_id(&t.bus, 0x085), 1); /* on again: the next one goes out */
}

static void test_time_cob_id_moves_the_route(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    co_frame_t old_id = frm(0x100, "00 00 00 00 00 00");
    co_frame_t new_id = frm(0x101, "00 00 00 00 00 00");
    CHECK(co_node_accepts(&t.node, &old_id));
    CHECK_EQ(write_u32(&t, 0x1012, 0, 0x80000101u), CO_ABORT_NONE);
    CHECK(!co_node_accepts(&t.node, &old_id));
    CHECK(co_node_accepts(&t.node, &new_id));
}

static void test_expedited_without_size_to_wide_objects(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    ingest(&t, 0, 0x605, "22 00 20 00 01 02 03 04"); /* u32: 4 bytes taken */
    CHECK_EQ(t.od.app_u32, 0x04030201u);
    ingest(&t, 0, 0x605, "22 02 20 00 61 62 63 64"); /* a string: 4 bytes taken */
    CHECK_STR(t.od.app_string, "abcd");
}

static void test_pdo_parameter_writes_that_change_nothing(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    uint32_t changes = t.bus.routes_changed;
    CHECK_EQ(write_u16(&t, 0x1800, 3, 10), CO_ABORT_NONE); /* inhibit: filters unchanged */
    CHECK_EQ(t.bus.routes_changed, changes);
    CHECK_EQ(write_u8(&t, 0x1400, 2, 254), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1400, 2, 253), CO_ABORT_VALUE); /* RTR types are TPDO-only */
    /* Mapping entries that can never be valid. */
    CHECK_EQ(write_u32(&t, 0x1400, 1, 0x80000205u), CO_ABORT_NONE);
    CHECK_EQ(write_u8(&t, 0x1600, 0, 0), CO_ABORT_NONE);
    const uint32_t bad[] = {0x62000100, 0x00050010, 0x00080020};
    for (int i = 0; i < 3; i++) {
        CHECK_EQ(write_u32(&t, 0x1600, 1, bad[i]), CO_ABORT_NONE);
        CHECK_EQ(write_u8(&t, 0x1600, 0, 1), CO_ABORT_NO_MAP); /* 0 bits, too wide, no object */
    }
    /* TPDO request in pre-operational: not running. */
    CHECK_EQ(co_tpdo_request(&t.node, 0), CO_ERR_STATE);
}

static void test_tpdo_252_rtr_before_any_sync(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(write_u8(&t, 0x1800, 2, 252), CO_ABORT_NONE);
    ingest(&t, 0, 0x000, "01 05");
    fake_clear(&t.bus);
    ingest(&t, 1 * MS, 0x185, "R4"); /* nothing sampled yet: no answer */
    CHECK_EQ(t.bus.count, 0);
    ingest(&t, 2 * MS, 0x080, "");
    ingest(&t, 3 * MS, 0x185, "R4");
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 1);
}

/* Two RPDOs: an error they share (deadline, length) ends only when both are fine again. */
static void two_rpdos(test_node_t *t)
{
    test_node_init(t, 5, 0);
    co_node_start(&t->node, 0);
    CHECK_EQ(write_u8(t, 0x1029, 1, 1), CO_ABORT_NONE); /* stay operational */
    CHECK_EQ(write_u32(t, 0x1401, 1, 0x80000305u), CO_ABORT_NONE);
    CHECK_EQ(write_u32(t, 0x1601, 1, 0x62000208), CO_ABORT_NONE);
    CHECK_EQ(write_u8(t, 0x1601, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(write_u32(t, 0x1401, 1, 0x305), CO_ABORT_NONE);
    ingest(t, 0, 0x000, "01 05");
}

static void test_shared_rpdo_errors_end_with_the_last(void)
{
    test_node_t t;
    two_rpdos(&t);
    CHECK_EQ(write_u16(&t, 0x1400, 5, 50), CO_ABORT_NONE);
    CHECK_EQ(write_u16(&t, 0x1401, 5, 50), CO_ABORT_NONE);
    ingest(&t, 10 * MS, 0x205, "01 02 03 04");
    ingest(&t, 10 * MS, 0x305, "05");
    co_node_poll(&t.node, 100 * MS);
    CHECK(co_emcy_active(&t.node, 0x8250));
    ingest(&t, 110 * MS, 0x205, "01 02 03 04");
    CHECK(co_emcy_active(&t.node, 0x8250)); /* RPDO2 is still missing */
    ingest(&t, 120 * MS, 0x305, "05");
    CHECK(!co_emcy_active(&t.node, 0x8250));

    two_rpdos(&t);
    ingest(&t, 10 * MS, 0x205, "01 02");
    ingest(&t, 10 * MS, 0x305, "");
    CHECK(co_emcy_active(&t.node, 0x8210));
    ingest(&t, 20 * MS, 0x205, "01 02 03 04");
    CHECK(co_emcy_active(&t.node, 0x8210));
    ingest(&t, 20 * MS, 0x305, "05");
    CHECK(!co_emcy_active(&t.node, 0x8210));
    CHECK_EQ(t.od.outputs[1], 5);
}

/* A change of a mapped value sends an event-driven TPDO only: not in pre-operational, not
 * for a synchronous one. */
static void test_value_changes_and_tpdo_types(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 0); /* pre-operational */
    ingest(&t, 0, 0x000, "01 05");
    CHECK_EQ(write_u8(&t, 0x1800, 2, 1), CO_ABORT_NONE); /* every SYNC */
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 2), CO_ABORT_NONE);
    CHECK_EQ(co_pdo_event(&t.node, 0x2000, 0), 0);
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 0);
    ingest(&t, 1 * MS, 0x080, "");
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 1);
    /* A SYNC start value with SYNCs that carry no counter: sent from the first SYNC. */
    CHECK_EQ(write_u8(&t, 0x1800, 6, 3), CO_ABORT_NONE);
    ingest(&t, 2 * MS, 0x080, "");
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 2);
    /* A TPDO made not valid sends nothing, whatever changes. */
    CHECK_EQ(write_u8(&t, 0x1800, 2, 255), CO_ABORT_NONE);
    CHECK_EQ(write_u32(&t, 0x1800, 1, 0x80000185u), CO_ABORT_NONE);
    CHECK_EQ(co_pdo_event(&t.node, 0x2000, 0), 0);
    CHECK_EQ(co_node_set_uint(&t.node, 0x2000, 0, 3), CO_ABORT_NONE);
    ingest(&t, 3 * MS, 0x185, "R4");
    CHECK_EQ(fake_count_id(&t.bus, 0x185), 2);
}

int main(void)
{
    RUN(test_node_init_arguments);
    RUN(test_local_reads_of_the_wrong_kind);
    RUN(test_guard_watch_limits_and_replies);
    RUN(test_unconfigured_node_sends_no_heartbeat);
    RUN(test_emcy_consumer_without_callback_or_with_bad_frames);
    RUN(test_block_download_bad_sequence_number);
    RUN(test_block_download_of_an_empty_value);
    RUN(test_block_upload_bad_acknowledgements);
    RUN(test_expedited_download_without_size);
    RUN(test_pdo_event_and_rtr_of_what_the_node_lacks);
    RUN(test_life_time_change_while_guarded);
    RUN(test_consumer_entry_of_the_wrong_length);
    RUN(test_time_producer_arguments_and_consumer_without_callback);
    RUN(test_sync_producer_follows_values_changed_directly);
    RUN(test_queue_overflow_and_driver_errors_without_callback);
    RUN(test_unsized_download_beyond_the_buffer);
    RUN(test_unsized_block_download_beyond_the_buffer);
    RUN(test_collision_report_of_an_empty_frame);
    RUN(test_guard_watch_repeats_and_timeouts_once);
    RUN(test_heartbeat_consumer_edges);
    RUN(test_nmt_before_start);
    RUN(test_emcy_producer_off);
    RUN(test_time_cob_id_moves_the_route);
    RUN(test_expedited_without_size_to_wide_objects);
    RUN(test_pdo_parameter_writes_that_change_nothing);
    RUN(test_tpdo_252_rtr_before_any_sync);
    RUN(test_shared_rpdo_errors_end_with_the_last);
    RUN(test_value_changes_and_tpdo_types);
    return check_summary();
}
