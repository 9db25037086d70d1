/* tests/test_sdo_client.c -- the SDO client, byte by byte against a scripted server, and
 * against the real server over the simulated bus. Client: node 1; server: node 5 (requests
 * on 0x605, responses on 0x585). */
#include "canola/sim.h"
#include "check.h"
#include "example_od.h"
#include "harness.h"

#include <stdlib.h>

/* ---- fixtures */

typedef struct result {
    int calls;
    uint8_t channel;
    co_abort_t abort;
    uint32_t len;
} result_t;

static test_node_t g_t; /* the client node (large: static) */
static uint64_t g_now;
static result_t g_r;

static void on_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    result_t *r = ctx;
    r->calls++;
    r->channel = channel;
    r->abort = abort;
    r->len = len;
}

/* Node 1, started (pre-operational), client channel 0 pointed at server 5. */
static co_node_t *client(void)
{
    CHECK_EQ(test_node_init(&g_t, 1, 0), CO_OK);
    g_now = 1000;
    CHECK_EQ(co_node_start(&g_t.node, g_now), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&g_t.node, 0, 5), CO_OK);
    fake_clear(&g_t.bus);
    memset(&g_r, 0, sizeof g_r);
    return &g_t.node;
}

/* What the client sent since the last call (candump style), then forget it. */
static const char *sent(void)
{
    static char buf[16384];
    fake_dump(&g_t.bus, buf, sizeof buf);
    fake_clear(&g_t.bus);
    return buf;
}

static void reply8(const uint8_t d[8])
{
    co_frame_t f = {.id = 0x585, .len = 8};
    memcpy(f.data, d, 8);
    co_node_ingest(&g_t.node, g_now, &f);
}

static void reply(const char *hex)
{
    co_frame_t f = frm(0x585, hex);
    co_node_ingest(&g_t.node, g_now, &f);
}

/* Expected candump string of one 0x605 frame. */
static const char *req8(const uint8_t d[8])
{
    static char buf[4][40];
    static int at;
    co_frame_t f = {.id = 0x605, .len = 8};
    memcpy(f.data, d, 8);
    at = (at + 1) % 4;
    return frame_str(&f, buf[at], sizeof buf[at]);
}

static uint8_t pattern(uint32_t i) { return (uint8_t)(i * 37u + 11u); }

/* Bitwise CRC-16-CCITT, independent of the table-driven one in the core. */
static uint16_t ref_crc(const uint8_t *p, uint32_t n)
{
    uint16_t crc = 0;
    for (uint32_t i = 0; i < n; i++) {
        crc ^= (uint16_t)(p[i] << 8);
        for (int b = 0; b < 8; b++) {
            crc = (uint16_t)((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
        }
    }
    return crc;
}

/* ---- expedited */

static void test_expedited_download_1_to_4(void)
{
    static const char *want[] = {"605#2F032000AA000000", "605#2B032000AABB0000",
                                 "605#27032000AABBCC00", "605#23032000AABBCCDD"};
    const uint8_t data[4] = {0xAA, 0xBB, 0xCC, 0xDD};
    for (uint32_t len = 1; len <= 4; len++) {
        co_node_t *n = client();
        CHECK_EQ(co_sdo_download(n, 0, 0x2003, 0, CO_SDO_EXPEDITED, data, len, on_done, &g_r),
                 CO_OK);
        CHECK_STR(sent(), want[len - 1]);
        CHECK(co_sdo_client_busy(n, 0));
        reply("60 03 20 00 00 00 00 00");
        CHECK_EQ(g_r.calls, 1);
        CHECK_EQ(g_r.abort, CO_ABORT_NONE);
        CHECK_EQ(g_r.len, len);
        CHECK(!co_sdo_client_busy(n, 0));
        CHECK_STR(sent(), "");
    }
    /* AUTO picks expedited for 1..4 bytes. */
    co_node_t *n = client();
    CHECK_EQ(co_sdo_download(n, 0, 0x2000, 0, CO_SDO_AUTO, data, 2, on_done, &g_r), CO_OK);
    CHECK_STR(sent(), "605#2B002000AABB0000");
}

static void test_expedited_upload_responses(void)
{
    static const struct {
        const char *resp;
        uint32_t len;
    } cases[] = {
        {"4F 00 20 00 11 22 33 44", 1}, {"4B 00 20 00 11 22 33 44", 2},
        {"47 00 20 00 11 22 33 44", 3}, {"43 00 20 00 11 22 33 44", 4},
        {"42 00 20 00 11 22 33 44", 4},
    };
    for (unsigned i = 0; i < 5; i++) {
        co_node_t *n = client();
        uint8_t buf[8];
        memset(buf, 0xEE, sizeof buf);
        CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r),
                 CO_OK);
        CHECK_STR(sent(), "605#4000200000000000");
        reply(cases[i].resp);
        CHECK_EQ(g_r.calls, 1);
        CHECK_EQ(g_r.abort, CO_ABORT_NONE);
        CHECK_EQ(g_r.len, cases[i].len);
        const uint8_t want[4] = {0x11, 0x22, 0x33, 0x44};
        CHECK(memcmp(buf, want, cases[i].len) == 0);
        CHECK_EQ(buf[cases[i].len], 0xEE); /* nothing written past the value */
        CHECK_STR(sent(), "");
    }
}

