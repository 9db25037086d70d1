/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_sdo_channels.c -- several SDO server and client channels at once.
 *
 * Built against its own copy of the core with CO_SDO_SERVERS_MAX = CO_SDO_CLIENTS_MAX = 4
 * (tests/CMakeLists.txt), so channels 1..3 exist.
 *
 * A device here is the example dictionary plus the SDO server parameters 0x1200 (the
 * default channel, 0x600/0x580 + $NODEID), 0x1201 and 0x1202 (off at power-on: both
 * COB-IDs 0x80000000), and 0x3000, a DOMAIN with no storage whose read hook produces a
 * pattern and whose write hook checks what arrives against one (pattern_domain.h), so
 * transfers of any size stream through the server. A master is the example dictionary
 * plus the SDO client parameters 0x1280..0x1282 with per-instance power-on values; it
 * deliberately has no 0x1283, so client channel 3 is a channel "without 0x1280 + i".
 *
 * Frame-level tests run a device on the recording fake driver (harness.h) and compare
 * frames byte for byte; transfer tests put devices and masters on the simulated bus at
 * 1 Mbit/s, with a raw port that notes when each COB-ID was first and last seen.
 */
#include <stdlib.h>

#include "canola/sim.h"
#include "check.h"
#include "harness.h"
#include "pattern_domain.h"

#if CO_SDO_SERVERS_MAX < 4 || CO_SDO_CLIENTS_MAX < 4
#error "test_sdo_channels needs CO_SDO_SERVERS_MAX and CO_SDO_CLIENTS_MAX of at least 4"
#endif

#define MS 1000ull
#define COB_OFF 0x80000000u
#define XFER_CAP 4096u
#define DEVICES_MAX 4
#define MASTERS_MAX 2
#define MASTER_PARAMS 3 /* 0x1280..0x1282 */
/* Every frame starts at the earliest NODE_LATENCY_US after it was sent, as a real node
 * needs some microseconds to answer. Without it the simulated nodes answer in zero time:
 * a reply is ready the instant the frame it answers ends and wins the next arbitration
 * whenever its COB-ID is lower, so a ping-pong on 0x605/0x585 keeps another master's 0x640
 * off the bus until it ends, and two transfers "at once" run one after the other. */
#define NODE_LATENCY_US 20

/* ---- object dictionary entries */

#define ENTRY(idx, s, t, a, sz, val, def)                                                          \
    ((co_od_entry_t){.index = (idx),                                                               \
                     .sub = (s),                                                                   \
                     .type = (t),                                                                  \
                     .attr = (a),                                                                  \
                     .size = (sz),                                                                 \
                     .value = (val),                                                               \
                     .dflt = (def)})

static const uint8_t k_server_default_subs = 2; /* 0x1200 sub0 */
static const uint8_t k_server_extra_subs = 3;   /* 0x1201.. sub0 */
static const uint8_t k_client_subs = 3;         /* 0x1280.. sub0 */
static const uint32_t k_cob_rx_base = 0x600;    /* + $NODEID */
static const uint32_t k_cob_tx_base = 0x580;    /* + $NODEID */
static const uint32_t k_cob_off = COB_OFF;
static const uint8_t k_zero_u8 = 0;

static bool entry_before(const co_od_entry_t *a, const co_od_entry_t *b)
{
    return a->index != b->index ? a->index < b->index : a->sub < b->sub;
}

/* Merge two sorted tables into `out` (room for `cap` entries); returns the count. */
static uint32_t merge_od(co_od_entry_t *out, uint32_t cap, const co_od_t *base,
                         const co_od_entry_t *extra, uint32_t n_extra)
{
    uint32_t i = 0;
    uint32_t j = 0;
    uint32_t n = 0;
    while ((i < base->count || j < n_extra) && n < cap) {
        bool take_extra =
            i == base->count || (j < n_extra && entry_before(&extra[j], &base->entries[i]));
        out[n++] = take_extra ? extra[j++] : base->entries[i++];
    }
    CHECK_EQ(n, base->count + n_extra);
    return n;
}

/* ---- building a device, and talking to one frame by frame */

/* A device: SDO server channels 0..2 and 0x3000. Its pattern_domain_t is the hooks'
 * context: a test sets what an upload produces and what a download must carry. */
typedef struct device {
    example_od_t od;
    uint8_t server_subs[3];      /* 0x1200..0x1202 sub0 */
    uint32_t server_cob[3][2];   /* sub1 client -> server, sub2 server -> client */
    uint8_t server_client_id[3]; /* 0x1201, 0x1202 sub3 (index 0 unused) */
    pattern_domain_t stream;     /* 0x3000 */
    co_od_entry_t entries[EXAMPLE_OD_MAX_ENTRIES + 16];
    co_node_t node;
    co_sim_port_t port;
    fake_bus_t fake;
} device_t;

static co_node_config_t device_config(device_t *d, uint8_t node_id)
{
    co_od_t base = example_od_init(&d->od, 0);
    co_od_entry_t extra[16];
    uint32_t n = 0;
    extra[n++] = ENTRY(0x1200, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &d->server_subs[0],
                       &k_server_default_subs);
    extra[n++] = ENTRY(0x1200, 1, CO_TYPE_UNSIGNED32, CO_OD_RW | CO_OD_NODEID, 4,
                       &d->server_cob[0][0], &k_cob_rx_base);
    extra[n++] = ENTRY(0x1200, 2, CO_TYPE_UNSIGNED32, CO_OD_RW | CO_OD_NODEID, 4,
                       &d->server_cob[0][1], &k_cob_tx_base);
    for (uint16_t ch = 1; ch <= 2; ch++) {
        uint16_t index = (uint16_t)(0x1200 + ch);
        extra[n++] = ENTRY(index, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &d->server_subs[ch],
                           &k_server_extra_subs);
        extra[n++] =
            ENTRY(index, 1, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &d->server_cob[ch][0], &k_cob_off);
        extra[n++] =
            ENTRY(index, 2, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &d->server_cob[ch][1], &k_cob_off);
        extra[n++] =
            ENTRY(index, 3, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &d->server_client_id[ch], &k_zero_u8);
    }
    extra[n++] = pattern_domain_entry(0x3000);
    uint32_t count = merge_od(d->entries, EXAMPLE_OD_MAX_ENTRIES + 16, &base, extra, n);
    co_node_config_t cfg = {.node_id = node_id,
                            .od = {.entries = d->entries, .count = count, .hook_ctx = &d->stream}};
    return cfg;
}

