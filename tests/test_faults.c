/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_faults.c -- fault injection on the simulated bus: what a real network does to a
 * device, and what the device must do about it.
 *
 * Frame loss and corruption during segmented and block SDO (many seeds), bus-off and
 * recovery, two nodes with the same node-ID, SYNC with jitter and SYNC that stops, a
 * heartbeat producer that stops and resumes, an SDO client that vanishes mid-transfer.
 */
#include <stdlib.h>

#include "canola/sim.h"
#include "check.h"
#include "example_od_domain.h"
#include "harness.h"
#include "pattern_domain.h"

#define MS 1000ull
#define TIMEOUT_MS 1000ull /* the default SDO time-out */

/* ---- stations */

/* A node with the example dictionary plus 0x3000, a streamed DOMAIN (pattern_domain.h). */
typedef struct station {
    example_od_t od;
    co_od_entry_t entries[EXAMPLE_OD_MAX_ENTRIES + 1];
    pattern_domain_t obj;
    co_node_t node;
    co_sim_port_t port;
    co_ec_event_t events[64];
    uint32_t event_count;
    co_emcy_msg_t emcys[64];
    uint32_t emcy_count;
} station_t;

static void on_event(void *user, const co_ec_event_t *ev)
{
    station_t *s = user;
    if (s->event_count < 64) {
        s->events[s->event_count++] = *ev;
    }
}

static void on_emcy(void *user, const co_emcy_msg_t *msg)
{
    station_t *s = user;
    if (s->emcy_count < 64) {
        s->emcys[s->emcy_count++] = *msg;
    }
}

static uint32_t count_events(const station_t *s, co_ec_event_kind_t kind, uint8_t id)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->event_count; i++) {
        n += s->events[i].kind == kind && s->events[i].node_id == id;
    }
    return n;
}

static uint32_t count_emcy(const station_t *s, uint32_t cob, uint16_t code)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < s->emcy_count; i++) {
        n += s->emcys[i].cob_id == cob && s->emcys[i].code == code;
    }
    return n;
}

static void station_init(co_sim_bus_t *bus, station_t *s, uint8_t id, uint16_t hb_ms)
{
    co_node_config_t cfg = {.node_id = id, .od = example_od_with_domain(&s->od, hb_ms, s->entries)};
    cfg.od.hook_ctx = &s->obj;
    cfg.user = s;
    cfg.on_errctl = on_event;
    cfg.on_emcy = on_emcy;
    CHECK_EQ(co_sim_port_attach(bus, &s->port), CO_OK);
    cfg.driver = co_sim_port_driver(&s->port);
    CHECK_EQ(co_node_init(&s->node, &cfg), CO_OK);
    co_sim_port_bind(&s->port, &s->node);
}

static void station_start(co_sim_bus_t *bus, station_t *s)
{
    CHECK_EQ(co_node_start(&s->node, bus->now_us), CO_OK);
}

static co_abort_t set_u32(station_t *s, uint16_t index, uint8_t sub, uint32_t v, uint32_t len)
{
    uint8_t b[4];
    co_put_u32(b, v);
    return co_node_write_net(&s->node, index, sub, b, len);
}

/* A raw port that records every frame with its time. */
#define TAP_MAX 4096
typedef struct tap {
    co_sim_port_t port;
    co_frame_t frames[TAP_MAX];
    uint64_t at[TAP_MAX];
    uint32_t count;
} tap_t;

static void tap_rx(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    tap_t *t = ctx;
    if (t->count < TAP_MAX) {
        t->at[t->count] = now_us;
        t->frames[t->count++] = *frame;
    }
}

static uint32_t tap_count(const tap_t *t, uint32_t id, uint64_t from_us)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < t->count; i++) {
        n += t->frames[i].id == id && t->at[i] >= from_us;
    }
    return n;
}

/* The latest frame with this COB-ID, or NULL. */
static const co_frame_t *tap_last(const tap_t *t, uint32_t id)
{
    for (uint32_t i = t->count; i-- > 0;) {
        if (t->frames[i].id == id) {
            return &t->frames[i];
        }
    }
    return NULL;
}

static void send_raw(tap_t *t, uint32_t id, const char *hex)
{
    co_frame_t f = frm(id, hex);
    CHECK_EQ(co_sim_send(&t->port, &f), CO_OK);
}

/* ---- SDO through loss and corruption */