static void test_upload_cap_overflow(void)
{
    uint8_t buf[16];
    /* expedited: 4 bytes into 2 */
    co_node_t *n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 0, CO_SDO_AUTO, buf, 2, on_done, &g_r), CO_OK);
    sent();
    reply("43 00 20 00 11 22 33 44");
    CHECK_STR(sent(), "605#8000200005000405");
    CHECK_EQ(g_r.abort, CO_ABORT_OUT_OF_MEMORY);
    CHECK_EQ(g_r.len, 0);
    /* segmented, size indicated above cap: aborted at once */
    n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2003, 0, CO_SDO_SEGMENTED, buf, 10, on_done, &g_r), CO_OK);
    sent();
    reply("41 03 20 00 0B 00 00 00");
    CHECK_STR(sent(), "605#8003200005000405");
    CHECK_EQ(g_r.abort, CO_ABORT_OUT_OF_MEMORY);
    /* segmented, size not indicated: aborted by the segment that does not fit */
    n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2003, 0, CO_SDO_SEGMENTED, buf, 10, on_done, &g_r), CO_OK);
    sent();
    reply("40 03 20 00 00 00 00 00");
    CHECK_STR(sent(), "605#6000000000000000");
    reply("00 01 02 03 04 05 06 07");
    CHECK_STR(sent(), "605#7000000000000000");
    reply("10 01 02 03 04 05 06 07");
    CHECK_STR(sent(), "605#8003200005000405");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_OUT_OF_MEMORY);
    /* block upload with size above cap */
    n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2003, 0, CO_SDO_BLOCK, buf, 10, on_done, &g_r), CO_OK);
    CHECK_STR(sent(), "605#A40320007F000000");
    reply("C6 03 20 00 20 00 00 00");
    CHECK_STR(sent(), "605#8003200005000405");
    CHECK_EQ(g_r.abort, CO_ABORT_OUT_OF_MEMORY);
}

/* ---- segmented */

/* Segmented upload of `len` bytes scripted segment by segment (size indicated or not). */
static void segmented_upload(uint32_t len, bool size_indicated)
{
    co_node_t *n = client();
    uint8_t buf[64];
    CHECK_EQ(co_sdo_upload(n, 0, 0x2003, 0, CO_SDO_SEGMENTED, buf, sizeof buf, on_done, &g_r),
             CO_OK);
    CHECK_STR(sent(), "605#4003200000000000");
    uint8_t d[8] = {size_indicated ? 0x41 : 0x40, 0x03, 0x20, 0x00};
    co_put_u32(&d[4], size_indicated ? len : 0);
    reply8(d);
    uint32_t off = 0;
    unsigned t = 0;
    for (;;) {
        uint8_t want[8] = {(uint8_t)(0x60 | (t << 4))};
        CHECK_STR(sent(), req8(want));
        uint32_t k = len - off < 7 ? len - off : 7;
        bool last = off + 7 >= len;
        memset(d, 0, sizeof d);
        d[0] = (uint8_t)((t << 4) | ((7 - k) << 1) | (last ? 1 : 0));
        for (uint32_t i = 0; i < k; i++) {
            d[1 + i] = pattern(off + i);
        }
        reply8(d);
        off += k;
        t ^= 1;
        if (last) {
            break;
        }
    }
    CHECK_STR(sent(), "");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_r.len, len);
    for (uint32_t i = 0; i < len; i++) {
        CHECK_EQ(buf[i], pattern(i));
    }
}

static void test_segmented_upload_sizes(void)
{
    /* 0 (one empty segment), and 1..7 bytes in the last segment after 0, 1 and 2 full ones */
    for (uint32_t len = 0; len <= 21; len++) {
        segmented_upload(len, true);
        segmented_upload(len, false);
    }
}