/* A device on the recording fake driver, started (boot-up cleared). */
static void device_start_fake(device_t *d, uint8_t node_id)
{
    co_node_config_t cfg = device_config(d, node_id);
    cfg.driver = fake_driver(&d->fake);
    CHECK_EQ(co_node_init(&d->node, &cfg), CO_OK);
    CHECK_EQ(co_node_start(&d->node, 0), CO_OK);
    fake_clear(&d->fake);
}

/* Feed `request` to a fake-driver device (its clock stays at 0); what it sent in reply,
 * candump style. */
static const char *exchange(device_t *d, co_frame_t request, char *buf, size_t cap)
{
    fake_clear(&d->fake);
    co_node_ingest(&d->node, 0, &request);
    return fake_dump(&d->fake, buf, cap);
}

static bool device_accepts(const device_t *d, uint32_t id)
{
    co_frame_t f = frm(id, "00 00 00 00 00 00 00 00");
    return co_node_accepts(&d->node, &f);
}

/* ---- dictionary access through the node (writes take effect on the services) */

static co_abort_t node_write_u32(co_node_t *node, uint16_t index, uint8_t sub, uint32_t value)
{
    uint8_t wire[4];
    co_put_u32(wire, value);
    return co_node_write_net(node, index, sub, wire, sizeof wire);
}

static co_abort_t node_write_u8(co_node_t *node, uint16_t index, uint8_t sub, uint8_t value)
{
    return co_node_write_net(node, index, sub, &value, 1);
}

static uint64_t get_uint(const co_node_t *node, uint16_t index, uint8_t sub)
{
    uint64_t v = 0xDEADBEEFu;
    CHECK_EQ(co_node_get_uint(node, index, sub, &v), CO_OK);
    return v;
}

/* ---- a master: SDO client channels 0..3, parameters 0x1280..0x1282 */

typedef struct xfer {
    uint8_t buf[XFER_CAP];
    int done_calls;
    co_abort_t abort;
    uint32_t len;
} xfer_t;

typedef struct master {
    example_od_t od;
    uint8_t client_subs[MASTER_PARAMS];      /* 0x1280.. sub0 */
    uint32_t client_cob[MASTER_PARAMS][2];   /* sub1 client -> server, sub2 server -> client */
    uint8_t client_server[MASTER_PARAMS];    /* sub3 server node-ID */
    uint32_t cob_power_on[MASTER_PARAMS][2]; /* power-on values (set before the master joins) */
    uint8_t server_power_on[MASTER_PARAMS];
    co_od_entry_t entries[EXAMPLE_OD_MAX_ENTRIES + 16];
    co_node_t node;
    co_sim_port_t port;
    xfer_t xfer[CO_SDO_CLIENTS_MAX];
} master_t;

/* Client parameters at power-on: off, as CiA 301 has them, unless a test says otherwise. */
static void master_power_on_off(master_t *m)
{
    for (uint8_t i = 0; i < MASTER_PARAMS; i++) {
        m->cob_power_on[i][0] = COB_OFF;
        m->cob_power_on[i][1] = COB_OFF;
        m->server_power_on[i] = 0;
    }
}

static void master_power_on_server(master_t *m, uint8_t ch, uint8_t server_id)
{
    m->cob_power_on[ch][0] = 0x600u + server_id;
    m->cob_power_on[ch][1] = 0x580u + server_id;
    m->server_power_on[ch] = server_id;
}

static co_node_config_t master_config(master_t *m, uint8_t node_id)
{
    co_od_t base = example_od_init(&m->od, 0);
    co_od_entry_t extra[16];
    uint32_t n = 0;
    for (uint8_t ch = 0; ch < MASTER_PARAMS; ch++) {
        uint16_t index = (uint16_t)(0x1280 + ch);
        extra[n++] =
            ENTRY(index, 0, CO_TYPE_UNSIGNED8, CO_OD_CO, 1, &m->client_subs[ch], &k_client_subs);
        extra[n++] = ENTRY(index, 1, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &m->client_cob[ch][0],
                           &m->cob_power_on[ch][0]);
        extra[n++] = ENTRY(index, 2, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &m->client_cob[ch][1],
                           &m->cob_power_on[ch][1]);
        extra[n++] = ENTRY(index, 3, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &m->client_server[ch],
                           &m->server_power_on[ch]);
    }
    uint32_t count = merge_od(m->entries, EXAMPLE_OD_MAX_ENTRIES + 16, &base, extra, n);
    co_node_config_t cfg = {.node_id = node_id, .od = {.entries = m->entries, .count = count}};
    return cfg;
}

static void on_done(void *ctx, uint8_t channel, co_abort_t abort, uint32_t len)
{
    (void)channel;
    xfer_t *x = ctx;
    x->done_calls++;
    x->abort = abort;
    x->len = len;
}