/* Codes a lossy bus may legitimately end a transfer with: a frame that never came (the
 * time-out) or one that came out of place (the protocol's own checks). */
static bool loss_code(co_abort_t code)
{
    return code == CO_ABORT_TIMEOUT || code == CO_ABORT_COMMAND || code == CO_ABORT_TOGGLE ||
           code == CO_ABORT_SEQUENCE;
}

typedef struct tally {
    uint32_t ok, aborted, wrong, hung, bad_code, block_wrong;
} tally_t;

/* `transfers` transfers between client 1 and server 5 with the bus's faults on; each must
 * end (done exactly once) within the time-out after its last frame. */
static void sdo_under_faults(uint64_t seed, double drop_p, double corrupt_p, uint32_t transfers,
                             tally_t *t)
{
    co_sim_bus_t *bus = calloc(1, sizeof *bus);
    station_t *srv = calloc(1, sizeof *srv);
    station_t *cli = calloc(1, sizeof *cli);
    const uint32_t cap = 600;
    uint8_t *buf = malloc(cap);
    co_sim_bus_init(bus, 1000000);
    station_init(bus, srv, 5, 0);
    station_init(bus, cli, 1, 0);
    station_start(bus, srv);
    station_start(bus, cli);
    CHECK_EQ(co_sdo_client_setup(&cli->node, 0, 5), CO_OK);
    co_sim_run_until(bus, 1 * MS);
    co_sim_seed(bus, seed);
    co_sim_drop_probability(bus, drop_p);
    co_sim_corrupt_probability(bus, corrupt_p);
    for (uint32_t i = 0; i < transfers; i++) {
        uint32_t size = (uint32_t)((seed * 131u + i * 97u) % cap);
        bool upload = (i + seed) % 2 == 0;
        co_sdo_mode_t mode = (i / 2) % 2 ? CO_SDO_BLOCK : CO_SDO_SEGMENTED;
        uint32_t pattern = (uint32_t)(seed * 1000u + i);
        srv->obj = (pattern_domain_t){.length = size, .up_seed = pattern, .down_seed = pattern};
        sdo_result_t r = {0};
        co_err_t err;
        if (upload) {
            memset(buf, 0, cap);
            err = co_sdo_upload(&cli->node, 0, 0x3000, 0, mode, buf, cap, sdo_result_done, &r);
        } else {
            pattern_fill(buf, pattern, size);
            err = co_sdo_download(&cli->node, 0, 0x3000, 0, mode, buf, size, sdo_result_done, &r);
        }
        CHECK_EQ(err, CO_OK);
        /* ~200 frames of ~0.13 ms, then at most one time-out: 2 s is plenty. */
        co_sim_run_until(bus, bus->now_us + 2000 * MS);
        if (r.calls != 1) {
            t->hung++;
            printf("  seed %llu transfer %u: done ran %d times\n", (unsigned long long)seed, i,
                   r.calls);
            continue;
        }
        if (r.abort == CO_ABORT_NONE) {
            bool right = upload ? r.len == size && pattern_matches(buf, pattern, size)
                                : pattern_domain_received(&srv->obj, size);
            t->ok += right;
            t->wrong += !right;
            t->block_wrong += !right && mode == CO_SDO_BLOCK;
        } else {
            t->aborted++;
            /* With corruption an abort frame's code bytes may be hit too: the client
             * reports what the wire said, so only "not success" is certain. */
            bool fits = corrupt_p > 0 ? r.abort != CO_ABORT_NONE : loss_code(r.abort);
            if (!fits) {
                t->bad_code++;
                printf("  seed %llu transfer %u: abort 0x%08X\n", (unsigned long long)seed, i,
                       (unsigned)r.abort);
            }
        }
        /* A server that missed the end times out before the next transfer. */
        co_sim_run_until(bus, bus->now_us + (TIMEOUT_MS + 100) * MS);
    }
    /* Faults off: both sides are usable again. */
    co_sim_drop_probability(bus, 0);
    co_sim_corrupt_probability(bus, 0);
    srv->obj = (pattern_domain_t){.length = 100, .up_seed = 1};
    sdo_result_t r = {0};
    CHECK_EQ(co_sdo_upload(&cli->node, 0, 0x3000, 0, CO_SDO_BLOCK, buf, cap, sdo_result_done, &r),
             CO_OK);
    co_sim_run_until(bus, bus->now_us + 100 * MS);
    CHECK_EQ(r.calls, 1);
    CHECK_EQ(r.abort, CO_ABORT_NONE);
    CHECK(pattern_matches(buf, 1, 100));
    free(buf);
    free(cli);
    free(srv);
    free(bus);
}

