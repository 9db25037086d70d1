/*
 * test_review.c -- behaviours found wanting in a review of the core, each pinned by
 * one test: the input, and what CiA 301 or the headers say must come out.
 *
 * A small dictionary of its own serves the SDO cases the example OD cannot reach:
 * a value whose read hook hands out a few bytes per call (co_od_hooks_t.read copies
 * "up to `cap` bytes", so a short piece is legal), and the SDO client parameters 0x1280.
 */
#include "check.h"
#include "harness.h"

#define MS 1000ull

static char dump[4096];

/* ---- A node with a small dictionary: node 5, pre-operational, bus cleared. */

#define MINI_TRICKLE 0x2200 /* DOMAIN ro: read hook hands out at most `piece` bytes a call */
#define MINI_ENTRIES 8

typedef struct mini {
    fake_bus_t bus;
    co_node_t node;
    co_node_config_t cfg;
    co_od_entry_t entries[MINI_ENTRIES];
    uint8_t client_count;
    uint32_t client_cob[2];
    uint8_t client_node;
    uint32_t len;   /* bytes of the trickle value: byte i is 0x10 + i */
    uint32_t piece; /* most bytes the read hook copies per call */
} mini_t;

static co_abort_t trickle_read(void *ctx, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                               uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)entry;
    mini_t *m = ctx;
    uint32_t left = offset < m->len ? m->len - offset : 0;
    uint32_t k = left < cap ? left : cap;
    k = k < m->piece ? k : m->piece;
    for (uint32_t i = 0; i < k; i++) {
        buf[i] = (uint8_t)(0x10u + offset + i);
    }
    *n = k;
    *total = m->len;
    return CO_ABORT_NONE;
}

static const co_od_hooks_t k_trickle_hooks = {.read = trickle_read};

static void mini_start(mini_t *m, uint32_t len, uint32_t piece)
{
    memset(m, 0, sizeof *m);
    m->len = len;
    m->piece = piece;
    m->client_count = 3;
    m->client_cob[0] = 0x80000000u;
    m->client_cob[1] = 0x80000000u;
    uint32_t n = 0;
    m->entries[n++] = (co_od_entry_t){.index = 0x1280,
                                      .type = CO_TYPE_UNSIGNED8,
                                      .attr = CO_OD_CO,
                                      .size = 1,
                                      .value = &m->client_count};
    m->entries[n++] = (co_od_entry_t){.index = 0x1280,
                                      .sub = 1,
                                      .type = CO_TYPE_UNSIGNED32,
                                      .attr = CO_OD_RW,
                                      .size = 4,
                                      .value = &m->client_cob[0]};
    m->entries[n++] = (co_od_entry_t){.index = 0x1280,
                                      .sub = 2,
                                      .type = CO_TYPE_UNSIGNED32,
                                      .attr = CO_OD_RW,
                                      .size = 4,
                                      .value = &m->client_cob[1]};
    m->entries[n++] = (co_od_entry_t){.index = 0x1280,
                                      .sub = 3,
                                      .type = CO_TYPE_UNSIGNED8,
                                      .attr = CO_OD_RW,
                                      .size = 1,
                                      .value = &m->client_node};
    m->entries[n++] = (co_od_entry_t){.index = MINI_TRICKLE,
                                      .type = CO_TYPE_DOMAIN,
                                      .attr = CO_OD_RO,
                                      .size = 0x10000u,
                                      .hooks = &k_trickle_hooks};
    m->cfg.node_id = 5;
    m->cfg.od = (co_od_t){.entries = m->entries, .count = n, .hook_ctx = m};
    m->cfg.driver = fake_driver(&m->bus);
    CHECK_EQ(co_node_init(&m->node, &m->cfg), CO_OK);
    CHECK_EQ(co_node_start(&m->node, 0), CO_OK);
    fake_clear(&m->bus);
}

static void to_server(mini_t *m, uint64_t now, const char *hex)
{
    co_frame_t f = frm(0x605, hex);
    co_node_ingest(&m->node, now, &f);
    (void)co_node_poll(&m->node, now);
}

/* ---- SDO server: read hooks that hand out short pieces */

/* sdo.h: "Uploads read the dictionary piece by piece (co_od_read with an offset), so read
 * hooks stream too"; od.h: the hook copies "up to `cap` bytes". A 3-byte value whose hook
 * gives one byte per call must still be uploaded whole: 0x47 + 10 11 12, not 10 00 00. */
static void test_expedited_upload_collects_every_piece_of_a_short_read_hook(void)
{
    mini_t m;
    mini_start(&m, 3, 1);
    to_server(&m, 0, "40 00 22 00 00 00 00 00");
    CHECK_STR(fake_dump(&m.bus, dump, sizeof dump), "585#4700220010111200");
}

/* A 20-byte value read 4 bytes per call, by block upload: after the client's start (0xA3)
 * the server must send the sub-block (CiA 301: segments 1..n, the last one flagged),
 * not fall silent until the transfer times out. */
static void test_block_upload_sends_segments_when_read_hook_gives_short_pieces(void)
{
    mini_t m;
    mini_start(&m, 20, 4);
    to_server(&m, 0, "A4 00 22 00 7F 00 00 00");
    CHECK_STR(fake_dump(&m.bus, dump, sizeof dump), "585#C600220014000000");
    fake_clear(&m.bus);
    to_server(&m, 1 * MS, "A3 00 00 00 00 00 00 00");
    CHECK_STR(fake_dump(&m.bus, dump, sizeof dump),
              "585#0110111213141516 585#021718191A1B1C1D 585#831E1F2021222300");
}