static xfer_t *xfer_begin(master_t *m, uint8_t ch)
{
    xfer_t *x = &m->xfer[ch];
    x->done_calls = 0;
    x->abort = 0xFFFFFFFFu;
    x->len = 0;
    return x;
}

static co_err_t start_upload(master_t *m, uint8_t ch, uint16_t index, uint8_t sub,
                             co_sdo_mode_t mode)
{
    xfer_t *x = xfer_begin(m, ch);
    return co_sdo_upload(&m->node, ch, index, sub, mode, x->buf, XFER_CAP, on_done, x);
}

/* Download `len` bytes of the pattern `seed` to 0x3000. */
static co_err_t start_stream_download(master_t *m, uint8_t ch, co_sdo_mode_t mode, uint32_t seed,
                                      uint32_t len)
{
    xfer_t *x = xfer_begin(m, ch);
    pattern_fill(x->buf, seed, len);
    return co_sdo_download(&m->node, ch, 0x3000, 0, mode, x->buf, len, on_done, x);
}

static co_err_t start_download_u32(master_t *m, uint8_t ch, uint16_t index, uint8_t sub,
                                   uint32_t value)
{
    xfer_t *x = xfer_begin(m, ch);
    co_put_u32(x->buf, value);
    return co_sdo_download(&m->node, ch, index, sub, CO_SDO_EXPEDITED, x->buf, 4, on_done, x);
}

static bool xfer_ok(const xfer_t *x, uint32_t len)
{
    return x->done_calls == 1 && x->abort == CO_ABORT_NONE && x->len == len;
}

static bool upload_matches(const xfer_t *x, const pattern_domain_t *s)
{
    return xfer_ok(x, s->length) && pattern_matches(x->buf, s->up_seed, x->len);
}

/* ---- the simulated bus, with a raw port noting when each 11-bit COB-ID was seen */

typedef struct sniffer {
    co_sim_port_t port;
    uint64_t first_us[0x800];
    uint64_t last_us[0x800];
    uint32_t count[0x800];
} sniffer_t;

typedef struct world {
    co_sim_bus_t bus;
    sniffer_t sniffer;
    device_t dev[DEVICES_MAX];
    master_t master[MASTERS_MAX];
} world_t;

static void sniff(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    sniffer_t *s = ctx;
    if (frame->flags & CO_FRAME_EXT) {
        return;
    }
    if (s->count[frame->id]++ == 0) {
        s->first_us[frame->id] = now_us;
    }
    s->last_us[frame->id] = now_us;
}

static world_t *world_new(void)
{
    world_t *w = calloc(1, sizeof *w);
    CHECK_EQ(co_sim_bus_init(&w->bus, 1000000), CO_OK);
    co_sim_delay(&w->bus, NODE_LATENCY_US);
    CHECK_EQ(co_sim_port_attach_raw(&w->bus, &w->sniffer.port, sniff, &w->sniffer), CO_OK);
    for (uint32_t i = 0; i < MASTERS_MAX; i++) {
        master_power_on_off(&w->master[i]);
    }
    return w;
}

static void join(world_t *w, co_sim_port_t *port, co_node_t *node, co_node_config_t cfg)
{
    CHECK_EQ(co_sim_port_attach(&w->bus, port), CO_OK);
    cfg.driver = co_sim_port_driver(port);
    CHECK_EQ(co_node_init(node, &cfg), CO_OK);
    co_sim_port_bind(port, node);
    CHECK_EQ(co_node_start(node, w->bus.now_us), CO_OK);
}

static device_t *device_join(world_t *w, uint32_t slot, uint8_t node_id)
{
    device_t *d = &w->dev[slot];
    join(w, &d->port, &d->node, device_config(d, node_id));
    return d;
}

/* A master joins with the power-on values its struct holds (off unless a test set them). */
static master_t *master_join(world_t *w, uint32_t slot, uint8_t node_id)
{
    master_t *m = &w->master[slot];
    join(w, &m->port, &m->node, master_config(m, node_id));
    return m;
}

static void run_ms(world_t *w, uint64_t ms) { co_sim_run_until(&w->bus, w->bus.now_us + ms * MS); }

/* Run until every listed transfer is done, or `limit_ms` of simulated time passed. */
static void run_until_done(world_t *w, xfer_t *const *xs, uint32_t n, uint64_t limit_ms)
{
    uint64_t end = w->bus.now_us + limit_ms * MS;
    for (;;) {
        bool all = true;
        for (uint32_t i = 0; i < n; i++) {
            all &= xs[i]->done_calls > 0;
        }
        if (all || w->bus.now_us >= end) {
            return;
        }
        co_sim_run_until(&w->bus, w->bus.now_us + 1 * MS);
    }
}

/* One transfer on a channel of `m`, run to its end. */
static void run_one(world_t *w, master_t *m, uint8_t ch)
{
    xfer_t *x = &m->xfer[ch];
    run_until_done(w, &x, 1, 3000);
}

/* True when the frames on COB-IDs `a` and `b` overlapped in time: the transfers they carry
 * were under way together rather than one after the other. */
static bool spans_overlap(const sniffer_t *s, uint32_t a, uint32_t b)
{
    return s->count[a] > 0 && s->count[b] > 0 && s->first_us[a] < s->last_us[b] &&
           s->first_us[b] < s->last_us[a];
}

/* Server channel 1 on 0x640 / 0x5C0 (client node 1), written with co_node_write_net as an
 * SDO download from a master would write it. */
static void configure_channel_1(co_node_t *node)
{
    CHECK_EQ(node_write_u32(node, 0x1201, 1, 0x640), CO_ABORT_NONE);
    CHECK_EQ(node_write_u32(node, 0x1201, 2, 0x5C0), CO_ABORT_NONE);
    CHECK_EQ(node_write_u8(node, 0x1201, 3, 1), CO_ABORT_NONE);
}