static void test_sdo_with_frame_loss_many_seeds(void)
{
    tally_t t = {0};
    for (uint64_t seed = 1; seed <= 24; seed++) {
        sdo_under_faults(seed, 0.02, 0, 24, &t);
    }
    printf("  loss 2%%: %u ok, %u aborted, %u wrong, %u hung\n", t.ok, t.aborted, t.wrong, t.hung);
    CHECK_EQ(t.hung, 0);
    CHECK_EQ(t.wrong, 0); /* a lost frame never turns into wrong data */
    CHECK_EQ(t.bad_code, 0);
    CHECK(t.ok > 0);
    CHECK(t.aborted > 0); /* the faults did bite */
}

static void test_sdo_with_corruption_many_seeds(void)
{
    tally_t t = {0};
    for (uint64_t seed = 100; seed < 124; seed++) {
        sdo_under_faults(seed, 0.01, 0.02, 24, &t);
    }
    printf("  loss 1%% + corruption 2%%: %u ok, %u aborted, %u wrong (segmented: no checksum), "
           "%u hung\n",
           t.ok, t.aborted, t.wrong, t.hung);
    CHECK_EQ(t.hung, 0);
    CHECK_EQ(t.bad_code, 0);
    /* Block transfer carries a CRC: a flipped data bit is an abort, never wrong data. */
    CHECK_EQ(t.block_wrong, 0);
    CHECK(t.aborted > 0);
    CHECK(t.ok > 0);
}

/* ---- bus-off */

/* Device 5 beats every 50 ms; master 1 consumes its heartbeat (150 ms) and its EMCY. */
typedef struct net {
    co_sim_bus_t bus;
    station_t master;
    station_t dev;
    tap_t tap;
} net_t;

static net_t *net_up(uint8_t error_behaviour)
{
    net_t *n = calloc(1, sizeof *n);
    co_sim_bus_init(&n->bus, 500000);
    CHECK_EQ(co_sim_port_attach_raw(&n->bus, &n->tap.port, tap_rx, &n->tap), CO_OK);
    station_init(&n->bus, &n->master, 1, 0);
    station_init(&n->bus, &n->dev, 5, 50);
    station_start(&n->bus, &n->master);
    station_start(&n->bus, &n->dev);
    CHECK_EQ(set_u32(&n->master, 0x1016, 1, hb_consumer_value(5, 150), 4), CO_ABORT_NONE);
    CHECK_EQ(set_u32(&n->master, 0x1028, 1, 0x85, 4), CO_ABORT_NONE);
    CHECK_EQ(set_u32(&n->dev, 0x1029, 1, error_behaviour, 1), CO_ABORT_NONE);
    co_sim_run_until(&n->bus, 10 * MS);
    send_raw(&n->tap, 0x000, "01 05"); /* start the device */
    co_sim_run_until(&n->bus, 200 * MS);
    CHECK_EQ(co_nmt_state(&n->dev.node), CO_NMT_OPERATIONAL);
    return n;
}

static void bus_off_and_back(uint8_t error_behaviour, co_nmt_state_t expected)
{
    net_t *n = net_up(error_behaviour);
    co_sim_bus_t *bus = &n->bus;
    /* The controller goes bus-off; the driver tells the node. */
    co_sim_set_bus_off(&n->dev.port, true);
    co_node_bus_event(&n->dev.node, CO_BUS_OFF);
    CHECK_EQ(co_nmt_state(&n->dev.node), expected);
    uint64_t off_at = bus->now_us;
    co_sim_run_until(bus, off_at + 400 * MS);
    /* Nothing of it reached the bus; the master noticed the silence. */
    CHECK_EQ(tap_count(&n->tap, 0x705, off_at + 1 * MS), 0); /* (one may have been on the wire) */
    CHECK_EQ(count_events(&n->master, CO_EC_HB_TIMEOUT, 5), 1);
    /* Recovery: EMCY 0x8140 when the state allows EMCY, heartbeats with the state of 0x1029. */
    co_sim_set_bus_off(&n->dev.port, false);
    co_node_bus_event(&n->dev.node, CO_BUS_OFF_RECOVERED);
    uint64_t back_at = bus->now_us;
    co_sim_run_until(bus, back_at + 200 * MS);
    CHECK(co_emcy_active(&n->dev.node, 0x8140));
    CHECK_EQ(count_events(&n->master, CO_EC_HB_RESUMED, 5), 1);
    const co_frame_t *hb = tap_last(&n->tap, 0x705);
    CHECK(hb != NULL && hb->len == 1 && hb->data[0] == (uint8_t)expected);
    uint32_t emcys = count_emcy(&n->master, 0x85, 0x8140);
    if (expected == CO_NMT_STOPPED) {
        CHECK_EQ(emcys, 0); /* no EMCY while stopped: it waits ... */
        send_raw(&n->tap, 0x000, "80 05");
        co_sim_run_until(bus, bus->now_us + 10 * MS);
        emcys = count_emcy(&n->master, 0x85, 0x8140); /* ... for pre-operational */
    }
    CHECK_EQ(emcys, 1);
    free(n);
}

