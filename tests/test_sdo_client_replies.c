/* SPDX-License-Identifier: Apache-2.0 */
/* tests/test_sdo_client_replies.c -- the SDO client against replies a correct server never
 * sends (each one ends the transfer with the CiA code for it, and the abort goes out), and
 * the argument checks of the client API. Client: node 1, server: node 5. */
#include "check.h"
#include "harness.h"

static test_node_t g_t; /* large: static */
static sdo_result_t g_r;

static co_node_t *client(void)
{
    CHECK_EQ(test_node_init(&g_t, 1, 0), CO_OK);
    CHECK_EQ(co_node_start(&g_t.node, 0), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&g_t.node, 0, 5), CO_OK);
    fake_clear(&g_t.bus);
    memset(&g_r, 0, sizeof g_r);
    return &g_t.node;
}

static void reply(const char *hex) { ingest(&g_t, 0, 0x585, hex); }

/* The last frame the client sent, candump style. */
static const char *last_sent(void)
{
    static char buf[40];
    if (g_t.bus.count == 0) {
        return "";
    }
    return frame_str(&g_t.bus.frames[g_t.bus.count - 1], buf, sizeof buf);
}

static uint8_t g_data[64];

static void start_download(co_sdo_mode_t mode, uint32_t len)
{
    CHECK_EQ(co_sdo_download(&g_t.node, 0, 0x2000, 0, mode, g_data, len, sdo_result_done, &g_r),
             CO_OK);
}

/* The transfer ended with `code`, and told the server so. */
static void check_aborted(co_abort_t code, const char *abort_frame)
{
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, code);
    CHECK_EQ(g_r.len, 0);
    CHECK_STR(last_sent(), abort_frame);
    CHECK(!co_sdo_client_busy(&g_t.node, 0));
}

/* Answers that name another object while a transfer waits for its initiate answer are
 * late answers to earlier requests (a server that answered after the time-out, or another
 * client of the same server): ignored by every kind of transfer, which goes on. */
static void test_response_for_another_sub_index(void)
{
    client();
    uint8_t buf[4];
    co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_AUTO, buf, 4, sdo_result_done, &g_r);
    reply("43 00 20 01 01 02 03 04");
    reply("43 00 10 00 91 01 00 00");
    CHECK_EQ(g_r.calls, 0);
    CHECK(co_sdo_client_busy(&g_t.node, 0));
    reply("43 00 20 00 01 02 03 04");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(buf[3], 4);
    static const uint8_t data[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    static const struct {
        co_sdo_mode_t mode;
        const char *stale;
        const char *right;
    } kinds[] = {
        {CO_SDO_EXPEDITED, "60 01 20 00 00 00 00 00", "60 00 20 00 00 00 00 00"},
        {CO_SDO_SEGMENTED, "60 00 20 02 00 00 00 00", "60 00 20 00 00 00 00 00"},
        {CO_SDO_BLOCK, "A4 00 21 00 7F 00 00 00", "A4 00 20 00 7F 00 00 00"},
    };
    for (uint32_t i = 0; i < 3; i++) {
        client();
        uint32_t len = kinds[i].mode == CO_SDO_EXPEDITED ? 4 : 12;
        CHECK_EQ(co_sdo_download(&g_t.node, 0, 0x2000, 0, kinds[i].mode, data, len, sdo_result_done,
                                 &g_r),
                 CO_OK);
        fake_clear(&g_t.bus);
        reply(kinds[i].stale);
        CHECK_EQ(g_t.bus.count, 0);
        CHECK(co_sdo_client_busy(&g_t.node, 0));
        reply(kinds[i].right);
        if (kinds[i].mode == CO_SDO_EXPEDITED) { /* done */
            CHECK_EQ(g_r.calls, 1);
            CHECK_EQ(g_r.abort, CO_ABORT_NONE);
        } else { /* the first segment goes out */
            CHECK_EQ(g_r.calls, 0);
            CHECK(g_t.bus.count >= 1);
            CHECK_EQ(g_t.bus.frames[0].data[0], kinds[i].mode == CO_SDO_BLOCK ? 0x01 : 0x00);
        }
    }
    client();
    co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_BLOCK, buf, 4, sdo_result_done, &g_r);
    fake_clear(&g_t.bus);
    reply("C6 00 20 05 04 00 00 00");
    CHECK_EQ(g_t.bus.count, 0);
    CHECK(co_sdo_client_busy(&g_t.node, 0));
}

/* A server that answers a segmented upload with empty segments (n = 7, not the last)
 * would keep the transfer open as long as it likes: each resets the time-out. The first
 * one ends it. */