/* Client channel `ch` of a master at server `id` through 0x1280 + ch. */
static void configure_client(master_t *m, uint8_t ch, uint32_t cob_tx, uint32_t cob_rx, uint8_t id)
{
    uint16_t index = (uint16_t)(0x1280 + ch);
    CHECK_EQ(node_write_u32(&m->node, index, 1, cob_tx), CO_ABORT_NONE);
    CHECK_EQ(node_write_u32(&m->node, index, 2, cob_rx), CO_ABORT_NONE);
    CHECK_EQ(node_write_u8(&m->node, index, 3, id), CO_ABORT_NONE);
}

/* ---- server channels, frame by frame */

static void test_server_channel_1_is_off_at_power_on(void)
{
    device_t *d = calloc(1, sizeof *d);
    char buf[256];
    device_start_fake(d, 5);
    CHECK_EQ(get_uint(&d->node, 0x1201, 1), COB_OFF);
    CHECK_EQ(get_uint(&d->node, 0x1201, 2), COB_OFF);
    CHECK(!device_accepts(d, 0x640));
    CHECK(device_accepts(d, 0x605));
    uint32_t unrouted = co_node_stats(&d->node)->rx_unrouted;
    CHECK_STR(exchange(d, frm(0x640, "40 00 10 00 00 00 00 00"), buf, sizeof buf), "");
    CHECK_EQ(co_node_stats(&d->node)->rx_unrouted, unrouted + 1);
    free(d);
}

static void test_server_channel_1_answers_on_its_cob_ids_once_configured(void)
{
    device_t *d = calloc(1, sizeof *d);
    char buf[256];
    device_start_fake(d, 5);
    configure_channel_1(&d->node);
    CHECK(device_accepts(d, 0x640));
    /* expedited upload of 0x1000 */
    CHECK_STR(exchange(d, frm(0x640, "40 00 10 00 00 00 00 00"), buf, sizeof buf),
              "5C0#4300100091010000");
    /* segmented upload of 0x1008 "canola example" (14 bytes) */
    CHECK_STR(exchange(d, frm(0x640, "40 08 10 00 00 00 00 00"), buf, sizeof buf),
              "5C0#410810000E000000");
    CHECK_STR(exchange(d, frm(0x640, "60 00 00 00 00 00 00 00"), buf, sizeof buf),
              "5C0#0063616E6F6C6120");
    CHECK_STR(exchange(d, frm(0x640, "70 00 00 00 00 00 00 00"), buf, sizeof buf),
              "5C0#116578616D706C65");
    /* expedited download of 0x2000 */
    CHECK_STR(exchange(d, frm(0x640, "23 00 20 00 EF BE AD DE"), buf, sizeof buf),
              "5C0#6000200000000000");
    CHECK_EQ(d->od.app_u32, 0xDEADBEEFu);
    /* the default channel is unchanged */
    CHECK_STR(exchange(d, frm(0x605, "40 00 20 00 00 00 00 00"), buf, sizeof buf),
              "585#43002000EFBEADDE");
    free(d);
}

static void test_server_channel_1_off_again_when_sub1_invalid(void)
{
    device_t *d = calloc(1, sizeof *d);
    char buf[256];
    device_start_fake(d, 5);
    configure_channel_1(&d->node);
    CHECK(device_accepts(d, 0x640));
    CHECK_EQ(node_write_u32(&d->node, 0x1201, 1, COB_OFF), CO_ABORT_NONE);
    CHECK(!device_accepts(d, 0x640));
    CHECK_STR(exchange(d, frm(0x640, "40 00 10 00 00 00 00 00"), buf, sizeof buf), "");
    /* valid again: it answers again */
    CHECK_EQ(node_write_u32(&d->node, 0x1201, 1, 0x640), CO_ABORT_NONE);
    CHECK_STR(exchange(d, frm(0x640, "40 00 10 00 00 00 00 00"), buf, sizeof buf),
              "5C0#4300100091010000");
    free(d);
}

/* A server that cannot answer does not listen: valid sub1 with invalid sub2 stays off. */
static void test_server_channel_with_invalid_response_cob_does_not_listen(void)
{
    device_t *d = calloc(1, sizeof *d);
    char buf[256];
    device_start_fake(d, 5);
    CHECK_EQ(node_write_u32(&d->node, 0x1201, 1, 0x640), CO_ABORT_NONE);
    CHECK_EQ(get_uint(&d->node, 0x1201, 2), COB_OFF);
    CHECK(!device_accepts(d, 0x640));
    CHECK_STR(exchange(d, frm(0x640, "40 00 10 00 00 00 00 00"), buf, sizeof buf), "");
    /* and once sub2 is valid it does */
    CHECK_EQ(node_write_u32(&d->node, 0x1201, 2, 0x5C0), CO_ABORT_NONE);
    CHECK(device_accepts(d, 0x640));
    /* invalid sub2 again (same identifier, bit 31 set): off again */
    CHECK_EQ(node_write_u32(&d->node, 0x1201, 2, COB_OFF | 0x5C0), CO_ABORT_NONE);
    CHECK(!device_accepts(d, 0x640));
    CHECK_STR(exchange(d, frm(0x640, "40 00 10 00 00 00 00 00"), buf, sizeof buf), "");
    free(d);
}