static void test_bus_off_error_behaviour_pre_operational(void)
{
    bus_off_and_back(0, CO_NMT_PRE_OPERATIONAL);
}

static void test_bus_off_error_behaviour_no_change(void)
{
    bus_off_and_back(1, CO_NMT_OPERATIONAL);
}

static void test_bus_off_error_behaviour_stopped(void) { bus_off_and_back(2, CO_NMT_STOPPED); }

/* ---- two nodes with one node-ID */

static void test_duplicate_node_id_is_reported(void)
{
    net_t *n = net_up(1);
    co_sim_bus_t *bus = &n->bus;
    station_t *twin = calloc(1, sizeof *twin);
    station_init(bus, twin, 5, 50); /* a second device configured as node 5 */
    station_start(bus, twin);       /* its boot-up reaches the first */
    co_sim_run_until(bus, bus->now_us + 500 * MS);
    /* Each saw the other's boot-up or heartbeat on its own COB-ID 0x705: one report each,
     * not one per heartbeat. */
    CHECK_EQ(count_events(&n->dev, CO_EC_ID_COLLISION, 5), 1);
    CHECK_EQ(count_events(twin, CO_EC_ID_COLLISION, 5), 1);
    CHECK(co_emcy_active(&n->dev.node, 0x8150));
    CHECK(co_emcy_active(&twin->node, 0x8150));
    CHECK_EQ(count_emcy(&n->master, 0x85, 0x8150), 2); /* the network hears about it */
    /* The first heard the twin's boot-up (state 0); cleared, the next heartbeat reports again. */
    CHECK_EQ(n->dev.events[0].state, 0);
    CHECK_EQ(co_emcy_clear(&n->dev.node, 0x8150), CO_OK);
    co_sim_run_until(bus, bus->now_us + 100 * MS);
    CHECK_EQ(count_events(&n->dev, CO_EC_ID_COLLISION, 5), 2);
    free(twin);
    free(n);
}

/* ---- SYNC jitter and missing SYNC */

