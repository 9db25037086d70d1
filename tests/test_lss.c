/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_lss.c -- LSS (CiA 305) slave and master, byte-exact on a fake driver: every
 * command, its answer, the states it is allowed in, malformed frames; the master's
 * frames, answers, time-outs; fastscan against one slave on the simulated bus.
 */
#include <stdlib.h>

#include "canola/sim.h"
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define LSS 0x7E5u

static char dump[8192];
#define BUS(t) fake_dump(&(t)->bus, dump, sizeof dump)

/* A started node; 0xFF boots into LSS-only operation. */
static test_node_t *slave(uint8_t id)
{
    test_node_t *t = calloc(1, sizeof *t);
    CHECK_EQ(test_node_init(t, id, 0), CO_OK);
    CHECK_EQ(co_node_start(&t->node, 0), CO_OK);
    fake_clear(&t->bus);
    return t;
}

static void to_config(test_node_t *t) { ingest(t, 0, LSS, "04 01 00 00 00 00 00 00"); }

static void test_unconfigured_node_sends_nothing_and_waits(void)
{
    test_node_t *t = calloc(1, sizeof *t);
    CHECK_EQ(test_node_init(t, 0xFF, 0), CO_OK);
    CHECK_EQ(co_node_start(&t->node, 0), CO_OK);
    CHECK_STR(BUS(t), "");
    CHECK_EQ(co_nmt_state(&t->node), CO_NMT_INITIALISING);
    CHECK_EQ(co_lss_slave_mode(&t->node), CO_LSS_WAITING);
    /* NMT does not reach it; SDO is not routed. */
    ingest(t, 0, 0x000, "01 00");
    CHECK_EQ(co_nmt_state(&t->node), CO_NMT_INITIALISING);
    CHECK_STR(BUS(t), "");
    free(t);
}