static void test_server_channels_1_and_2_are_independent(void)
{
    device_t *d = calloc(1, sizeof *d);
    char buf[256];
    device_start_fake(d, 5);
    configure_channel_1(&d->node);
    CHECK_EQ(node_write_u32(&d->node, 0x1202, 1, 0x641), CO_ABORT_NONE);
    CHECK_EQ(node_write_u32(&d->node, 0x1202, 2, 0x5C1), CO_ABORT_NONE);
    /* open a segmented upload on channel 1, then use channel 2 in between */
    CHECK_STR(exchange(d, frm(0x640, "40 08 10 00 00 00 00 00"), buf, sizeof buf),
              "5C0#410810000E000000");
    CHECK_STR(exchange(d, frm(0x641, "40 00 10 00 00 00 00 00"), buf, sizeof buf),
              "5C1#4300100091010000");
    CHECK_STR(exchange(d, frm(0x641, "60 00 00 00 00 00 00 00"), buf, sizeof buf),
              "5C1#8000000001000405"); /* channel 2 is idle: a segment request is an error */
    CHECK_STR(exchange(d, frm(0x640, "60 00 00 00 00 00 00 00"), buf, sizeof buf),
              "5C0#0063616E6F6C6120");
    /* turning channel 2 off leaves channel 1's transfer alone */
    CHECK_EQ(node_write_u32(&d->node, 0x1202, 1, COB_OFF), CO_ABORT_NONE);
    CHECK_STR(exchange(d, frm(0x640, "70 00 00 00 00 00 00 00"), buf, sizeof buf),
              "5C0#116578616D706C65");
    free(d);
}

static void test_reset_communication_turns_server_channel_1_off(void)
{
    device_t *d = calloc(1, sizeof *d);
    char buf[256];
    device_start_fake(d, 5);
    configure_channel_1(&d->node);
    CHECK(device_accepts(d, 0x640));
    CHECK_EQ(co_nmt_apply(&d->node, CO_NMT_CMD_RESET_COMMUNICATION), CO_OK);
    CHECK_EQ(get_uint(&d->node, 0x1201, 1), COB_OFF);
    CHECK_EQ(get_uint(&d->node, 0x1201, 2), COB_OFF);
    CHECK(!device_accepts(d, 0x640));
    CHECK_STR(exchange(d, frm(0x640, "40 00 10 00 00 00 00 00"), buf, sizeof buf), "");
    CHECK_EQ(get_uint(&d->node, 0x1200, 1), 0x605);
    CHECK_STR(exchange(d, frm(0x605, "40 00 10 00 00 00 00 00"), buf, sizeof buf),
              "585#4300100091010000");
    free(d);
}

/* A client may turn a channel off through that channel itself. Writing sub1 invalid: the
 * confirmation still leaves on 0x5C0 and the channel is silent afterwards. */
static void test_server_channel_1_switched_off_through_itself(void)
{
    device_t *d = calloc(1, sizeof *d);
    char buf[256];
    device_start_fake(d, 5);
    configure_channel_1(&d->node);
    CHECK_STR(exchange(d, frm(0x640, "23 01 12 01 40 06 00 80"), buf, sizeof buf),
              "5C0#6001120100000000");
    CHECK(!device_accepts(d, 0x640));
    free(d);
}

/* The same with sub2: the server's response COB-ID becomes invalid while it answers the
 * write. The confirmation must not go out on identifier 0x000 (NMT's, the highest
 * priority on the bus); the expected place is the COB-ID the request was served on. */
static void test_server_response_cob_invalidated_through_itself(void)
{
    device_t *d = calloc(1, sizeof *d);
    char buf[256];
    device_start_fake(d, 5);
    configure_channel_1(&d->node);
    const char *reply = exchange(d, frm(0x640, "23 01 12 02 00 00 00 80"), buf, sizeof buf);
    CHECK_EQ(fake_count_id(&d->fake, 0x000), 0);
    CHECK_STR(reply, "5C0#6001120200000000");
    CHECK_EQ(get_uint(&d->node, 0x1201, 2), COB_OFF);
    CHECK(!device_accepts(d, 0x640));
    free(d);
}

/* ---- server channels on the simulated bus */

/* Master 1 on device 5's channel 0 and master 2 on its channel 1 (configured by master 1
 * by SDO, master 2's client through 0x1280): a block download and a segmented upload of
 * 0x3000 at the same time. */
static void test_two_masters_on_server_channels_0_and_1_at_once(void)
{
    world_t *w = world_new();
    device_t *d = device_join(w, 0, 5);
    master_t *a = master_join(w, 0, 1);
    master_t *b = master_join(w, 1, 2);
    CHECK_EQ(co_sdo_client_setup(&a->node, 0, 5), CO_OK);
    configure_client(b, 0, 0x640, 0x5C0, 5);
    run_ms(w, 1);

    CHECK_EQ(start_download_u32(a, 0, 0x1201, 1, 0x640), CO_OK);
    run_one(w, a, 0);
    CHECK(xfer_ok(&a->xfer[0], 4));
    CHECK_EQ(start_download_u32(a, 0, 0x1201, 2, 0x5C0), CO_OK);
    run_one(w, a, 0);
    CHECK(xfer_ok(&a->xfer[0], 4));
    CHECK(device_accepts(d, 0x640));

    const uint32_t down_len = 3000;
    d->stream = (pattern_domain_t){.length = 2000, .up_seed = 22, .down_seed = 11};
    CHECK_EQ(start_stream_download(a, 0, CO_SDO_BLOCK, 11, down_len), CO_OK);
    CHECK_EQ(start_upload(b, 0, 0x3000, 0, CO_SDO_SEGMENTED), CO_OK);
    xfer_t *both[] = {&a->xfer[0], &b->xfer[0]};
    run_until_done(w, both, 2, 2000);

    CHECK(xfer_ok(&a->xfer[0], down_len));
    CHECK(pattern_domain_received(&d->stream, down_len));
    CHECK(upload_matches(&b->xfer[0], &d->stream));
    CHECK(spans_overlap(&w->sniffer, 0x605, 0x640));
    CHECK(spans_overlap(&w->sniffer, 0x585, 0x5C0));
    CHECK_EQ(co_node_stats(&d->node)->tx_overflow, 0);
    free(w);
}