static void test_empty_upload_segment_before_the_last_is_refused(void)
{
    client();
    uint8_t buf[8];
    co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_AUTO, buf, sizeof buf, sdo_result_done, &g_r);
    reply("40 00 20 00 00 00 00 00"); /* segmented, size not indicated */
    CHECK_STR(last_sent(), "605#6000000000000000");
    reply("0E 00 00 00 00 00 00 00"); /* toggle 0, n = 7, c = 0: no data, more to come */
    check_aborted(CO_ABORT_COMMAND, "605#8000200001000405");
    /* An empty last segment still ends a transfer well (all its data came before). */
    client();
    co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_AUTO, buf, sizeof buf, sdo_result_done, &g_r);
    reply("40 00 20 00 00 00 00 00");
    reply("00 01 02 03 04 05 06 07"); /* 7 bytes */
    reply("1F 00 00 00 00 00 00 00"); /* toggle 1, n = 7, c = 1 */
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_r.len, 7);
}

static void test_download_initiate_answered_wrongly(void)
{
    client();
    start_download(CO_SDO_SEGMENTED, 10);
    reply("61 00 20 00 00 00 00 00");
    check_aborted(CO_ABORT_COMMAND, "605#8000200001000405");
}

static void test_block_download_initiate_answered_wrongly(void)
{
    client();
    start_download(CO_SDO_BLOCK, 10);
    reply("60 00 20 00 00 00 00 00");
    check_aborted(CO_ABORT_COMMAND, "605#8000200001000405");
}

static void test_block_download_ack_answered_wrongly(void)
{
    client();
    start_download(CO_SDO_BLOCK, 20);
    reply("A4 00 20 00 7F 00 00 00");
    CHECK_EQ(g_t.bus.count, 4); /* initiate + 3 segments */
    reply("A3 03 7F 00 00 00 00 00");
    check_aborted(CO_ABORT_COMMAND, "605#8000200001000405");
}

static void test_block_download_ack_with_bad_block_size(void)
{
    const char *sizes[] = {"A2 01 00 00 00 00 00 00", "A2 01 80 00 00 00 00 00"};
    for (int i = 0; i < 2; i++) {
        client();
        start_download(CO_SDO_BLOCK, 20);
        reply("A4 00 20 00 7F 00 00 00");
        reply(sizes[i]);
        check_aborted(CO_ABORT_BLOCK_SIZE, "605#8000200002000405");
    }
}

/* A block download pauses while the transmit queue holds frames and resumes from poll. */
static void test_block_download_waits_for_the_queue(void)
{
    client();
    start_download(CO_SDO_BLOCK, 30);
    g_t.bus.busy = true;
    reply("A4 00 20 00 7F 00 00 00");
    co_node_poll(&g_t.node, 1000);
    /* The driver took nothing: one segment waits in the queue, no more were made. */
    CHECK_EQ(g_t.bus.count, 1);
    CHECK_EQ(co_node_stats(&g_t.node)->tx_queued, 1);
    g_t.bus.busy = false;
    co_node_poll(&g_t.node, 2000);
    CHECK_EQ(g_t.bus.count, 1 + 5);            /* the queued one, then the rest of the 5 */
    CHECK_EQ(g_t.bus.frames[5].data[0], 0x85); /* seqno 5, last */
    reply("A2 05 7F 00 00 00 00 00");
    CHECK_EQ(g_t.bus.frames[6].data[0] & 0xE3, 0xC1); /* the end */
    reply("A1 00 00 00 00 00 00 00");
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_r.len, 30);
}

/* (Sequence numbers outside 1..blksize: test_sdo_client_hostile.c.) */
static void test_block_upload_last_sub_block_shorter_than_asked(void)
{
    client();
    uint8_t buf[32];
    CHECK_EQ(co_sdo_client_block_options(&g_t.node, 0, 4, false, 0), CO_OK);
    co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_BLOCK, buf, sizeof buf, sdo_result_done, &g_r);
    reply("C2 00 20 00 0E 00 00 00"); /* 14 bytes, no CRC */
    reply("01 01 02 03 04 05 06 07");
    reply("82 08 09 0A 0B 0C 0D 0E");
    CHECK_STR(last_sent(), "605#A202040000000000");
    reply("C1 00 00 00 00 00 00 00"); /* n = 0: 14 bytes, as indicated */
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
    CHECK_EQ(g_r.len, 14);
    CHECK_EQ(buf[13], 0x0E);
}