static void segmented_download(uint32_t len)
{
    co_node_t *n = client();
    uint8_t data[64];
    for (uint32_t i = 0; i < len; i++) {
        data[i] = pattern(i);
    }
    CHECK_EQ(co_sdo_download(n, 0, 0x2003, 0, CO_SDO_SEGMENTED, data, len, on_done, &g_r), CO_OK);
    uint8_t want[8] = {0x21, 0x03, 0x20, 0x00};
    co_put_u32(&want[4], len);
    CHECK_STR(sent(), req8(want));
    reply("60 03 20 00 00 00 00 00");
    uint32_t off = 0;
    unsigned t = 0;
    for (;;) {
        uint32_t k = len - off < 7 ? len - off : 7;
        bool last = off + 7 >= len;
        memset(want, 0, sizeof want);
        want[0] = (uint8_t)((t << 4) | ((7 - k) << 1) | (last ? 1 : 0));
        for (uint32_t i = 0; i < k; i++) {
            want[1 + i] = pattern(off + i);
        }
        CHECK_STR(sent(), req8(want));
        CHECK_EQ(g_r.calls, 0);
        uint8_t d[8] = {(uint8_t)(0x20 | (t << 4))};
        reply8(d);
        off += k;
        t ^= 1;
        if (last) {
            break;
        }
    }
    CHECK_STR(sent(), "");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_r.len, len);
}

static void test_segmented_download_sizes(void)
{
    for (uint32_t len = 0; len <= 21; len++) {
        segmented_download(len);
    }
    /* AUTO: 0 and 5+ bytes go segmented */
    co_node_t *n = client();
    const uint8_t data[5] = {1, 2, 3, 4, 5};
    CHECK_EQ(co_sdo_download(n, 0, 0x2003, 0, CO_SDO_AUTO, data, 5, on_done, &g_r), CO_OK);
    CHECK_STR(sent(), "605#2103200005000000");
    n = client();
    CHECK_EQ(co_sdo_download(n, 0, 0x2003, 0, CO_SDO_AUTO, NULL, 0, on_done, &g_r), CO_OK);
    CHECK_STR(sent(), "605#2103200000000000");
    reply("60 03 20 00 00 00 00 00");
    CHECK_STR(sent(), "605#0F00000000000000");
}

static void test_toggle_errors(void)
{
    uint8_t buf[32];
    co_node_t *n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2003, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    reply("41 03 20 00 14 00 00 00");
    reply("00 01 02 03 04 05 06 07"); /* t=0: fine */
    CHECK_STR(sent(), "605#4003200000000000 605#6000000000000000 605#7000000000000000");
    reply("00 01 02 03 04 05 06 07"); /* t=0 again */
    CHECK_STR(sent(), "605#8003200000000305");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_TOGGLE);

    const uint8_t data[10] = {0};
    n = client();
    CHECK_EQ(co_sdo_download(n, 0, 0x2003, 0, CO_SDO_AUTO, data, 10, on_done, &g_r), CO_OK);
    reply("60 03 20 00 00 00 00 00");
    CHECK_STR(sent(), "605#210320000A000000 605#0000000000000000");
    reply("30 00 00 00 00 00 00 00"); /* toggle 1 for the first segment */
    CHECK_STR(sent(), "605#8003200000000305");
    CHECK_EQ(g_r.abort, CO_ABORT_TOGGLE);
}

static void test_size_mismatch(void)
{
    uint8_t buf[32];
    /* more than indicated */
    co_node_t *n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2003, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    reply("41 03 20 00 05 00 00 00");
    reply("01 01 02 03 04 05 06 07"); /* 7 bytes, last */
    CHECK_STR(sent(), "605#4003200000000000 605#6000000000000000 605#8003200012000706");
    CHECK_EQ(g_r.abort, CO_ABORT_LEN_HIGH);
    /* less than indicated */
    n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2003, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    reply("41 03 20 00 09 00 00 00");
    reply("05 01 02 03 04 05 06 07"); /* 5 bytes, last */
    CHECK_STR(sent(), "605#4003200000000000 605#6000000000000000 605#8003200013000706");
    CHECK_EQ(g_r.abort, CO_ABORT_LEN_LOW);
}

/* ---- protocol errors, aborts, time-out */