/* Both channels in block transfer at once: they share the device's transmit queue. */
static void test_block_upload_and_block_download_on_two_server_channels(void)
{
    world_t *w = world_new();
    device_t *d = device_join(w, 0, 5);
    master_t *a = master_join(w, 0, 1);
    master_t *b = master_join(w, 1, 2);
    configure_channel_1(&d->node);
    CHECK_EQ(co_sdo_client_setup(&a->node, 0, 5), CO_OK);
    configure_client(b, 1, 0x640, 0x5C0, 5);
    run_ms(w, 1);

    d->stream = (pattern_domain_t){.length = 4000, .up_seed = 3, .down_seed = 4};
    CHECK_EQ(start_upload(a, 0, 0x3000, 0, CO_SDO_BLOCK), CO_OK);
    CHECK_EQ(start_stream_download(b, 1, CO_SDO_BLOCK, 4, 3500), CO_OK);
    xfer_t *both[] = {&a->xfer[0], &b->xfer[1]};
    run_until_done(w, both, 2, 2000);

    CHECK(upload_matches(&a->xfer[0], &d->stream));
    CHECK(xfer_ok(&b->xfer[1], 3500));
    CHECK(pattern_domain_received(&d->stream, 3500));
    CHECK(spans_overlap(&w->sniffer, 0x605, 0x640));
    CHECK(spans_overlap(&w->sniffer, 0x585, 0x5C0));
    CHECK_EQ(co_node_stats(&d->node)->tx_overflow, 0);
    free(w);
}

/* ---- client channels */

/* co_sdo_client_progress: the bytes moved so far, growing, all of them at the end (a
 * segmented upload of 4,000 bytes, sampled every simulated millisecond). */
static void test_client_progress_counts_the_bytes_moved(void)
{
    world_t *w = world_new();
    device_t *d = device_join(w, 0, 5);
    master_t *a = master_join(w, 0, 1);
    CHECK_EQ(co_sdo_client_setup(&a->node, 0, 5), CO_OK);
    run_ms(w, 1);
    d->stream = (pattern_domain_t){.length = 4000, .up_seed = 3, .down_seed = 4};
    CHECK_EQ(co_sdo_client_progress(&a->node, 0), 0);
    CHECK_EQ(start_upload(a, 0, 0x3000, 0, CO_SDO_SEGMENTED), CO_OK);
    uint32_t seen = 0;
    bool between = false;
    for (int i = 0; i < 2000 && a->xfer[0].done_calls == 0; i++) {
        run_ms(w, 1);
        uint32_t now = co_sdo_client_progress(&a->node, 0);
        CHECK(now >= seen);
        between = between || (now > 0 && now < 4000);
        seen = now;
    }
    CHECK(between);
    CHECK(upload_matches(&a->xfer[0], &d->stream));
    CHECK_EQ(co_sdo_client_progress(&a->node, 0), 4000);
    CHECK_EQ(co_sdo_client_progress(&a->node, CO_SDO_CLIENTS_MAX), 0);
    CHECK_EQ(co_sdo_client_progress(NULL, 0), 0);
    free(w);
}

/* One master, four client channels (co_sdo_client_setup), four devices, every kind of
 * transfer at once. Channel 3 has no 0x1283 in the master's dictionary. */
static void test_one_master_four_client_channels_four_devices(void)
{
    world_t *w = world_new();
    device_t *d[4];
    for (uint8_t i = 0; i < 4; i++) {
        d[i] = device_join(w, i, (uint8_t)(5 + i));
    }
    master_t *m = master_join(w, 0, 1);
    for (uint8_t ch = 0; ch < 4; ch++) {
        CHECK_EQ(co_sdo_client_setup(&m->node, ch, (uint8_t)(5 + ch)), CO_OK);
    }
    CHECK_EQ(get_uint(&m->node, 0x1282, 1), 0x607);
    CHECK_EQ(get_uint(&m->node, 0x1282, 2), 0x587);
    CHECK_EQ(get_uint(&m->node, 0x1282, 3), 7);
    run_ms(w, 1);

    d[0]->stream = (pattern_domain_t){.down_seed = 10};
    d[1]->stream = (pattern_domain_t){.length = 3000, .up_seed = 11};
    d[2]->stream = (pattern_domain_t){.down_seed = 12};
    d[3]->stream = (pattern_domain_t){.length = 1500, .up_seed = 13};
    CHECK_EQ(start_stream_download(m, 0, CO_SDO_BLOCK, 10, 3000), CO_OK);
    CHECK_EQ(start_upload(m, 1, 0x3000, 0, CO_SDO_BLOCK), CO_OK);
    CHECK_EQ(start_stream_download(m, 2, CO_SDO_SEGMENTED, 12, 1500), CO_OK);
    CHECK_EQ(start_upload(m, 3, 0x3000, 0, CO_SDO_SEGMENTED), CO_OK);
    for (uint8_t ch = 0; ch < 4; ch++) {
        CHECK(co_sdo_client_busy(&m->node, ch));
    }
    xfer_t *all[] = {&m->xfer[0], &m->xfer[1], &m->xfer[2], &m->xfer[3]};
    run_until_done(w, all, 4, 3000);

    CHECK(xfer_ok(&m->xfer[0], 3000));
    CHECK(pattern_domain_received(&d[0]->stream, 3000));
    CHECK(upload_matches(&m->xfer[1], &d[1]->stream));
    CHECK(xfer_ok(&m->xfer[2], 1500));
    CHECK(pattern_domain_received(&d[2]->stream, 1500));
    CHECK(upload_matches(&m->xfer[3], &d[3]->stream));
    /* Bus access follows CAN priority (the two block transfers fill the bus and channel 3's
     * 0x608 waits for them), but no channel ran alone: each overlapped another. */
    for (uint32_t ch = 0; ch < 4; ch++) {
        bool together = false;
        for (uint32_t other = 0; other < 4; other++) {
            together |= other != ch && spans_overlap(&w->sniffer, 0x605 + ch, 0x605 + other);
        }
        CHECK(together);
    }
    CHECK_EQ(co_node_stats(&m->node)->tx_overflow, 0);

    /* and the other way round on the same channels */
    d[0]->stream = (pattern_domain_t){.length = 2500, .up_seed = 20};
    d[1]->stream = (pattern_domain_t){.down_seed = 21};
    d[2]->stream = (pattern_domain_t){.length = 700, .up_seed = 22};
    d[3]->stream = (pattern_domain_t){.down_seed = 23};
    CHECK_EQ(start_upload(m, 0, 0x3000, 0, CO_SDO_SEGMENTED), CO_OK);
    CHECK_EQ(start_stream_download(m, 1, CO_SDO_SEGMENTED, 21, 2500), CO_OK);
    CHECK_EQ(start_upload(m, 2, 0x3000, 0, CO_SDO_BLOCK), CO_OK);
    CHECK_EQ(start_stream_download(m, 3, CO_SDO_BLOCK, 23, 700), CO_OK);
    run_until_done(w, all, 4, 3000);
    CHECK(upload_matches(&m->xfer[0], &d[0]->stream));
    CHECK(xfer_ok(&m->xfer[1], 2500));
    CHECK(pattern_domain_received(&d[1]->stream, 2500));
    CHECK(upload_matches(&m->xfer[2], &d[2]->stream));
    CHECK(xfer_ok(&m->xfer[3], 700));
    CHECK(pattern_domain_received(&d[3]->stream, 700));
    free(w);
}