static void test_block_upload_end_longer_than_indicated(void)
{
    client();
    uint8_t buf[32];
    CHECK_EQ(co_sdo_client_block_options(&g_t.node, 0, 4, false, 0), CO_OK);
    co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_BLOCK, buf, sizeof buf, sdo_result_done, &g_r);
    reply("C2 00 20 00 0A 00 00 00"); /* 10 bytes indicated */
    reply("01 01 02 03 04 05 06 07");
    reply("82 08 09 0A 0B 0C 0D 0E");
    reply("C1 00 00 00 00 00 00 00"); /* says 14 */
    check_aborted(CO_ABORT_LEN_HIGH, "605#8000200012000706");
}

static void test_rtr_on_the_response_id_is_malformed(void)
{
    client();
    uint8_t buf[4];
    co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_AUTO, buf, 4, sdo_result_done, &g_r);
    reply("R8");
    CHECK_EQ(co_node_stats(&g_t.node)->rx_malformed, 1);
    CHECK(co_sdo_client_busy(&g_t.node, 0)); /* still waiting for the real answer */
    reply("43 00 20 00 01 02 03 04");
    CHECK_EQ(g_r.abort, CO_ABORT_NONE);
}

/* Without a completion callback a transfer still runs and ends. */
static void test_transfer_without_callback(void)
{
    client();
    uint8_t buf[4];
    CHECK_EQ(co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_AUTO, buf, 4, NULL, NULL), CO_OK);
    reply("43 00 20 00 01 02 03 04");
    CHECK(!co_sdo_client_busy(&g_t.node, 0));
    CHECK_EQ(buf[3], 4);
}

static void test_abort_with_code_zero_reports_general_error(void)
{
    client();
    start_download(CO_SDO_SEGMENTED, 10);
    CHECK_EQ(co_sdo_client_abort(&g_t.node, 0, 0), CO_OK);
    check_aborted(CO_ABORT_GENERAL, "605#8000200000000008");
    CHECK_EQ(co_sdo_client_abort(&g_t.node, 0, 0), CO_ERR_STATE);
    CHECK_EQ(co_sdo_client_abort(NULL, 0, 1), CO_ERR_ARG);
    CHECK_EQ(co_sdo_client_abort(&g_t.node, CO_SDO_CLIENTS_MAX, 1), CO_ERR_ARG);
}

static void test_start_refused_by_state_and_arguments(void)
{
    co_node_t *n = client();
    uint8_t buf[4];
    CHECK_EQ(co_sdo_upload(NULL, 0, 0x2000, 0, CO_SDO_AUTO, buf, 4, sdo_result_done, &g_r),
             CO_ERR_ARG);
    CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 0, (co_sdo_mode_t)4, buf, 4, sdo_result_done, &g_r),
             CO_ERR_ARG);
    CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 0, CO_SDO_AUTO, NULL, 4, sdo_result_done, &g_r),
             CO_ERR_ARG);
    CHECK_EQ(co_sdo_download(n, 0, 0x2000, 0, CO_SDO_AUTO, NULL, 4, sdo_result_done, &g_r),
             CO_ERR_ARG);
    CHECK_EQ(co_sdo_client_block_options(NULL, 0, 4, true, 0), CO_ERR_ARG);
    CHECK_EQ(co_sdo_client_block_options(n, CO_SDO_CLIENTS_MAX, 4, true, 0), CO_ERR_ARG);
    CHECK_EQ(co_sdo_client_block_options(n, 0, 128, true, 0), CO_ERR_ARG);
    CHECK_EQ(co_sdo_client_setup(NULL, 0, 5), CO_ERR_ARG);
    CHECK(!co_sdo_client_busy(NULL, 0));
    CHECK(!co_sdo_client_busy(n, CO_SDO_CLIENTS_MAX));
    /* Stopped: SDO may not be sent. */
    ingest(&g_t, 0, 0x000, "02 01");
    CHECK_EQ(co_sdo_upload(n, 0, 0x2000, 0, CO_SDO_AUTO, buf, 4, sdo_result_done, &g_r),
             CO_ERR_STATE);
    /* A node not started yet. */
    CHECK_EQ(test_node_init(&g_t, 1, 0), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&g_t.node, 0, 5), CO_OK);
    CHECK_EQ(co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_AUTO, buf, 4, sdo_result_done, &g_r),
             CO_ERR_STATE);
}