static void test_sync_jitter_window_and_missing_sync(void)
{
    net_t *n = net_up(0);
    co_sim_bus_t *bus = &n->bus;
    station_t *dev = &n->dev;
    /* RPDO1 synchronous (type 0) with a 50 ms deadline; TPDO1 on every SYNC; window 4 ms. */
    CHECK_EQ(set_u32(dev, 0x1400, 2, 0, 1), CO_ABORT_NONE);
    CHECK_EQ(set_u32(dev, 0x1400, 5, 50, 2), CO_ABORT_NONE);
    CHECK_EQ(set_u32(dev, 0x1800, 2, 1, 1), CO_ABORT_NONE);
    CHECK_EQ(set_u32(dev, 0x1007, 0, 4000, 4), CO_ABORT_NONE);
    srand(7);
    uint64_t t = bus->now_us;
    uint32_t syncs = 0;
    uint8_t expect = dev->od.outputs[0];
    uint8_t pending = 0; /* value sent inside the window, applied at the next SYNC */
    bool have_pending = false;
    uint64_t first_sync = 0;
    for (uint32_t cycle = 0; cycle < 100; cycle++) {
        /* SYNC every 10 ms +- 3 ms. */
        t += 10 * MS + (uint64_t)(rand() % 6001) - 3000;
        co_sim_run_until(bus, t);
        send_raw(&n->tap, 0x080, "");
        co_sim_run_until(bus, t + 500); /* an empty frame takes ~0.1 ms at 500 kbit/s */
        first_sync = first_sync ? first_sync : t;
        syncs++;
        if (have_pending) {
            expect = pending;
            have_pending = false;
        }
        CHECK_EQ(dev->od.outputs[0], expect);
        /* The RPDO comes well inside (1..3.5 ms) or well outside (4.5..6.5 ms) the 4 ms
         * window after the SYNC: inside it is kept for the next SYNC, outside dropped. */
        bool inside = rand() % 2 == 0;
        uint64_t offset =
            inside ? 1000u + (uint64_t)(rand() % 2500) : 4500u + (uint64_t)(rand() % 2000);
        uint8_t v = (uint8_t)(cycle + 1);
        co_sim_run_until(bus, t + offset);
        char hex[16];
        snprintf(hex, sizeof hex, "%02X 00 00 00", v);
        send_raw(&n->tap, 0x205, hex);
        pending = v;
        have_pending = inside;
    }
    co_sim_run_until(bus, t + 1 * MS);
    /* One TPDO per SYNC, all within the window; no deadline missed with 13 ms gaps. */
    CHECK_EQ(tap_count(&n->tap, 0x185, first_sync), syncs);
    CHECK_EQ(count_emcy(&n->master, 0x85, 0x8250), 0);
    CHECK_EQ(co_nmt_state(&dev->node), CO_NMT_OPERATIONAL);
    /* SYNC and RPDOs stop: the deadline passes, EMCY 0x8250, 0x1029 = 0 -> pre-operational,
     * and no more synchronous TPDOs. */
    uint64_t last_tpdo = tap_count(&n->tap, 0x185, 0);
    co_sim_run_until(bus, t + 200 * MS);
    CHECK_EQ(count_emcy(&n->master, 0x85, 0x8250), 1);
    CHECK_EQ(co_nmt_state(&dev->node), CO_NMT_PRE_OPERATIONAL);
    CHECK_EQ(tap_count(&n->tap, 0x185, 0), last_tpdo);
    free(n);
}

/* ---- a heartbeat producer that stops and resumes */

static void test_heartbeat_stops_and_resumes(void)
{
    net_t *n = net_up(1);
    co_sim_bus_t *bus = &n->bus;
    uint64_t stop_at = bus->now_us;
    CHECK_EQ(set_u32(&n->dev, 0x1017, 0, 0, 2), CO_ABORT_NONE);
    co_sim_run_until(bus, stop_at + 140 * MS);
    CHECK_EQ(count_events(&n->master, CO_EC_HB_TIMEOUT, 5), 0); /* < 150 ms since the last */
    co_sim_run_until(bus, stop_at + 400 * MS);
    CHECK_EQ(count_events(&n->master, CO_EC_HB_TIMEOUT, 5), 1); /* once, not per period */
    CHECK(co_emcy_active(&n->master.node, 0x8130));
    uint64_t resume_at = bus->now_us;
    CHECK_EQ(set_u32(&n->dev, 0x1017, 0, 50, 2), CO_ABORT_NONE);
    co_sim_run_until(bus, resume_at + 60 * MS);
    CHECK_EQ(count_events(&n->master, CO_EC_HB_RESUMED, 5), 1);
    CHECK_EQ(count_events(&n->master, CO_EC_HB_TIMEOUT, 5), 1);
    CHECK(!co_emcy_active(&n->master.node, 0x8130)); /* communication is back */
    /* And monitoring goes on: a second silence is a second timeout. */
    CHECK_EQ(set_u32(&n->dev, 0x1017, 0, 0, 2), CO_ABORT_NONE);
    co_sim_run_until(bus, bus->now_us + 300 * MS);
    CHECK_EQ(count_events(&n->master, CO_EC_HB_TIMEOUT, 5), 2);
    free(n);
}

/* ---- an SDO client that vanishes */

static const co_frame_t *sdo_abort_after(const tap_t *t, uint64_t from_us, uint64_t *at)
{
    for (uint32_t i = 0; i < t->count; i++) {
        if (t->frames[i].id == 0x585 && t->at[i] >= from_us && t->frames[i].data[0] == 0x80) {
            *at = t->at[i];
            return &t->frames[i];
        }
    }
    return NULL;
}