static void test_client_channel_configured_through_0x1281(void)
{
    world_t *w = world_new();
    device_join(w, 0, 5);
    master_t *m = master_join(w, 0, 1);
    run_ms(w, 1);
    CHECK_EQ(start_upload(m, 1, 0x1000, 0, CO_SDO_AUTO), CO_ERR_STATE);

    configure_client(m, 1, 0x605, 0x585, 5);
    co_frame_t response = frm(0x585, "43 00 10 00 91 01 00 00");
    CHECK(co_node_accepts(&m->node, &response));
    CHECK_EQ(start_upload(m, 1, 0x1000, 0, CO_SDO_AUTO), CO_OK);
    run_one(w, m, 1);
    CHECK(xfer_ok(&m->xfer[1], 4));
    CHECK_EQ(co_get_u32(m->xfer[1].buf), 0x191);
    CHECK_EQ(w->sniffer.count[0x605], 1);
    CHECK_EQ(w->sniffer.count[0x585], 1);
    free(w);
}

/* Reset communication reloads 0x1281 from its power-on values: a channel preset at
 * power-on to device 6, pointed at device 5 through 0x1281, talks to device 6 again. */
static void test_reset_communication_reloads_0x1281_power_on_values(void)
{
    world_t *w = world_new();
    device_t *d5 = device_join(w, 0, 5);
    device_t *d6 = device_join(w, 1, 6);
    master_power_on_server(&w->master[0], 1, 6);
    master_t *m = master_join(w, 0, 1);
    d5->od.app_u32 = 0x55555555u;
    d6->od.app_u32 = 0x66666666u;
    run_ms(w, 1);

    CHECK_EQ(start_upload(m, 1, 0x2000, 0, CO_SDO_AUTO), CO_OK);
    run_one(w, m, 1);
    CHECK(xfer_ok(&m->xfer[1], 4));
    CHECK_EQ(co_get_u32(m->xfer[1].buf), 0x66666666u);

    configure_client(m, 1, 0x605, 0x585, 5);
    CHECK_EQ(start_upload(m, 1, 0x2000, 0, CO_SDO_AUTO), CO_OK);
    run_one(w, m, 1);
    CHECK(xfer_ok(&m->xfer[1], 4));
    CHECK_EQ(co_get_u32(m->xfer[1].buf), 0x55555555u);

    CHECK_EQ(co_nmt_apply(&m->node, CO_NMT_CMD_RESET_COMMUNICATION), CO_OK);
    run_ms(w, 1);
    CHECK_EQ(get_uint(&m->node, 0x1281, 1), 0x606);
    CHECK_EQ(get_uint(&m->node, 0x1281, 2), 0x586);
    CHECK_EQ(get_uint(&m->node, 0x1281, 3), 6);
    CHECK_EQ(start_upload(m, 1, 0x2000, 0, CO_SDO_AUTO), CO_OK);
    run_one(w, m, 1);
    CHECK(xfer_ok(&m->xfer[1], 4));
    CHECK_EQ(co_get_u32(m->xfer[1].buf), 0x66666666u);
    free(w);
}

/* co_sdo_client_setup writes 0x1280 + ch; its power-on value (off) comes back at reset
 * communication, so the channel is off. Channel 3 has no 0x1283 and keeps its setup. */