/* ---- SDO client parameters (0x1280): COB-ID values CiA 301 does not allow */

/* CiA 301, COB-ID of an SDO parameter: bit 29 = 0 (11-bit CAN-ID) requires bits 28..11 to
 * be 0. 0x00000800 is not a CAN-ID the channel can use; storing it makes the client
 * (co_cob_frame masks to 11 bits) send its requests on COB-ID 0x000, the NMT command ID.
 * The write must be refused with 0x06090030 (invalid value). */
static void test_client_cob_id_with_bits_above_11_bit_id_is_refused(void)
{
    mini_t m;
    mini_start(&m, 0, 0);
    uint8_t v[4];
    co_put_u32(v, 0x00000800u);
    CHECK_EQ(co_node_write_net(&m.node, 0x1280, 1, v, 4), CO_ABORT_VALUE);
}

/* ---- NMT gating of frames that wait in the transmit queue */

/* nmt.h: SDO runs in pre-operational and operational only, and "every producer" consults
 * the service table. An SDO response that waited in the queue (driver busy) when an NMT
 * stop arrived must not leave once the node is stopped. */
static void test_sdo_response_queued_before_stop_is_not_sent_when_stopped(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    t.bus.busy = true;
    co_frame_t req = frm(0x605, "40 00 10 00 00 00 00 00");
    co_node_ingest(&t.node, 1 * MS, &req);
    co_frame_t stop = frm(0x000, "02 05");
    co_node_ingest(&t.node, 2 * MS, &stop);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_STOPPED);
    t.bus.busy = false;
    (void)co_node_poll(&t.node, 3 * MS);
    CHECK_EQ(fake_count_id(&t.bus, 0x585), 0);
}

/* The other way round: an SDO response that waited when an NMT start arrived may still
 * leave, as operational allows SDO. */
static void test_sdo_response_queued_before_start_is_sent_when_operational(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    t.bus.busy = true;
    co_frame_t req = frm(0x605, "40 00 10 00 00 00 00 00");
    co_node_ingest(&t.node, 1 * MS, &req);
    co_frame_t start = frm(0x000, "01 05");
    co_node_ingest(&t.node, 2 * MS, &start);
    CHECK_EQ(co_nmt_state(&t.node), CO_NMT_OPERATIONAL);
    t.bus.busy = false;
    (void)co_node_poll(&t.node, 3 * MS);
    CHECK_EQ(fake_count_id(&t.bus, 0x585), 1);
    CHECK_EQ(co_node_stats(&t.node)->tx_gated, 0);
}

/* ---- Follow-ups of the same review */

/* A heartbeat left waiting by a busy driver must not leave after the boot-up that a reset
 * sends: the reset makes it stale (same COB-ID, so it would otherwise go first). */
static void test_reset_drops_a_heartbeat_left_waiting(void)
{
    test_node_t t;
    test_node_init(&t, 5, 100);
    co_node_start(&t.node, 0);
    fake_clear(&t.bus);
    t.bus.busy = true;
    co_node_poll(&t.node, 100 * MS); /* the heartbeat 705#7F waits */
    co_frame_t reset = frm(0x000, "81 05");
    co_node_ingest(&t.node, 110 * MS, &reset);
    t.bus.busy = false;
    co_node_poll(&t.node, 111 * MS);
    CHECK_STR(fake_dump(&t.bus, dump, sizeof dump), "705#00");
    CHECK_EQ(co_node_stats(&t.node)->tx_gated, 1);
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

/* An unconfigured node (0xFF) keeps $NODEID defaults at their base: 0x1014 is 0x80, not
 * 0x80 + 0xFF. */
static void test_unconfigured_node_keeps_node_id_defaults_at_base(void)
{
    test_node_t t;
    test_node_init(&t, CO_NODE_ID_UNCONFIGURED, 0);
    co_node_start(&t.node, 0);
    CHECK_EQ(t.od.emcy_cob_id, 0x80);
}

/* A node neither consumes its own heartbeat nor guards itself (0x700 + its ID is its own
 * error-control COB-ID). */
static void test_own_node_id_refused_for_monitoring(void)
{
    test_node_t t;
    test_node_init(&t, 5, 0);
    co_node_start(&t.node, 0);
    uint8_t v[4];
    co_put_u32(v, hb_consumer_value(5, 100));
    CHECK_EQ(co_node_write_net(&t.node, 0x1016, 1, v, 4), CO_ABORT_PARAM_INCOMPAT);
    CHECK_EQ(co_guard_watch(&t.node, 5, 100, 3), CO_ERR_ARG);
}

int main(void)
{
    RUN(test_expedited_upload_collects_every_piece_of_a_short_read_hook);
    RUN(test_block_upload_sends_segments_when_read_hook_gives_short_pieces);
    RUN(test_client_cob_id_with_bits_above_11_bit_id_is_refused);
    RUN(test_sdo_response_queued_before_stop_is_not_sent_when_stopped);
    RUN(test_sdo_response_queued_before_start_is_sent_when_operational);
    RUN(test_reset_drops_a_heartbeat_left_waiting);
    RUN(test_standard_frame_with_an_oversized_id_is_malformed);
    RUN(test_unconfigured_node_keeps_node_id_defaults_at_base);
    RUN(test_own_node_id_refused_for_monitoring);
    return check_summary();
}