/* The server is usable again: an expedited read of 0x1000 is answered. */
static void check_server_answers(net_t *n)
{
    uint64_t from = n->bus.now_us;
    send_raw(&n->tap, 0x605, "40 00 10 00 00 00 00 00");
    co_sim_run_until(&n->bus, from + 10 * MS);
    const co_frame_t *f = tap_last(&n->tap, 0x585);
    CHECK(f != NULL && f->data[0] == 0x43 && co_get_u32(&f->data[4]) == n->dev.od.device_type);
}

static void test_client_vanishes_mid_block_download(void)
{
    net_t *n = net_up(1);
    co_sim_bus_t *bus = &n->bus;
    n->dev.obj = (pattern_domain_t){.length = 1000, .down_seed = 3};
    send_raw(&n->tap, 0x605, "C6 00 30 00 E8 03 00 00"); /* 1000 bytes, CRC */
    co_sim_run_until(bus, bus->now_us + 5 * MS);
    const co_frame_t *ack = tap_last(&n->tap, 0x585);
    CHECK(ack != NULL && ack->data[0] == 0xA4 && ack->data[4] >= 3);
    /* Three segments of the sub-block, then nothing. */
    send_raw(&n->tap, 0x605, "01 00 00 00 00 00 00 00");
    send_raw(&n->tap, 0x605, "02 00 00 00 00 00 00 00");
    send_raw(&n->tap, 0x605, "03 00 00 00 00 00 00 00");
    co_sim_run_until(bus, bus->now_us + 1 * MS);
    uint64_t last = bus->now_us;
    co_sim_run_until(bus, last + 2000 * MS);
    uint64_t at = 0;
    const co_frame_t *ab = sdo_abort_after(&n->tap, last - 1 * MS, &at);
    CHECK(ab != NULL);
    if (ab) {
        CHECK_EQ(co_get_u32(&ab->data[4]), CO_ABORT_TIMEOUT);
        CHECK_EQ(co_get_u16(&ab->data[1]), 0x3000);
        CHECK(at >= last + (TIMEOUT_MS - 2) * MS && at <= last + (TIMEOUT_MS + 2) * MS);
    }
    CHECK(!n->dev.obj.complete);
    check_server_answers(n);
    free(n);
}

static void test_client_vanishes_mid_block_upload(void)
{
    net_t *n = net_up(1);
    co_sim_bus_t *bus = &n->bus;
    n->dev.obj = (pattern_domain_t){.length = 1000, .up_seed = 3};
    send_raw(&n->tap, 0x605, "A4 00 30 00 10 00 00 00"); /* blksize 16, CRC */
    co_sim_run_until(bus, bus->now_us + 5 * MS);
    const co_frame_t *init = tap_last(&n->tap, 0x585);
    CHECK(init != NULL && (init->data[0] & 0xF9) == 0xC0);
    send_raw(&n->tap, 0x605, "A3 00 00 00 00 00 00 00"); /* start: a sub-block comes */
    co_sim_run_until(bus, bus->now_us + 10 * MS);
    uint64_t last = bus->now_us;
    CHECK(tap_count(&n->tap, 0x585, last - 10 * MS) == 16);
    /* No acknowledgement ever: the server gives up after the time-out. */
    co_sim_run_until(bus, last + 2000 * MS);
    uint64_t at = 0;
    const co_frame_t *ab = sdo_abort_after(&n->tap, last - 10 * MS, &at);
    CHECK(ab != NULL);
    if (ab) {
        CHECK_EQ(co_get_u32(&ab->data[4]), CO_ABORT_TIMEOUT);
        CHECK(at <= last + (TIMEOUT_MS + 2) * MS);
    }
    check_server_answers(n);
    free(n);
}

int main(void)
{
    RUN(test_sdo_with_frame_loss_many_seeds);
    RUN(test_sdo_with_corruption_many_seeds);
    RUN(test_bus_off_error_behaviour_pre_operational);
    RUN(test_bus_off_error_behaviour_no_change);
    RUN(test_bus_off_error_behaviour_stopped);
    RUN(test_duplicate_node_id_is_reported);
    RUN(test_sync_jitter_window_and_missing_sync);
    RUN(test_heartbeat_stops_and_resumes);
    RUN(test_client_vanishes_mid_block_download);
    RUN(test_client_vanishes_mid_block_upload);
    return check_summary();
}