static void test_reset_communication_and_channels_set_up_by_the_application(void)
{
    world_t *w = world_new();
    device_join(w, 0, 5);
    device_join(w, 1, 6);
    master_t *m = master_join(w, 0, 1);
    CHECK_EQ(co_sdo_client_setup(&m->node, 0, 5), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&m->node, 3, 6), CO_OK);
    CHECK_EQ(get_uint(&m->node, 0x1280, 1), 0x605);
    run_ms(w, 1);

    CHECK_EQ(co_nmt_apply(&m->node, CO_NMT_CMD_RESET_COMMUNICATION), CO_OK);
    run_ms(w, 1);
    CHECK_EQ(get_uint(&m->node, 0x1280, 1), COB_OFF);
    CHECK_EQ(get_uint(&m->node, 0x1280, 2), COB_OFF);
    CHECK_EQ(get_uint(&m->node, 0x1280, 3), 0);
    co_frame_t from_5 = frm(0x585, "43 00 10 00 91 01 00 00");
    CHECK(!co_node_accepts(&m->node, &from_5));
    CHECK_EQ(start_upload(m, 0, 0x1000, 0, CO_SDO_AUTO), CO_ERR_STATE);

    CHECK_EQ(start_upload(m, 3, 0x1000, 0, CO_SDO_AUTO), CO_OK);
    run_one(w, m, 3);
    CHECK(xfer_ok(&m->xfer[3], 4));
    CHECK_EQ(co_get_u32(m->xfer[3].buf), 0x191);
    CHECK_EQ(w->sniffer.count[0x606], 1);
    free(w);
}

static void on_flashed(void *ctx, const co_flash_result_t *r)
{
    (void)r;
    (*(int *)ctx)++;
}

/* Two client channels to one server would both take its responses: refused, by the
 * setup and by a program download that would set a channel up so. Channels served by
 * the node itself use no frames and may share it. */
static void test_two_client_channels_to_one_server_refused(void)
{
    world_t *w = world_new();
    device_join(w, 0, 5);
    master_t *m = master_join(w, 0, 1);
    run_ms(w, 1);
    CHECK_EQ(co_sdo_client_setup(&m->node, 0, 5), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&m->node, 1, 5), CO_ERR_STATE);
    CHECK_EQ(get_uint(&m->node, 0x1281, 3), 0); /* left as it was */
    static const uint8_t image[16] = {1, 2, 3};
    int flashed = 0;
    co_flash_t flash;
    co_flash_request_t req = {.channel = 1,
                              .server = 5,
                              .data = image,
                              .len = sizeof image,
                              .done = on_flashed,
                              .ctx = &flashed};
    CHECK_EQ(co_flash_start(&flash, &m->node, &req), CO_ERR_STATE);
    run_ms(w, 10);
    CHECK_EQ(flashed, 0);
    CHECK_EQ(w->sniffer.count[0x605], 0);
    /* The node itself, on two channels at once. */
    CHECK_EQ(co_sdo_client_setup(&m->node, 1, 1), CO_OK);
    CHECK_EQ(co_sdo_client_setup(&m->node, 2, 1), CO_OK);
    CHECK_EQ(start_upload(m, 1, 0x1000, 0, CO_SDO_AUTO), CO_OK);
    CHECK(xfer_ok(&m->xfer[1], 4));
    CHECK_EQ(start_upload(m, 2, 0x1018, 1, CO_SDO_AUTO), CO_OK);
    CHECK(xfer_ok(&m->xfer[2], 4));
    CHECK_EQ(co_get_u32(m->xfer[1].buf), m->od.device_type);
    CHECK_EQ(w->sniffer.count[0x601], 0);
    free(w);
}

/* A channel whose client -> server COB-ID has bit 31 set is off: no transfer starts. */
static void test_client_channel_with_an_invalid_cob_id_does_not_start(void)
{
    world_t *w = world_new();
    device_join(w, 0, 5);
    master_t *m = master_join(w, 0, 1);
    run_ms(w, 1);
    configure_client(m, 1, COB_OFF | 0x605, 0x585, 5);
    CHECK_EQ(start_upload(m, 1, 0x1000, 0, CO_SDO_AUTO), CO_ERR_STATE);
    configure_client(m, 1, 0x605, COB_OFF | 0x585, 5);
    CHECK_EQ(start_upload(m, 1, 0x1000, 0, CO_SDO_AUTO), CO_ERR_STATE);
    run_ms(w, 10);
    CHECK_EQ(w->sniffer.count[0x605], 0);
    CHECK_EQ(m->xfer[1].done_calls, 0);
    configure_client(m, 1, 0x605, 0x585, 5);
    CHECK_EQ(start_upload(m, 1, 0x1000, 0, CO_SDO_AUTO), CO_OK);
    run_one(w, m, 1);
    CHECK(xfer_ok(&m->xfer[1], 4));
    CHECK_EQ(w->sniffer.count[0x605], 1);
    free(w);
}

int main(void)
{
    RUN(test_server_channel_1_is_off_at_power_on);
    RUN(test_client_progress_counts_the_bytes_moved);
    RUN(test_server_channel_1_answers_on_its_cob_ids_once_configured);
    RUN(test_server_channel_1_off_again_when_sub1_invalid);
    RUN(test_server_channel_with_invalid_response_cob_does_not_listen);
    RUN(test_server_channels_1_and_2_are_independent);
    RUN(test_reset_communication_turns_server_channel_1_off);
    RUN(test_server_channel_1_switched_off_through_itself);
    RUN(test_server_response_cob_invalidated_through_itself);
    RUN(test_two_masters_on_server_channels_0_and_1_at_once);
    RUN(test_block_upload_and_block_download_on_two_server_channels);
    RUN(test_one_master_four_client_channels_four_devices);
    RUN(test_client_channel_configured_through_0x1281);
    RUN(test_reset_communication_reloads_0x1281_power_on_values);
    RUN(test_reset_communication_and_channels_set_up_by_the_application);
    RUN(test_two_client_channels_to_one_server_refused);
    RUN(test_client_channel_with_an_invalid_cob_id_does_not_start);
    return check_summary();
}