static void test_server_abort(void)
{
    uint8_t buf[8];
    co_node_t *n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2099, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    sent();
    reply("80 99 20 00 00 00 02 06");
    CHECK_STR(sent(), "");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NO_OBJECT);
    CHECK(!co_sdo_client_busy(n, 0));
    /* an abort in the middle of a block upload */
    n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2003, 0, CO_SDO_BLOCK, buf, sizeof buf, on_done, &g_r), CO_OK);
    reply("C6 03 20 00 08 00 00 00");
    sent();
    reply("80 03 20 00 00 00 06 06");
    CHECK_STR(sent(), "");
    CHECK_EQ(g_r.abort, CO_ABORT_HARDWARE);
    /* frames after the end are ignored */
    reply("43 03 20 00 01 02 03 04");
    CHECK_EQ(g_r.calls, 1);
    CHECK_STR(sent(), "");
}

static void test_protocol_errors(void)
{
    uint8_t buf[8];
    /* unknown command byte */
    co_node_t *n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    sent();
    reply("E0 00 20 00 00 00 00 00");
    CHECK_STR(sent(), "605#8000200001000405");
    CHECK_EQ(g_r.abort, CO_ABORT_COMMAND);
    /* response for another object */
    n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    sent();
    reply("43 01 20 00 00 00 00 00");
    CHECK_STR(sent(), "605#8000200000000008");
    CHECK_EQ(g_r.abort, CO_ABORT_GENERAL);
    /* short frames are malformed and ignored */
    n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    sent();
    uint32_t before = co_node_stats(n)->rx_malformed;
    reply("43 00 20 00 01 02 03");
    CHECK_EQ(co_node_stats(n)->rx_malformed, before + 1);
    CHECK_EQ(g_r.calls, 0);
    CHECK(co_sdo_client_busy(n, 0));
    reply("43 00 20 00 01 02 03 04");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.len, 4);
    /* a frame with no transfer open: ignored */
    reply("43 00 20 00 01 02 03 04");
    CHECK_EQ(g_r.calls, 1);
    CHECK_STR(sent(), "");
    /* a server abort with code 0 must not read as success */
    n = client();
    CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    reply("80 00 20 00 00 00 00 00");
    CHECK_EQ(g_r.abort, CO_ABORT_GENERAL);
}

static void test_timeout_exact(void)
{
    CHECK_EQ(test_node_init(&g_t, 1, 0), CO_OK);
    g_t.node.cfg.sdo_timeout_ms = 500;
    CHECK_EQ(co_node_start(&g_t.node, 2000), CO_OK);
    co_node_t *n = &g_t.node;
    CHECK_EQ(co_sdo_client_setup(n, 0, 5), CO_OK);
    memset(&g_r, 0, sizeof g_r);
    uint8_t buf[32];
    fake_clear(&g_t.bus);
    CHECK_EQ(co_sdo_upload(n, 0, 0x2003, 0, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    CHECK_STR(sent(), "605#4003200000000000");
    CHECK_EQ(co_node_poll(n, 2000), 502000);
    CHECK_EQ(co_node_poll(n, 501999), 502000);
    CHECK_EQ(g_r.calls, 0);
    /* a response restarts the time-out */
    g_now = 400000;
    reply("41 03 20 00 14 00 00 00");
    CHECK_STR(sent(), "605#6000000000000000");
    CHECK_EQ(co_node_poll(n, 502000), 900000);
    CHECK_EQ(g_r.calls, 0);
    CHECK_EQ(co_node_poll(n, 899999), 900000);
    CHECK_STR(sent(), "");
    CHECK_EQ(co_node_poll(n, 900000), CO_TIME_NEVER);
    CHECK_STR(sent(), "605#8003200000000405");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_TIMEOUT);
    /* default: 1000 ms */
    n = client();
    CHECK_EQ(co_sdo_download(n, 0, 0x2000, 0, CO_SDO_AUTO, buf, 4, on_done, &g_r), CO_OK);
    CHECK_EQ(co_node_poll(n, 1000), 1001000);
    CHECK_EQ(co_node_poll(n, 1000999), 1001000);
    CHECK_EQ(g_r.calls, 0);
    co_node_poll(n, 1001000);
    CHECK_EQ(g_r.abort, CO_ABORT_TIMEOUT);
}

static void test_client_abort(void)
{
    uint8_t buf[8];
    co_node_t *n = client();
    CHECK_EQ(co_sdo_client_abort(n, 0, CO_ABORT_DATA_STORE), CO_ERR_STATE);
    CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 1, CO_SDO_AUTO, buf, sizeof buf, on_done, &g_r), CO_OK);
    sent();
    CHECK_EQ(co_sdo_client_abort(n, 0, CO_ABORT_DATA_STORE), CO_OK);
    CHECK_STR(sent(), "605#8000200120000008");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_DATA_STORE);
    CHECK(!co_sdo_client_busy(n, 0));
    CHECK_EQ(co_node_poll(n, 5000000), CO_TIME_NEVER);
    CHECK_EQ(g_r.calls, 1);
}