static void test_inquire_in_configuration_only(void)
{
    test_node_t *t = slave(0xFF);
    ingest(t, 0, LSS, "5A 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), ""); /* waiting: ignored */
    to_config(t);
    CHECK_EQ(co_lss_slave_mode(&t->node), CO_LSS_CONFIGURATION);
    CHECK_STR(BUS(t), "");
    ingest(t, 0, LSS, "5A 00 00 00 00 00 00 00");
    ingest(t, 0, LSS, "5B 00 00 00 00 00 00 00");
    ingest(t, 0, LSS, "5C 00 00 00 00 00 00 00");
    ingest(t, 0, LSS, "5D 00 00 00 00 00 00 00");
    ingest(t, 0, LSS, "5E 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#5AA00C0000000000 7E4#5B01000000000000 7E4#5C00000100000000 "
                      "7E4#5D00000000000000 7E4#5EFF000000000000");
    free(t);
}

static void test_configure_node_id_then_boot(void)
{
    test_node_t *t = slave(0xFF);
    ingest(t, 0, LSS, "11 05 00 00 00 00 00 00");
    CHECK_STR(BUS(t), ""); /* waiting: ignored */
    to_config(t);
    ingest(t, 0, LSS, "11 00 00 00 00 00 00 00");
    ingest(t, 0, LSS, "11 80 00 00 00 00 00 00");
    ingest(t, 0, LSS, "11 05 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#1101000000000000 7E4#1101000000000000 7E4#1100000000000000");
    CHECK_EQ(co_node_id(&t->node), 0xFF); /* pending until it leaves configuration */
    fake_clear(&t->bus);
    ingest(t, 1 * MS, LSS, "04 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "705#00");
    CHECK_EQ(co_node_id(&t->node), 5);
    CHECK_EQ(co_nmt_state(&t->node), CO_NMT_PRE_OPERATIONAL);
    /* Its COB-IDs follow the new ID: the SDO server answers on 0x585. */
    co_frame_t req = frm(0x605, "40 00 10 00 00 00 00 00");
    CHECK(co_node_accepts(&t->node, &req));
    fake_clear(&t->bus);
    co_node_ingest(&t->node, 2 * MS, &req);
    CHECK_EQ(fake_count_id(&t->bus, 0x585), 1);
    /* Now configured: fastscan and "non-configured" no longer answer. */
    fake_clear(&t->bus);
    ingest(t, 3 * MS, LSS, "4C 00 00 00 00 00 00 00");
    ingest(t, 3 * MS, LSS, "51 00 00 00 00 80 00 00");
    CHECK_STR(BUS(t), "");
    free(t);
}

static void test_configured_node_takes_new_id_at_reset_communication(void)
{
    test_node_t *t = slave(5);
    to_config(t);
    ingest(t, 0, LSS, "11 07 00 00 00 00 00 00");
    ingest(t, 0, LSS, "04 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#1100000000000000");
    CHECK_EQ(co_node_id(&t->node), 5);
    fake_clear(&t->bus);
    ingest(t, 1 * MS, 0x000, "82 05");
    CHECK_STR(BUS(t), "707#00");
    CHECK_EQ(co_node_id(&t->node), 7);
    /* Reset node brings back the stored node-ID (nothing was stored: the initial 5). */
    fake_clear(&t->bus);
    ingest(t, 2 * MS, 0x000, "81 07");
    CHECK_STR(BUS(t), "705#00");
    free(t);
}

static void test_configure_unconfigured_again(void)
{
    test_node_t *t = slave(5);
    to_config(t);
    ingest(t, 0, LSS, "11 FF 00 00 00 00 00 00");
    ingest(t, 0, LSS, "04 00 00 00 00 00 00 00");
    ingest(t, 1 * MS, 0x000, "82 00");
    CHECK_STR(BUS(t), "7E4#1100000000000000"); /* no boot-up: it waits for an ID */
    CHECK_EQ(co_node_id(&t->node), 0xFF);
    CHECK_EQ(co_nmt_state(&t->node), CO_NMT_INITIALISING);
    free(t);
}

typedef struct app {
    uint8_t bit_timing_index;
    uint32_t bit_timing_calls;
    uint64_t bit_timing_at;
    co_node_t *node;
    uint8_t stored_id, stored_bt;
    uint32_t store_calls;
    co_err_t store_result;
} app_t;

static void on_bit_timing(void *ctx, uint8_t index)
{
    app_t *a = ctx;
    a->bit_timing_index = index;
    a->bit_timing_calls++;
    a->bit_timing_at = a->node->now_us;
}

static co_err_t on_store(void *ctx, uint8_t node_id, uint8_t bt)
{
    app_t *a = ctx;
    a->stored_id = node_id;
    a->stored_bt = bt;
    a->store_calls++;
    return a->store_result;
}

/* The switch waits its delay even when the node is polled for other work meanwhile (its
 * heartbeat, every millisecond). */
static void test_bit_timing_switch_waits_for_its_delay(void)
{
    test_node_t *t = slave(5);
    app_t a = {.node = &t->node};
    co_lss_slave_config_t lc = {.bit_timings = 1u << 3, .on_bit_timing = on_bit_timing, .ctx = &a};
    CHECK_EQ(co_lss_slave_setup(&t->node, &lc), CO_OK);
    CHECK_EQ(co_node_set_uint(&t->node, 0x1017, 0, 1), CO_ABORT_NONE);
    to_config(t);
    ingest(t, 0, LSS, "13 00 03 00 00 00 00 00");
    ingest(t, 100 * MS, LSS, "15 0A 00 00 00 00 00 00"); /* switch after 10 ms */
    for (uint64_t ms = 100; ms < 110; ms++) {
        /* the heartbeat (not sent: quiet) still wants a poll every millisecond */
        CHECK_EQ(co_node_poll(&t->node, ms * MS), (ms + 1) * MS);
        CHECK_EQ(a.bit_timing_calls, 0);
    }
    co_node_poll(&t->node, 110 * MS);
    CHECK_EQ(a.bit_timing_calls, 1);
    CHECK_EQ(a.bit_timing_at, 110 * MS);
    free(t);
}

/* CiA 305: after the switch the slave sends nothing for another delay, the heartbeat
 * included, not only its LSS answers. */
static void test_nothing_sent_in_the_quiet_time_after_the_switch(void)
{
    test_node_t *t = slave(5);
    co_lss_slave_config_t lc = {.bit_timings = 1u << 3};
    CHECK_EQ(co_lss_slave_setup(&t->node, &lc), CO_OK);
    CHECK_EQ(co_node_set_uint(&t->node, 0x1017, 0, 1), CO_ABORT_NONE);
    to_config(t);
    ingest(t, 0, LSS, "13 00 03 00 00 00 00 00");
    co_node_poll(&t->node, 99 * MS);
    fake_clear(&t->bus);
    ingest(t, 100 * MS, LSS, "15 0A 00 00 00 00 00 00"); /* switch at 110 ms */
    for (uint64_t ms = 101; ms < 120; ms++) {
        co_node_poll(&t->node, ms * MS);
        if (ms == 115) { /* taken by no service either: no answer, now or later */
            ingest(t, ms * MS, 0x605, "40 00 10 00 00 00 00 00");
        }
    }
    CHECK_STR(BUS(t), "");
    co_node_poll(&t->node, 120 * MS);
    CHECK_EQ(fake_count_id(&t->bus, 0x705), 1);
    CHECK_EQ(fake_count_id(&t->bus, 0x585), 0);
    ingest(t, 121 * MS, 0x605, "40 00 10 00 00 00 00 00"); /* the services are back */
    CHECK_EQ(fake_count_id(&t->bus, 0x585), 1);
    free(t);
}

static void test_bit_timing_configure_and_activate(void)
{
    test_node_t *t = slave(5);
    app_t a = {.node = &t->node};
    co_lss_slave_config_t lc = {
        .bit_timings = (1u << 2) | (1u << 3), .on_bit_timing = on_bit_timing, .ctx = &a};
    CHECK_EQ(co_lss_slave_setup(&t->node, &lc), CO_OK);
    to_config(t);
    ingest(t, 0, LSS, "15 0A 00 00 00 00 00 00"); /* nothing configured: ignored */
    ingest(t, 0, LSS, "13 00 05 00 00 00 00 00"); /* 100k (reserved index): no */
    ingest(t, 0, LSS, "13 01 03 00 00 00 00 00"); /* another table: no */
    ingest(t, 0, LSS, "13 00 03 00 00 00 00 00"); /* 250k: yes */
    CHECK_STR(BUS(t), "7E4#1301000000000000 7E4#1301000000000000 7E4#1300000000000000");
    CHECK_EQ(co_node_poll(&t->node, 1 * MS), CO_TIME_NEVER);
    fake_clear(&t->bus);
    ingest(t, 100 * MS, LSS, "15 0A 00 00 00 00 00 00"); /* switch after 10 ms */
    CHECK_EQ(co_node_poll(&t->node, 100 * MS), 110 * MS);
    CHECK_EQ(a.bit_timing_calls, 0);
    co_node_poll(&t->node, 110 * MS);
    CHECK_EQ(a.bit_timing_calls, 1);
    CHECK_EQ(a.bit_timing_index, 3);
    CHECK_EQ(a.bit_timing_at, 110 * MS);
    /* Silent for a second delay, then answers again. */
    ingest(t, 119 * MS, LSS, "5E 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "");
    ingest(t, 120 * MS, LSS, "5E 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#5E05000000000000");
    free(t);
}

static void test_store_configuration(void)
{
    test_node_t *t = slave(0xFF);
    to_config(t);
    ingest(t, 0, LSS, "17 00 00 00 00 00 00 00"); /* no store callback: not supported */
    CHECK_STR(BUS(t), "7E4#1701000000000000");
    app_t a = {.node = &t->node, .store_result = CO_ERR_CONFIG};
    co_lss_slave_config_t lc = {.bit_timings = 1u << 4, .store = on_store, .ctx = &a};
    co_lss_slave_setup(&t->node, &lc);
    fake_clear(&t->bus);
    ingest(t, 0, LSS, "11 09 00 00 00 00 00 00");
    ingest(t, 0, LSS, "13 00 04 00 00 00 00 00");
    ingest(t, 0, LSS, "17 00 00 00 00 00 00 00"); /* the medium fails: error 2 */
    a.store_result = CO_OK;
    ingest(t, 0, LSS, "17 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#1100000000000000 7E4#1300000000000000 7E4#1702000000000000 "
                      "7E4#1700000000000000");
    CHECK_EQ(a.store_calls, 2);
    CHECK_EQ(a.stored_id, 9);
    CHECK_EQ(a.stored_bt, 4);
    /* The stored ID is what reset node comes back to. */
    ingest(t, 0, LSS, "04 00 00 00 00 00 00 00");
    CHECK_EQ(co_node_id(&t->node), 9);
    fake_clear(&t->bus);
    ingest(t, 1 * MS, 0x000, "81 00");
    CHECK_STR(BUS(t), "709#00");
    free(t);
}

static void test_switch_selective(void)
{
    test_node_t *t = slave(0xFF);
    /* Wrong product: nothing. */
    ingest(t, 0, LSS, "40 A0 0C 00 00 00 00 00");
    ingest(t, 0, LSS, "41 02 00 00 00 00 00 00");
    ingest(t, 0, LSS, "42 00 00 01 00 00 00 00");
    ingest(t, 0, LSS, "43 00 00 00 00 00 00 00");
    /* Out of order: nothing. */
    ingest(t, 0, LSS, "41 01 00 00 00 00 00 00");
    ingest(t, 0, LSS, "42 00 00 01 00 00 00 00");
    ingest(t, 0, LSS, "43 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "");
    CHECK_EQ(co_lss_slave_mode(&t->node), CO_LSS_WAITING);
    ingest(t, 0, LSS, "40 A0 0C 00 00 00 00 00");
    ingest(t, 0, LSS, "41 01 00 00 00 00 00 00");
    ingest(t, 0, LSS, "42 00 00 01 00 00 00 00");
    ingest(t, 0, LSS, "43 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#4400000000000000");
    CHECK_EQ(co_lss_slave_mode(&t->node), CO_LSS_CONFIGURATION);
    free(t);
}

static void test_identify_remote_slave(void)
{
    test_node_t *t = slave(3);
    /* revision 0x00010000 in [0x10000, 0x20000], serial 0 in [0, 5]: answers */
    ingest(t, 0, LSS, "46 A0 0C 00 00 00 00 00");
    ingest(t, 0, LSS, "47 01 00 00 00 00 00 00");
    ingest(t, 0, LSS, "48 00 00 01 00 00 00 00");
    ingest(t, 0, LSS, "49 00 00 02 00 00 00 00");
    ingest(t, 0, LSS, "4A 00 00 00 00 00 00 00");
    ingest(t, 0, LSS, "4B 05 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#4F00000000000000");
    fake_clear(&t->bus);
    /* revision range [0x10001, 0x20000] excludes it */
    ingest(t, 0, LSS, "46 A0 0C 00 00 00 00 00");
    ingest(t, 0, LSS, "47 01 00 00 00 00 00 00");
    ingest(t, 0, LSS, "48 01 00 01 00 00 00 00");
    ingest(t, 0, LSS, "49 00 00 02 00 00 00 00");
    ingest(t, 0, LSS, "4A 00 00 00 00 00 00 00");
    ingest(t, 0, LSS, "4B 05 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "");
    free(t);
}

static void test_identify_non_configured(void)
{
    test_node_t *t = slave(0xFF);
    ingest(t, 0, LSS, "4C 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#5000000000000000");
    free(t);
    t = slave(4);
    ingest(t, 0, LSS, "4C 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "");
    free(t);
}

/* Slave address: A0 0C 00 00 / 01 00 00 00 / 00 00 01 00 / 00 00 00 00. */
static void test_fastscan_slave(void)
{
    test_node_t *t = slave(0xFF);
    ingest(t, 0, LSS, "51 00 00 00 00 80 00 00"); /* reset: every unconfigured slave */
    CHECK_STR(BUS(t), "7E4#4F00000000000000");
    fake_clear(&t->bus);
    ingest(t, 0, LSS, "51 00 00 00 00 1F 00 00"); /* bit 31 of vendor is 0: match */
    ingest(t, 0, LSS, "51 00 00 00 00 0C 00 00"); /* bits 31..12 are 0: match */
    ingest(t, 0, LSS, "51 00 00 00 00 0A 00 00"); /* bit 11 is 1: no */
    ingest(t, 0, LSS, "51 00 08 00 00 0A 00 00"); /* bit 11 = 1, 10 = 0: no (bit 10 is 1) */
    ingest(t, 0, LSS, "51 00 0C 00 00 0A 00 00"); /* match */
    ingest(t, 0, LSS, "51 A0 0C 00 00 00 01 02"); /* wrong part (pos is 0): no */
    CHECK_STR(BUS(t), "7E4#4F00000000000000 7E4#4F00000000000000 7E4#4F00000000000000");
    fake_clear(&t->bus);
    /* Verify each part and move on; the last one (3 -> 0) switches to configuration. */
    ingest(t, 0, LSS, "51 A0 0C 00 00 00 00 01");
    ingest(t, 0, LSS, "51 01 00 00 00 00 01 02");
    ingest(t, 0, LSS, "51 00 00 01 00 00 02 03");
    CHECK_EQ(co_lss_slave_mode(&t->node), CO_LSS_WAITING);
    ingest(t, 0, LSS, "51 00 00 00 00 00 03 00");
    CHECK_STR(BUS(t), "7E4#4F00000000000000 7E4#4F00000000000000 7E4#4F00000000000000 "
                      "7E4#4F00000000000000");
    CHECK_EQ(co_lss_slave_mode(&t->node), CO_LSS_CONFIGURATION);
    /* In configuration it no longer takes part. */
    fake_clear(&t->bus);
    ingest(t, 0, LSS, "51 00 00 00 00 80 00 00");
    CHECK_STR(BUS(t), "");
    free(t);
}

static void test_malformed_frames_ignored(void)
{
    test_node_t *t = slave(0xFF);
    uint32_t before = co_node_stats(&t->node)->rx_malformed;
    ingest(t, 0, LSS, "04 01 00 00 00 00 00"); /* 7 bytes */
    ingest(t, 0, LSS, "R8");
    ingest(t, 0, LSS, "04 02 00 00 00 00 00 00"); /* no such mode */
    ingest(t, 0, LSS, "99 00 00 00 00 00 00 00"); /* unknown specifier */
    ingest(t, 0, LSS, "");
    CHECK_EQ(co_node_stats(&t->node)->rx_malformed - before, 5);
    CHECK_EQ(co_lss_slave_mode(&t->node), CO_LSS_WAITING);
    ingest(t, 0, LSS, "51 00 00 00 00 20 00 00"); /* bit checked 32: ignored */
    ingest(t, 0, LSS, "51 00 00 00 00 00 04 00"); /* sub 4: ignored */
    CHECK_STR(BUS(t), "");
    free(t);
}

/* ---- master */

typedef struct done_log {
    co_lss_result_t r[8];
    uint32_t n;
} done_log_t;

static void on_done(void *ctx, const co_lss_result_t *r)
{
    done_log_t *log = ctx;
    if (log->n < 8) {
        log->r[log->n++] = *r;
    }
}

static void test_master_configure_node_id(void)
{
    test_node_t *m = slave(1);
    done_log_t log = {0};
    CHECK_EQ(co_lss_configure_node_id(&m->node, 0, on_done, &log), CO_ERR_ARG);
    CHECK_EQ(co_lss_configure_node_id(&m->node, 5, on_done, &log), CO_OK);
    CHECK_STR(BUS(m), "7E5#1105000000000000");
    CHECK(co_lss_master_busy(&m->node));
    CHECK_EQ(co_lss_store(&m->node, on_done, &log), CO_ERR_BUSY);
    ingest(m, 1 * MS, 0x7E4, "5E 00 00 00 00 00 00 00"); /* not its answer */
    ingest(m, 1 * MS, 0x7E4, "11 00 00 00");             /* short: malformed */
    CHECK_EQ(log.n, 0);
    ingest(m, 2 * MS, 0x7E4, "11 00 00 00 00 00 00 00");
    CHECK_EQ(log.n, 1);
    CHECK_EQ(log.r[0].status, CO_LSS_OK);
    CHECK_EQ(log.r[0].cs, 0x11);
    CHECK(!co_lss_master_busy(&m->node));
    /* Refused, with the error codes. */
    CHECK_EQ(co_lss_configure_bit_timing(&m->node, 0, 9, on_done, &log), CO_OK);
    ingest(m, 3 * MS, 0x7E4, "13 FF 21 00 00 00 00 00");
    CHECK_EQ(log.r[1].status, CO_LSS_REFUSED);
    CHECK_EQ(log.r[1].error, 0xFF);
    CHECK_EQ(log.r[1].spec_error, 0x21);
    CHECK_STR(BUS(m), "7E5#1105000000000000 7E5#1300090000000000");
    CHECK_STR(co_lss_status_name(CO_LSS_REFUSED), "refused by the slave");
    free(m);
}

static void test_master_timeout_and_cancel(void)
{
    test_node_t *m = slave(1);
    done_log_t log = {0};
    CHECK_EQ(co_lss_master_set_timeout(&m->node, 0), CO_ERR_ARG);
    CHECK_EQ(co_lss_master_set_timeout(&m->node, 20), CO_OK);
    co_node_poll(&m->node, 10 * MS);
    CHECK_EQ(co_lss_store(&m->node, on_done, &log), CO_OK);
    CHECK_EQ(co_node_poll(&m->node, 29 * MS), 30 * MS);
    CHECK_EQ(log.n, 0);
    co_node_poll(&m->node, 30 * MS);
    CHECK_EQ(log.n, 1);
    CHECK_EQ(log.r[0].status, CO_LSS_TIMEOUT);
    ingest(m, 31 * MS, 0x7E4, "17 00 00 00 00 00 00 00"); /* too late: ignored */
    CHECK_EQ(log.n, 1);
    CHECK_EQ(co_lss_master_cancel(&m->node), CO_ERR_STATE);
    CHECK_EQ(co_lss_inquire(&m->node, 0x5F, on_done, &log), CO_ERR_ARG);
    CHECK_EQ(co_lss_inquire(&m->node, CO_LSS_CS_INQUIRE_SERIAL, on_done, &log), CO_OK);
    CHECK_EQ(co_lss_master_cancel(&m->node), CO_OK);
    CHECK_EQ(log.r[1].status, CO_LSS_CANCELLED);
    CHECK_STR(BUS(m), "7E5#1700000000000000 7E5#5D00000000000000");
    free(m);
}

static void test_master_inquire_and_selective(void)
{
    test_node_t *m = slave(1);
    done_log_t log = {0};
    co_lss_inquire(&m->node, CO_LSS_CS_INQUIRE_SERIAL, on_done, &log);
    ingest(m, 0, 0x7E4, "5D 78 56 34 12 00 00 00");
    co_lss_inquire(&m->node, CO_LSS_CS_INQUIRE_NODE_ID, on_done, &log);
    ingest(m, 0, 0x7E4, "5E 22 00 00 00 00 00 00");
    CHECK_EQ(log.r[0].value, 0x12345678);
    CHECK_EQ(log.r[1].value, 0x22);
    fake_clear(&m->bus);
    co_lss_address_t a = {0x11223344, 2, 3, 4};
    CHECK_EQ(co_lss_switch_selective(&m->node, &a, on_done, &log), CO_OK);
    CHECK_STR(BUS(m), "7E5#4044332211000000 7E5#4102000000000000 7E5#4203000000000000 "
                      "7E5#4304000000000000");
    ingest(m, 0, 0x7E4, "44 00 00 00 00 00 00 00");
    CHECK_EQ(log.r[2].status, CO_LSS_OK);
    fake_clear(&m->bus);
    CHECK_EQ(co_lss_switch_global(&m->node, CO_LSS_CONFIGURATION), CO_OK);
    CHECK_EQ(co_lss_switch_global(&m->node, (co_lss_mode_t)2), CO_ERR_ARG);
    CHECK_EQ(co_lss_activate_bit_timing(&m->node, 0x1234), CO_OK);
    CHECK_STR(BUS(m), "7E5#0401000000000000 7E5#1534120000000000");
    free(m);
}

static void test_master_identify_counts_answers(void)
{
    test_node_t *m = slave(1);
    done_log_t log = {0};
    co_lss_address_t lo = {0xCA0, 1, 0, 0}, hi = {0, 0, 0x20000, 0xFFFFFFFF};
    CHECK_EQ(co_lss_identify_remote(&m->node, &lo, &hi, on_done, &log), CO_OK);
    CHECK_STR(BUS(m), "7E5#46A00C0000000000 7E5#4701000000000000 7E5#4800000000000000 "
                      "7E5#4900000200000000 7E5#4A00000000000000 7E5#4BFFFFFFFF000000");
    ingest(m, 1 * MS, 0x7E4, "4F 00 00 00 00 00 00 00");
    ingest(m, 2 * MS, 0x7E4, "4F 00 00 00 00 00 00 00");
    CHECK_EQ(log.n, 0); /* waits the whole time-out: more may answer */
    co_node_poll(&m->node, 100 * MS);
    CHECK_EQ(log.r[0].status, CO_LSS_OK);
    CHECK_EQ(log.r[0].answers, 2);
    fake_clear(&m->bus);
    CHECK_EQ(co_lss_identify_non_configured(&m->node, on_done, &log), CO_OK);
    CHECK_STR(BUS(m), "7E5#4C00000000000000");
    co_node_poll(&m->node, 200 * MS);
    CHECK_EQ(log.r[1].status, CO_LSS_TIMEOUT);
    free(m);
}

static void test_master_fastscan_frames(void)
{
    test_node_t *m = slave(1);
    done_log_t log = {0};
    CHECK_EQ(co_lss_fastscan(&m->node, NULL, on_done, &log), CO_OK);
    CHECK_STR(BUS(m), "7E5#5100000000800000");
    fake_clear(&m->bus);
    ingest(m, 1 * MS, 0x7E4, "4F 00 00 00 00 00 00 00");
    co_node_poll(&m->node, 100 * MS);
    CHECK_STR(BUS(m), "7E5#51000000001F0000"); /* vendor bit 31, guess 0 */
    fake_clear(&m->bus);
    co_node_poll(&m->node, 200 * MS); /* nobody: bit 31 is 1 */
    CHECK_STR(BUS(m), "7E5#51000000801E0000");
    /* No answer to the reset: nobody there. */
    co_lss_master_cancel(&m->node);
    co_lss_fastscan(&m->node, NULL, on_done, &log);
    co_node_poll(&m->node, 400 * MS);
    CHECK_EQ(log.r[1].status, CO_LSS_TIMEOUT);
    free(m);
}

/* Above {1, 2, 3, 4}: the prefix verified, then the branch looked for from bit 0 up in the
 * serial; a prefix nobody shares moves the search to that part. */
static void test_master_fastscan_above_frames(void)
{
    test_node_t *m = slave(1);
    done_log_t log = {0};
    co_lss_fastscan_t scan = {.address = {1, 2, 3, 4}, .above = true};
    uint64_t t = 0;
#define STEP(heard, want)                                                                          \
    do {                                                                                           \
        CHECK_STR(BUS(m), want);                                                                   \
        fake_clear(&m->bus);                                                                       \
        if (heard) {                                                                               \
            ingest(m, t + 1 * MS, 0x7E4, "4F 00 00 00 00 00 00 00");                               \
        }                                                                                          \
        t += 100 * MS;                                                                             \
        co_node_poll(&m->node, t);                                                                 \
    } while (0)
    CHECK_EQ(co_lss_fastscan(&m->node, &scan, on_done, &log), CO_OK);
    STEP(true, "7E5#5100000000800000");  /* reset */
    STEP(true, "7E5#5101000000000001");  /* vendor 1, on to part 1 */
    STEP(true, "7E5#5102000000000102");  /* product 2 */
    STEP(true, "7E5#5103000000000203");  /* revision 3 */
    STEP(false, "7E5#5105000000000303"); /* serial 4 = ..100: above it with bit 0 set? */
    STEP(false, "7E5#5106000000010303"); /* bit 1 */
    STEP(true, "7E5#5108000000030303");  /* bit 2 is set in 4: bit 3 -- someone */
    STEP(false, "7E5#5108000000020303"); /* below it, bit 2 guessed 0: nobody, so 1 */
    STEP(true, "7E5#510C000000010303");
    STEP(true, "7E5#510C000000000303");
    STEP(true, "7E5#510C000000000300");  /* the serial 0xC: verify, into configuration */
    STEP(false, "7E5#510C000000000300"); /* the probe */
    CHECK_EQ(log.n, 1);
    CHECK_EQ(log.r[0].status, CO_LSS_OK);
    CHECK_EQ(log.r[0].address.serial, 0xC);
    CHECK_EQ(log.r[0].address.revision, 3);
    CHECK(!log.r[0].keeps_answering);
    /* Nobody with product 2: the branch is looked for in the product, above 2. */
    CHECK_EQ(co_lss_fastscan(&m->node, &scan, on_done, &log), CO_OK);
    STEP(true, "7E5#5100000000800000");
    STEP(true, "7E5#5101000000000001");
    STEP(false, "7E5#5102000000000102");
    STEP(true, "7E5#5100000000800000"); /* again, for a product above 2 */
    STEP(true, "7E5#5101000000000001");
    STEP(false, "7E5#5103000000000101");       /* 2 = ..10: bit 0 */
    STEP(true, "7E5#5104000000020101");        /* bit 1 is set: bit 2 -- someone */
    CHECK_STR(BUS(m), "7E5#5104000000010101"); /* below it, the walk */
    co_lss_master_cancel(&m->node);
    /* Nobody above: every part searched, then none. */
    fake_clear(&m->bus);
    scan.address = (co_lss_address_t){0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFFE};
    CHECK_EQ(co_lss_fastscan(&m->node, &scan, on_done, &log), CO_OK);
    STEP(true, "7E5#5100000000800000");
    STEP(true, "7E5#51FFFFFFFF000001");
    STEP(true, "7E5#51FFFFFFFF000102");
    STEP(true, "7E5#51FFFFFFFF000203");
    STEP(false, "7E5#51FFFFFFFF000303");    /* bit 0, the only 0 */
    for (int part = 2; part >= 0; part--) { /* no 0 bit in parts 2, 1, 0: no query */
        CHECK_EQ(log.n, 2);
        STEP(true, "7E5#5100000000800000");
        for (int p = 0; p < part; p++) {
            char want[32];
            snprintf(want, sizeof want, "7E5#51FFFFFFFF00%02X%02X", p, p + 1);
            STEP(true, want);
        }
    }
    CHECK_EQ(log.n, 3);
    CHECK_EQ(log.r[2].status, CO_LSS_TIMEOUT);
#undef STEP
    free(m);
}

/* ---- master and slave on the simulated bus */

typedef struct pair {
    co_sim_bus_t bus;
    example_od_t od[2];
    co_node_t node[2];
    co_sim_port_t port[2];
    uint32_t ident[4];
} pair_t;

static pair_t *pair_up(void)
{
    pair_t *p = calloc(1, sizeof *p);
    co_sim_bus_init(&p->bus, 250000);
    const uint8_t ids[2] = {1, 0xFF};
    uint32_t ident[4] = {0xCA0, 0xBEEF, 0x00020003, 0x80000001};
    memcpy(p->ident, ident, sizeof ident);
    for (int i = 0; i < 2; i++) {
        co_node_config_t cfg = {.node_id = ids[i], .od = example_od_init(&p->od[i], 0)};
        if (i == 1) {
            for (uint32_t e = 0; e < cfg.od.count; e++) {
                co_od_entry_t *en = &p->od[i].entries[e];
                if (en->index == 0x1018 && en->sub >= 1) {
                    en->dflt = &p->ident[en->sub - 1];
                }
            }
        }
        co_sim_port_attach(&p->bus, &p->port[i]);
        cfg.driver = co_sim_port_driver(&p->port[i]);
        CHECK_EQ(co_node_init(&p->node[i], &cfg), CO_OK);
        co_sim_port_bind(&p->port[i], &p->node[i]);
        co_node_start(&p->node[i], 0);
    }
    co_lss_master_set_timeout(&p->node[0], 5);
    return p;
}

static void test_fastscan_finds_the_slave(void)
{
    pair_t *p = pair_up();
    done_log_t log = {0};
    co_sim_run_until(&p->bus, 10 * MS);
    CHECK_EQ(co_lss_fastscan(&p->node[0], NULL, on_done, &log), CO_OK);
    co_sim_run_until(&p->bus, 2000 * MS);
    CHECK_EQ(log.n, 1);
    CHECK_EQ(log.r[0].status, CO_LSS_OK);
    CHECK_EQ(log.r[0].address.vendor, 0xCA0);
    CHECK_EQ(log.r[0].address.product, 0xBEEF);
    CHECK_EQ(log.r[0].address.revision, 0x00020003);
    CHECK_EQ(log.r[0].address.serial, 0x80000001);
    CHECK_EQ(co_lss_slave_mode(&p->node[1]), CO_LSS_CONFIGURATION);
    CHECK(!log.r[0].keeps_answering); /* quiet in configuration, as CiA 305 has it */
    /* Known vendor and product: only revision and serial are scanned bit by bit. */
    co_lss_switch_global(&p->node[0], CO_LSS_WAITING);
    co_lss_fastscan_t scan = {.address = {0xCA0, 0xBEEF, 0, 0}, .known = 0x3};
    co_sim_run_until(&p->bus, 2100 * MS);
    CHECK_EQ(co_lss_fastscan(&p->node[0], &scan, on_done, &log), CO_OK);
    co_sim_run_until(&p->bus, 2100 * MS + (1 + 2 + 64 + 2 + 1) * 5 * MS);
    CHECK_EQ(log.n, 2);
    CHECK_EQ(log.r[1].status, CO_LSS_OK);
    CHECK_EQ(log.r[1].address.serial, 0x80000001);
    /* A wrong known vendor: the verify finds nobody. */
    co_lss_switch_global(&p->node[0], CO_LSS_WAITING);
    scan.address.vendor = 0xCA1;
    co_sim_run_until(&p->bus, 3000 * MS);
    co_lss_fastscan(&p->node[0], &scan, on_done, &log);
    co_sim_run_until(&p->bus, 4000 * MS);
    CHECK_EQ(log.r[2].status, CO_LSS_SCAN_FAILED);
    free(p);
}

/* ---- a slave that answers every fastscan request in configuration (as CANopenNode's
 * slaves do): a model on a raw port of the simulated bus */

typedef struct chatty_slave {
    co_sim_port_t port;
    uint32_t address[4];
    bool configuration;
    uint8_t pos;
    uint32_t answers;
} chatty_slave_t;

static void chatty_answer(chatty_slave_t *c)
{
    co_frame_t f = frm(0x7E4, "4F 00 00 00 00 00 00 00");
    CHECK_EQ(co_sim_send(&c->port, &f), CO_OK);
    c->answers++;
}

static void chatty_rx(void *ctx, uint64_t now_us, const co_frame_t *f)
{
    (void)now_us;
    chatty_slave_t *c = ctx;
    if (f->id != 0x7E5 || f->len != 8) {
        return;
    }
    const uint8_t *d = f->data;
    if (d[0] == 0x04) { /* switch state global */
        c->configuration = d[1] == 1;
        return;
    }
    if (d[0] != 0x51) {
        return;
    }
    if (c->configuration) { /* every fastscan request is answered */
        chatty_answer(c);
        return;
    }
    uint8_t bit = d[5], sub = d[6], next = d[7];
    if (bit == 0x80) {
        c->pos = 0;
        chatty_answer(c);
        return;
    }
    if (bit > 31 || sub > 3 || next > 3 || sub != c->pos) {
        return;
    }
    uint32_t mask = 0xFFFFFFFFu << bit;
    if (((co_get_u32(d + 1) ^ c->address[sub]) & mask) == 0) {
        chatty_answer(c);
        c->pos = next;
        if (bit == 0 && next < sub) {
            c->configuration = true;
        }
    }
}

static void test_fastscan_tells_a_slave_that_keeps_answering(void)
{
    typedef struct rig {
        co_sim_bus_t bus;
        example_od_t od;
        co_node_t node;
        co_sim_port_t port;
    } rig_t;
    rig_t *r = calloc(1, sizeof *r);
    co_sim_bus_t *bus = &r->bus;
    static chatty_slave_t chatty;
    memset(&chatty, 0, sizeof chatty);
    chatty.address[0] = 0x2E0;
    chatty.address[1] = 0x17;
    chatty.address[2] = 0x3;
    chatty.address[3] = 0x12345678;
    co_sim_bus_init(bus, 500000);
    CHECK_EQ(co_sim_port_attach_raw(bus, &chatty.port, chatty_rx, &chatty), CO_OK);
    co_node_config_t cfg = {.node_id = 1, .od = example_od_init(&r->od, 0)};
    co_sim_port_attach(bus, &r->port);
    cfg.driver = co_sim_port_driver(&r->port);
    CHECK_EQ(co_node_init(&r->node, &cfg), CO_OK);
    co_sim_port_bind(&r->port, &r->node);
    co_node_start(&r->node, 0);
    co_node_t *master = &r->node;
    co_lss_master_set_timeout(master, 5);
    done_log_t log = {0};
    CHECK_EQ(co_lss_fastscan(master, NULL, on_done, &log), CO_OK);
    co_sim_run_until(bus, 2000 * MS);
    CHECK_EQ(log.n, 1);
    CHECK_EQ(log.r[0].status, CO_LSS_OK);
    CHECK_EQ(log.r[0].address.vendor, 0x2E0);
    CHECK_EQ(log.r[0].address.serial, 0x12345678);
    CHECK(log.r[0].keeps_answering);
    CHECK(chatty.configuration);
    /* Left in configuration it would confirm every bit: switched back to waiting, the next
     * scan finds it again, the same address (not the all-zero one). */
    co_lss_switch_global(master, CO_LSS_WAITING);
    co_sim_run_until(bus, 2010 * MS);
    CHECK_EQ(co_lss_fastscan(master, NULL, on_done, &log), CO_OK);
    co_sim_run_until(bus, 4000 * MS);
    CHECK_EQ(log.n, 2);
    CHECK_EQ(log.r[1].status, CO_LSS_OK);
    CHECK_EQ(log.r[1].address.product, 0x17);
    CHECK_EQ(log.r[1].address.serial, 0x12345678);
    /* Back in waiting, it is not above itself: a scan above it finds nobody. */
    co_lss_switch_global(master, CO_LSS_WAITING);
    co_sim_run_until(bus, 4010 * MS);
    co_lss_fastscan_t above = {.address = log.r[1].address, .above = true};
    CHECK_EQ(co_lss_fastscan(master, &above, on_done, &log), CO_OK);
    co_sim_run_until(bus, 6000 * MS);
    CHECK_EQ(log.n, 3);
    CHECK_EQ(log.r[2].status, CO_LSS_TIMEOUT);
    CHECK(!chatty.configuration);
    free(r);
}

/* ---- scenario: eight unconfigured devices, found one by one and given node-IDs 10..17 */

#define FLEET 8

typedef struct fleet {
    co_sim_bus_t bus;
    example_od_t od[FLEET + 1];
    co_node_t node[FLEET + 1]; /* 0 is the master */
    co_sim_port_t port[FLEET + 1];
    uint32_t ident[FLEET + 1][4];
    uint8_t next_id;
    uint32_t scans, found, none;
    co_lss_address_t addresses[FLEET];
    uint32_t bootups[128];
} fleet_t;

static void fleet_rx_trace(void *ctx, const char *line)
{
    fleet_t *f = ctx;
    unsigned id = 0, b = 1;
    const char *p = strstr(line, "sim0 ");
    if (p && sscanf(p + 5, "%x#%2x", &id, &b) == 2 && id > 0x700 && id < 0x780 && b == 0) {
        f->bootups[id - 0x700]++;
    }
}

static void fleet_next(fleet_t *f);

static void fleet_configured(void *ctx, const co_lss_result_t *r)
{
    fleet_t *f = ctx;
    CHECK_EQ(r->status, CO_LSS_OK);
    co_lss_switch_global(&f->node[0], CO_LSS_WAITING); /* the device boots with its ID */
    f->next_id++;
    fleet_next(f);
}

static void fleet_scanned(void *ctx, const co_lss_result_t *r)
{
    fleet_t *f = ctx;
    if (r->status != CO_LSS_OK) {
        f->none++;
        return;
    }
    if (f->found < FLEET) {
        f->addresses[f->found] = r->address;
    }
    f->found++;
    CHECK_EQ(co_lss_configure_node_id(&f->node[0], f->next_id, fleet_configured, f), CO_OK);
}

static void fleet_next(fleet_t *f)
{
    f->scans++;
    CHECK_EQ(co_lss_fastscan(&f->node[0], NULL, fleet_scanned, f), CO_OK);
}

static void test_eight_devices_found_by_fastscan_then_boot(void)
{
    fleet_t *f = calloc(1, sizeof *f);
    co_sim_bus_init(&f->bus, 500000);
    co_sim_set_trace(&f->bus, fleet_rx_trace, f);
    for (int i = 0; i <= FLEET; i++) {
        co_node_config_t cfg = {.node_id = i == 0 ? 1 : 0xFF,
                                .od = example_od_init(&f->od[i], i == 0 ? 0 : 100)};
        /* Same vendor; two products; serials that share long prefixes. */
        uint32_t ident[4] = {0xCA0, 0x100u + (uint32_t)(i & 1), 0x00010000, 0x1000u + (uint32_t)i};
        memcpy(f->ident[i], ident, sizeof ident);
        for (uint32_t e = 0; e < cfg.od.count; e++) {
            co_od_entry_t *en = &f->od[i].entries[e];
            if (en->index == 0x1018 && en->sub >= 1) {
                en->dflt = &f->ident[i][en->sub - 1];
            }
        }
        co_sim_port_attach(&f->bus, &f->port[i]);
        cfg.driver = co_sim_port_driver(&f->port[i]);
        CHECK_EQ(co_node_init(&f->node[i], &cfg), CO_OK);
        co_sim_port_bind(&f->port[i], &f->node[i]);
        co_node_start(&f->node[i], 0);
    }
    co_lss_master_set_timeout(&f->node[0], 10);
    co_sim_run_until(&f->bus, 10 * MS);
    CHECK_EQ(f->bootups[1], 1); /* only the master booted */
    for (int i = 1; i <= FLEET; i++) {
        CHECK_EQ(co_nmt_state(&f->node[i]), CO_NMT_INITIALISING);
    }
    f->next_id = 10;
    fleet_next(f);
    co_sim_run_until(&f->bus, 60000 * MS);
    CHECK_EQ(f->found, FLEET);
    CHECK_EQ(f->none, 1); /* the ninth scan finds nobody left */
    CHECK_EQ(f->scans, FLEET + 1);
    for (int i = 1; i <= FLEET; i++) {
        uint8_t id = co_node_id(&f->node[i]);
        CHECK(id >= 10 && id < 10 + FLEET);
        CHECK_EQ(f->bootups[id], 1);
        CHECK_EQ(co_nmt_state(&f->node[i]), CO_NMT_PRE_OPERATIONAL);
        /* The address found for the ID given is this device's. */
        CHECK_EQ(f->addresses[id - 10].serial, f->ident[i][3]);
        CHECK_EQ(f->addresses[id - 10].product, f->ident[i][1]);
    }
    /* They run as any node now: heartbeats with their new IDs, NMT start reaches them. */
    uint32_t before = f->bootups[10];
    co_nmt_send(&f->node[0], CO_NMT_CMD_START, 0);
    co_sim_run_until(&f->bus, 61000 * MS);
    for (int i = 1; i <= FLEET; i++) {
        CHECK_EQ(co_nmt_state(&f->node[i]), CO_NMT_OPERATIONAL);
    }
    CHECK_EQ(f->bootups[10], before);
    free(f);
}

/* ---- master: arguments, busy, wrong answers and time-outs for every request */

typedef co_err_t (*lss_request_fn)(co_node_t *node, co_lss_done_fn done, void *ctx);

static co_err_t rq_selective(co_node_t *n, co_lss_done_fn d, void *c)
{
    static const co_lss_address_t a = {1, 2, 3, 4};
    return co_lss_switch_selective(n, &a, d, c);
}
static co_err_t rq_node_id(co_node_t *n, co_lss_done_fn d, void *c)
{
    return co_lss_configure_node_id(n, CO_NODE_ID_UNCONFIGURED, d, c);
}
static co_err_t rq_bit_timing(co_node_t *n, co_lss_done_fn d, void *c)
{
    return co_lss_configure_bit_timing(n, 0, 4, d, c);
}
static co_err_t rq_store(co_node_t *n, co_lss_done_fn d, void *c) { return co_lss_store(n, d, c); }
static co_err_t rq_inquire_vendor(co_node_t *n, co_lss_done_fn d, void *c)
{
    return co_lss_inquire(n, CO_LSS_CS_INQUIRE_VENDOR, d, c);
}
static co_err_t rq_identify(co_node_t *n, co_lss_done_fn d, void *c)
{
    static const co_lss_address_t lo = {1, 2, 0, 0}, hi = {1, 2, 9, 9};
    return co_lss_identify_remote(n, &lo, &hi, d, c);
}
static co_err_t rq_non_configured(co_node_t *n, co_lss_done_fn d, void *c)
{
    return co_lss_identify_non_configured(n, d, c);
}
static co_err_t rq_fastscan(co_node_t *n, co_lss_done_fn d, void *c)
{
    return co_lss_fastscan(n, NULL, d, c);
}

static void test_master_arguments(void)
{
    test_node_t *m = slave(1);
    done_log_t log = {0};
    co_lss_address_t a = {0};
    CHECK_EQ(co_lss_master_set_timeout(&m->node, 65536), CO_ERR_ARG);
    CHECK_EQ(co_lss_master_set_timeout(&m->node, 65535), CO_OK);
    CHECK_EQ(co_lss_switch_selective(&m->node, NULL, on_done, &log), CO_ERR_ARG);
    CHECK_EQ(co_lss_configure_node_id(&m->node, 128, on_done, &log), CO_ERR_ARG);
    CHECK_EQ(co_lss_configure_node_id(&m->node, 0xFE, on_done, &log), CO_ERR_ARG);
    CHECK_EQ(co_lss_inquire(&m->node, CO_LSS_CS_INQUIRE_VENDOR - 1, on_done, &log), CO_ERR_ARG);
    CHECK_EQ(co_lss_identify_remote(&m->node, NULL, &a, on_done, &log), CO_ERR_ARG);
    CHECK_EQ(co_lss_identify_remote(&m->node, &a, NULL, on_done, &log), CO_ERR_ARG);
    CHECK(!co_lss_master_busy(&m->node));
    CHECK_STR(BUS(m), ""); /* nothing sent */
    CHECK_EQ(log.n, 0);
    CHECK_STR(co_lss_status_name(CO_LSS_OK), "ok");
    CHECK_STR(co_lss_status_name(CO_LSS_TIMEOUT), "time-out");
    CHECK_STR(co_lss_status_name(CO_LSS_SCAN_FAILED), "fastscan lost the slave");
    CHECK_STR(co_lss_status_name(CO_LSS_CANCELLED), "cancelled");
    CHECK_STR(co_lss_status_name(99), "unknown");
    free(m);
}

static void test_master_every_request_busy_and_timed_out(void)
{
    static const lss_request_fn requests[] = {rq_selective,      rq_node_id,        rq_bit_timing,
                                              rq_store,          rq_inquire_vendor, rq_identify,
                                              rq_non_configured, rq_fastscan};
    /* An answer of the wrong kind for each: another request's answer. */
    static const char *wrong[] = {"43 00 00 00 00 00 00 00", "13 00 00 00 00 00 00 00",
                                  "11 00 00 00 00 00 00 00", "5E 00 00 00 00 00 00 00",
                                  "5B 00 00 00 00 00 00 00", "50 00 00 00 00 00 00 00",
                                  "4F 00 00 00 00 00 00 00", "50 00 00 00 00 00 00 00"};
    const uint32_t count = sizeof requests / sizeof requests[0];
    test_node_t *m = slave(1);
    CHECK_EQ(co_lss_master_set_timeout(&m->node, 10), CO_OK);
    uint64_t now = 0;
    for (uint32_t i = 0; i < count; i++) {
        done_log_t log = {0};
        fake_clear(&m->bus);
        CHECK_EQ(requests[i](&m->node, on_done, &log), CO_OK);
        uint32_t sent = m->bus.count;
        CHECK(sent >= 1);
        /* While it runs every other request is refused and sends nothing. */
        for (uint32_t j = 0; j < count; j++) {
            CHECK_EQ(requests[j](&m->node, on_done, &log), CO_ERR_BUSY);
        }
        CHECK_EQ(m->bus.count, sent);
        /* A wrong answer, and a remote frame, are not the answer. */
        ingest(m, now + 1 * MS, 0x7E4, wrong[i]);
        co_frame_t rtr = frm(0x7E4, "R8");
        co_node_ingest(&m->node, now + 1 * MS, &rtr);
        CHECK_EQ(log.n, 0);
        CHECK(co_lss_master_busy(&m->node));
        /* Nobody answers: a time-out after 10 ms (fastscan: after its reset step). */
        co_node_poll(&m->node, now + 10 * MS);
        CHECK_EQ(log.n, 1);
        CHECK_EQ(log.r[0].status, CO_LSS_TIMEOUT);
        CHECK_EQ(log.r[0].answers, 0);
        CHECK(!co_lss_master_busy(&m->node));
        now += 20 * MS;
        co_node_poll(&m->node, now);
    }
    CHECK(m->node.stats.rx_malformed >= count);
    /* Without a callback a request still ends, and the master is free again. */
    for (uint32_t i = 0; i < count; i++) {
        CHECK_EQ(requests[i](&m->node, NULL, NULL), CO_OK);
        co_node_poll(&m->node, now + 10 * MS);
        CHECK(!co_lss_master_busy(&m->node));
        now += 20 * MS;
    }
    free(m);
}

static void test_master_answers_without_callback(void)
{
    test_node_t *m = slave(1);
    CHECK_EQ(co_lss_inquire(&m->node, CO_LSS_CS_INQUIRE_PRODUCT, NULL, NULL), CO_OK);
    ingest(m, 1 * MS, 0x7E4, "5B 01 02 03 04 00 00 00");
    CHECK(!co_lss_master_busy(&m->node));
    /* Identify non-configured: the answers are counted until the time-out. */
    done_log_t log = {0};
    CHECK_EQ(co_lss_identify_non_configured(&m->node, on_done, &log), CO_OK);
    ingest(m, 2 * MS, 0x7E4, "4F 00 00 00 00 00 00 00"); /* identify answer: not this one */
    ingest(m, 3 * MS, 0x7E4, "50 00 00 00 00 00 00 00");
    ingest(m, 4 * MS, 0x7E4, "50 00 00 00 00 00 00 00");
    ingest(m, 5 * MS, 0x7E4, "50 00 00 00 00 00 00 00");
    CHECK_EQ(log.n, 0);
    co_node_poll(&m->node, 200 * MS);
    CHECK_EQ(log.n, 1);
    CHECK_EQ(log.r[0].status, CO_LSS_OK);
    CHECK_EQ(log.r[0].answers, 3);
    CHECK_EQ(log.r[0].cs, CO_LSS_CS_IDENT_NON_CONFIGURED);
    /* Store refused by the slave (error 1: not supported). */
    CHECK_EQ(co_lss_store(&m->node, on_done, &log), CO_OK);
    ingest(m, 300 * MS, 0x7E4, "17 01 00 00 00 00 00 00");
    CHECK_EQ(log.n, 2);
    CHECK_EQ(log.r[1].status, CO_LSS_REFUSED);
    CHECK_EQ(log.r[1].error, 1);
    free(m);
}

/* ---- slave: arguments and the requests it must not answer */

static void test_slave_setup_arguments(void)
{
    test_node_t *t = slave(5);
    co_lss_slave_config_t lc = {.bit_timings = 1u << 3};
    CHECK_EQ(co_lss_slave_setup(NULL, &lc), CO_ERR_ARG);
    CHECK_EQ(co_lss_slave_setup(&t->node, NULL), CO_ERR_ARG);
    /* Nothing was taken: bit timing 3 is still unsupported. */
    to_config(t);
    ingest(t, 0, LSS, "13 00 03 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#1301000000000000");
    free(t);
}

static void test_slave_bit_timing_edges(void)
{
    test_node_t *t = slave(5);
    /* Every table-0 index supported, but no callback to switch the controller. */
    co_lss_slave_config_t lc = {.bit_timings = 0xFFFF};
    CHECK_EQ(co_lss_slave_setup(&t->node, &lc), CO_OK);
    to_config(t);
    ingest(t, 0, LSS, "13 00 10 00 00 00 00 00"); /* index 16: beyond the table */
    ingest(t, 0, LSS, "13 00 0F 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#1301000000000000 7E4#1300000000000000");
    fake_clear(&t->bus);
    ingest(t, 100 * MS, LSS, "15 0A 00 00 00 00 00 00"); /* switch after 10 ms */
    CHECK_EQ(co_node_poll(&t->node, 100 * MS), 110 * MS);
    CHECK_EQ(co_node_poll(&t->node, 105 * MS), 110 * MS);
    CHECK_EQ(co_node_poll(&t->node, 110 * MS), 120 * MS); /* nothing to call; quiet */
    CHECK_EQ(co_lss_slave_mode(&t->node), CO_LSS_CONFIGURATION);
    ingest(t, 120 * MS, LSS, "5E 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "7E4#5E05000000000000");
    free(t);
}

static void test_slave_ignores_out_of_place_requests(void)
{
    test_node_t *t = slave(0xFF);
    /* Fastscan: after the reset, a frame naming part 4 as the next is not answered. */
    ingest(t, 0, LSS, "51 00 00 00 00 80 00 00");
    CHECK_STR(BUS(t), "7E4#4F00000000000000");
    fake_clear(&t->bus);
    ingest(t, 0, LSS, "51 00 00 00 00 1F 00 04");
    CHECK_STR(BUS(t), "");
    ingest(t, 0, LSS, "51 00 00 00 00 1F 00 00"); /* the same with next 0: answered */
    CHECK_STR(BUS(t), "7E4#4F00000000000000");
    /* Switch selective is for slaves waiting: one in configuration does not answer. */
    to_config(t);
    fake_clear(&t->bus);
    ingest(t, 0, LSS, "40 A0 0C 00 00 00 00 00");
    ingest(t, 0, LSS, "41 01 00 00 00 00 00 00");
    ingest(t, 0, LSS, "42 00 00 01 00 00 00 00");
    ingest(t, 0, LSS, "43 00 00 00 00 00 00 00");
    CHECK_STR(BUS(t), "");
    CHECK_EQ(co_lss_slave_mode(&t->node), CO_LSS_CONFIGURATION);
    free(t);
}

int main(void)
{
    RUN(test_unconfigured_node_sends_nothing_and_waits);
    RUN(test_inquire_in_configuration_only);
    RUN(test_configure_node_id_then_boot);
    RUN(test_configured_node_takes_new_id_at_reset_communication);
    RUN(test_configure_unconfigured_again);
    RUN(test_bit_timing_configure_and_activate);
    RUN(test_bit_timing_switch_waits_for_its_delay);
    RUN(test_nothing_sent_in_the_quiet_time_after_the_switch);
    RUN(test_store_configuration);
    RUN(test_switch_selective);
    RUN(test_identify_remote_slave);
    RUN(test_identify_non_configured);
    RUN(test_fastscan_slave);
    RUN(test_malformed_frames_ignored);
    RUN(test_master_configure_node_id);
    RUN(test_master_timeout_and_cancel);
    RUN(test_master_inquire_and_selective);
    RUN(test_master_identify_counts_answers);
    RUN(test_master_fastscan_frames);
    RUN(test_master_fastscan_above_frames);
    RUN(test_fastscan_finds_the_slave);
    RUN(test_fastscan_tells_a_slave_that_keeps_answering);
    RUN(test_eight_devices_found_by_fastscan_then_boot);
    RUN(test_master_arguments);
    RUN(test_master_every_request_busy_and_timed_out);
    RUN(test_master_answers_without_callback);
    RUN(test_slave_setup_arguments);
    RUN(test_slave_bit_timing_edges);
    RUN(test_slave_ignores_out_of_place_requests);
    return check_summary();
}