/* A channel to the node itself reads and writes locally, with or without a callback. */
static void test_local_channel_without_buffers_or_callbacks(void)
{
    client();
    CHECK_EQ(co_sdo_client_setup(&g_t.node, 0, 1), CO_OK);
    CHECK_EQ(co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_AUTO, NULL, 0, sdo_result_done, &g_r),
             CO_OK);
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_OUT_OF_MEMORY); /* 4 bytes do not fit 0 */
    uint8_t v[4] = {1, 2, 3, 4};
    CHECK_EQ(co_sdo_download(&g_t.node, 0, 0x2000, 0, CO_SDO_AUTO, v, 4, NULL, NULL), CO_OK);
    CHECK_EQ(g_t.od.app_u32, 0x04030201u);
    uint8_t out[4];
    CHECK_EQ(co_sdo_upload(&g_t.node, 0, 0x2000, 0, CO_SDO_AUTO, out, 4, NULL, NULL), CO_OK);
    CHECK_EQ(out[0], 1);
    CHECK_EQ(
        co_sdo_download(&g_t.node, 0, 0x2000, 0, CO_SDO_SEGMENTED, NULL, 0, sdo_result_done, &g_r),
        CO_OK);
    CHECK_EQ(g_r.abort, CO_ABORT_LEN_LOW);
    CHECK_EQ(g_t.bus.count, 0); /* no frames */
}

static void test_typed_access_arguments(void)
{
    co_node_t *n = client();
    sdo_result_t r = {0};
    CHECK_EQ(co_sdo_read_value(NULL, 0, 0x2000, 0, sdo_result_value, &r), CO_ERR_ARG);
    CHECK_EQ(co_sdo_read_value(n, CO_SDO_CLIENTS_MAX, 0x2000, 0, sdo_result_value, &r), CO_ERR_ARG);
    CHECK_EQ(co_sdo_read_value(n, 0, 0x2000, 0, NULL, &r), CO_ERR_ARG);
    CHECK_EQ(co_sdo_write_value(NULL, 0, 0x2000, 0, 1, 4, sdo_result_done, &r), CO_ERR_ARG);
    CHECK_EQ(co_sdo_write_value(n, 0, 0x2000, 0, 1, 4, NULL, &r), CO_ERR_ARG);
    CHECK_EQ(co_sdo_write_value(n, 0, 0x2000, 0, 1, 0, sdo_result_done, &r), CO_ERR_ARG);
    CHECK_EQ(co_sdo_read_value(n, 0, 0x2000, 0, sdo_result_value, &r), CO_OK);
    CHECK_EQ(co_sdo_write_value(n, 0, 0x2000, 0, 1, 4, sdo_result_done, &r), CO_ERR_BUSY);
    /* A failed read reports value 0 and length 0. */
    reply("80 00 20 00 00 00 02 06");
    CHECK_EQ(r.calls, 1);
    CHECK_EQ(r.abort, CO_ABORT_NO_OBJECT);
    CHECK_EQ(r.value, 0);
    CHECK_EQ(r.len, 0);
}

/* Reset communication ends an open transfer locally, as leaving the states that allow SDO
 * does: reported with 0x08000022, and no frame (the server times out by itself). */
static void test_reset_communication_ends_a_transfer(void)
{
    client();
    start_download(CO_SDO_SEGMENTED, 10);
    fake_clear(&g_t.bus);
    CHECK_EQ(co_nmt_apply(&g_t.node, CO_NMT_CMD_RESET_COMMUNICATION), CO_OK);
    CHECK_EQ(g_r.calls, 1);
    CHECK_EQ(g_r.abort, CO_ABORT_DATA_STATE);
    CHECK_EQ(fake_count_id(&g_t.bus, 0x605), 0);
    CHECK(!co_sdo_client_busy(&g_t.node, 0));
}

int main(void)
{
    RUN(test_response_for_another_sub_index);
    RUN(test_empty_upload_segment_before_the_last_is_refused);
    RUN(test_download_initiate_answered_wrongly);
    RUN(test_block_download_initiate_answered_wrongly);
    RUN(test_block_download_ack_answered_wrongly);
    RUN(test_block_download_ack_with_bad_block_size);
    RUN(test_block_download_waits_for_the_queue);
    RUN(test_block_upload_last_sub_block_shorter_than_asked);
    RUN(test_block_upload_end_longer_than_indicated);
    RUN(test_rtr_on_the_response_id_is_malformed);
    RUN(test_transfer_without_callback);
    RUN(test_abort_with_code_zero_reports_general_error);
    RUN(test_start_refused_by_state_and_arguments);
    RUN(test_local_channel_without_buffers_or_callbacks);
    RUN(test_typed_access_arguments);
    RUN(test_reset_communication_ends_a_transfer);
    return check_summary();
}