/* ---- block download */

/* Scripted block download: sub-blocks of `blk` segments, each acknowledged whole. */
static void block_download(uint32_t len, uint8_t blk, bool server_crc)
{
    co_node_t *n = client();
    static uint8_t data[2048];
    for (uint32_t i = 0; i < len; i++) {
        data[i] = pattern(i);
    }
    CHECK_EQ(co_sdo_download(n, 0, 0x2003, 0, CO_SDO_BLOCK, data, len, on_done, &g_r), CO_OK);
    uint8_t want[8] = {0xC6, 0x03, 0x20, 0x00};
    co_put_u32(&want[4], len);
    CHECK_STR(sent(), req8(want));
    uint8_t d[8] = {server_crc ? 0xA4 : 0xA0, 0x03, 0x20, 0x00, blk};
    reply8(d);
    uint32_t off = 0;
    bool done = false;
    while (!done) {
        uint8_t seq = 0;
        char expect[16384] = "";
        size_t at = 0;
        while (seq < blk && !done) {
            uint32_t k = len - off < 7 ? len - off : 7;
            done = off + 7 >= len;
            memset(want, 0, sizeof want);
            want[0] = (uint8_t)((done ? 0x80 : 0) | ++seq);
            for (uint32_t i = 0; i < k; i++) {
                want[1 + i] = pattern(off + i);
            }
            at += (size_t)snprintf(expect + at, sizeof expect - at, "%s%s", at ? " " : "",
                                   req8(want));
            off += k;
        }
        CHECK_STR(sent(), expect);
        uint8_t ack[8] = {0xA2, seq, blk};
        reply8(ack);
    }
    uint32_t nfree = len == 0 ? 7 : (7 - len % 7) % 7;
    uint16_t crc = server_crc ? ref_crc(data, len) : 0;
    uint8_t end[8] = {(uint8_t)(0xC1 | (nfree << 2)), (uint8_t)crc, (uint8_t)(crc >> 8)};
    CHECK_STR(sent(), req8(end));
    CHECK_EQ(g_r.calls, 0);
    reply("A1 00 00 00 00 00 00 00");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_r.len, len);
    CHECK_STR(sent(), "");
}

static void test_block_download(void)
{
    /* last segment holding 1..7 bytes (n = 6..0), and the empty download (n = 7) */
    for (uint32_t len = 0; len <= 15; len++) {
        block_download(len, 127, true);
    }
    /* 1..127 segments per sub-block, over several sub-blocks */
    static const uint8_t blks[] = {1, 2, 3, 7, 64, 126, 127};
    for (unsigned i = 0; i < sizeof blks; i++) {
        block_download(7u * 127u + 3u, blks[i], true);
        block_download(7u * blks[i], blks[i], false);
        block_download(7u * blks[i] + 1, blks[i], true);
    }
    block_download(2000, 127, true);
}

static void test_block_download_no_crc_offered(void)
{
    co_node_t *n = client();
    CHECK_EQ(co_sdo_client_block_options(n, 0, 127, false, 0), CO_OK);
    const uint8_t data[3] = {1, 2, 3};
    CHECK_EQ(co_sdo_download(n, 0, 0x2003, 0, CO_SDO_BLOCK, data, 3, on_done, &g_r), CO_OK);
    CHECK_STR(sent(), "605#C203200003000000");
    reply("A4 03 20 00 10 00 00 00"); /* the server supports CRC; we did not offer it */
    CHECK_STR(sent(), "605#8101020300000000");
    reply("A2 01 10 00 00 00 00 00");
    CHECK_STR(sent(), "605#D100000000000000"); /* n = 4, CRC 0 */
    reply("A1 00 00 00 00 00 00 00");
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
}

int main(void)
{
    RUN(test_expedited_download_1_to_4);
    RUN(test_expedited_upload_responses);
    RUN(test_upload_cap_overflow);
    RUN(test_segmented_upload_sizes);
    RUN(test_segmented_download_sizes);
    RUN(test_toggle_errors);
    RUN(test_size_mismatch);
    RUN(test_server_abort);
    RUN(test_protocol_errors);
    RUN(test_timeout_exact);
    RUN(test_client_abort);
    RUN(test_block_download);
    RUN(test_block_download_no_crc_offered);
    return check_summary();
}
