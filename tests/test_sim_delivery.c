/* SPDX-License-Identifier: Apache-2.0 */
/* tests/test_sim_delivery.c -- the simulated bus's shortcuts behave as the plain rules:
 * the delivery index gives each node exactly the frames co_node_accepts passes at its turn,
 * the pending heap sends frames in the order arbitration (or send order) decides, and the
 * byte-wise frame length equals co_sim_frame_bits (which test_sim checks bit by bit). */
#include "canola/sim.h"
#include "check.h"
#include "example_od.h"
#include "harness.h"

#define REC_MAX 1024

typedef struct rec {
    uint64_t t[REC_MAX];
    co_frame_t f[REC_MAX];
    uint32_t n;
} rec_t;

static void rec_rx(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    rec_t *r = ctx;
    if (r->n < REC_MAX) {
        r->t[r->n] = now_us;
        r->f[r->n] = *frame;
        r->n++;
    }
}

static co_sim_bus_t g_bus;

static co_sim_bus_t *new_bus(uint32_t bitrate)
{
    CHECK_EQ(co_sim_bus_init(&g_bus, bitrate), CO_OK);
    return &g_bus;
}

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005u + 1442695040888963407u;
    return *s >> 33;
}

static co_frame_t random_frame(uint64_t *s)
{
    co_frame_t f;
    memset(&f, 0, sizeof f);
    bool ext = lcg(s) % 4 == 0;
    f.id = (uint32_t)lcg(s) & (ext ? CO_ID_EXT_MAX : CO_ID_STD_MAX);
    f.flags = (uint8_t)((ext ? CO_FRAME_EXT : 0) | ((lcg(s) % 6 == 0) ? CO_FRAME_RTR : 0));
    f.len = (uint8_t)(lcg(s) % 9);
    uint8_t fill = (uint8_t)(lcg(s) % 3 == 0 ? 0x00 : lcg(s) % 2 ? 0xFF : 0x55);
    for (unsigned i = 0; i < 8; i++) {
        f.data[i] = (uint8_t)(lcg(s) % 3 == 0 ? lcg(s) : fill); /* runs: stuffing */
    }
    return f;
}

/* The arbitration field as CAN sends it, written here independently of sim.c: base ID,
 * then (11-bit) RTR and a dominant IDE, or (29-bit) recessive SRR and IDE, the extension
 * and RTR. Lower wins. */
static uint64_t arbitration(const co_frame_t *f)
{
    uint64_t rtr = (f->flags & CO_FRAME_RTR) ? 1 : 0;
    if (f->flags & CO_FRAME_EXT) {
        return (uint64_t)(f->id >> 18) << 21 | 1u << 20 | 1u << 19 | (f->id & 0x3FFFF) << 1 | rtr;
    }
    return (uint64_t)f->id << 21 | rtr << 20;
}

/* ---- Frame length. */

static void test_bus_counts_frame_bits(void)
{
    /* Every frame's length on the bus (the byte-wise computation) is co_sim_frame_bits. */
    co_sim_bus_t *bus = new_bus(0);
    co_sim_port_t a;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    a.mailboxes = 255;
    uint64_t s = 7, want = 0;
    for (int round = 0; round < 100; round++) {
        for (int i = 0; i < 200; i++) {
            co_frame_t f = random_frame(&s);
            CHECK_EQ(co_sim_send(&a, &f), CO_OK);
            want += co_sim_frame_bits(&f);
        }
        CHECK_EQ(co_sim_run_until(bus, bus->now_us + 1), CO_OK);
    }
    CHECK_EQ(bus->stats.frames, 20000);
    CHECK_EQ(bus->stats.bits, want);
}

/* ---- The pending frames. */

typedef struct sent {
    co_frame_t f;
    uint32_t seq; /* send order */
} sent_t;

/* Lower arbitration field first, then the earlier sent. */
static bool wins(const sent_t *a, const sent_t *b)
{
    uint64_t ka = arbitration(&a->f), kb = arbitration(&b->f);
    return ka != kb ? ka < kb : a->seq < b->seq;
}

/* Index of the winner among want[from..n) whose seq < ready_below. */
static uint32_t winner(const sent_t *want, uint32_t from, uint32_t n, uint32_t ready_below)
{
    uint32_t best = n;
    for (uint32_t i = from; i < n; i++) {
        if (want[i].seq < ready_below && (best == n || wins(&want[i], &want[best]))) {
            best = i;
        }
    }
    return best;
}

static void test_arbitration_order_many(void)
{
    /* 500 frames from two ports: 250 at time 0, 250 more at 2 ms while the first are still
     * going out. Each arbitration takes the lowest field among the frames sent before it
     * began; the frames go back to back. */
    co_sim_bus_t *bus = new_bus(1000000);
    static rec_t rr;
    static sent_t want[500];
    memset(&rr, 0, sizeof rr);
    co_sim_port_t a, b, r;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, NULL, NULL);
    co_sim_port_attach_raw(bus, &r, rec_rx, &rr);
    a.mailboxes = b.mailboxes = 255;
    uint64_t s = 11;
    uint32_t n = 0;
    for (; n < 250; n++) {
        want[n] = (sent_t){random_frame(&s), n};
        CHECK_EQ(co_sim_send(n % 2 ? &b : &a, &want[n].f), CO_OK);
    }
    CHECK_EQ(co_sim_run_until(bus, 2000), CO_OK);
    for (; n < 500; n++) {
        want[n] = (sent_t){random_frame(&s), n};
        CHECK_EQ(co_sim_send(n % 2 ? &b : &a, &want[n].f), CO_OK);
    }
    CHECK_EQ(co_sim_run_until(bus, 1000000), CO_OK);
    CHECK_EQ(rr.n, 500);

    /* The expected order, by selection over what was sent when each frame began. */
    uint64_t start = 0;
    uint32_t mismatches = 0;
    for (uint32_t k = 0; k < 500; k++) {
        uint32_t w = winner(want, k, 500, start <= 2000 ? 250 : 500);
        sent_t tmp = want[k];
        want[k] = want[w];
        want[w] = tmp;
        start += co_sim_frame_bits(&want[k].f); /* 1 us per bit */
        if ((rr.f[k].id != want[k].f.id || rr.f[k].flags != want[k].f.flags || rr.t[k] != start) &&
            mismatches++ < 5) {
            char got[40], exp[40];
            printf("  frame %u: got %s at %llu, expected %s at %llu\n", k,
                   frame_str(&rr.f[k], got, sizeof got), (unsigned long long)rr.t[k],
                   frame_str(&want[k].f, exp, sizeof exp), (unsigned long long)start);
        }
    }
    CHECK_EQ(mismatches, 0);
}

static void test_instant_order_with_delays(void)
{
    /* Instant delivery: the oldest frame ready goes first; a frame sent later without
     * delay overtakes older ones that wait for theirs. */
    co_sim_bus_t *bus = new_bus(0);
    static rec_t rr;
    memset(&rr, 0, sizeof rr);
    co_sim_port_t a, r;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &r, rec_rx, &rr);
    a.mailboxes = 10;
    co_frame_t f1 = frm(0x101, "01"), f2 = frm(0x002, "02"), f3 = frm(0x703, "03");
    co_frame_t f4 = frm(0x004, "04");
    co_sim_delay(bus, 300);
    co_sim_send(&a, &f1); /* ready at 300 */
    co_sim_send(&a, &f2); /* ready at 300 */
    co_sim_delay(bus, 100);
    co_sim_send(&a, &f3); /* ready at 100 */
    co_sim_delay(bus, 0);
    co_sim_send(&a, &f4); /* ready now */
    CHECK_EQ(co_sim_run_until(bus, 1000), CO_OK);
    CHECK_EQ(rr.n, 4);
    CHECK_EQ(rr.f[0].id, 0x004);
    CHECK_EQ(rr.t[0], 0);
    CHECK_EQ(rr.f[1].id, 0x703);
    CHECK_EQ(rr.t[1], 100);
    CHECK_EQ(rr.f[2].id, 0x101); /* sent before 0x002: first, whatever the ID */
    CHECK_EQ(rr.t[2], 300);
    CHECK_EQ(rr.f[3].id, 0x002);
}

static void test_bus_off_leaves_order(void)
{
    /* A port going bus-off takes its waiting frames out; the others keep their order. */
    co_sim_bus_t *bus = new_bus(500000);
    static rec_t rr;
    memset(&rr, 0, sizeof rr);
    co_sim_port_t a, b, r;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, NULL, NULL);
    co_sim_port_attach_raw(bus, &r, rec_rx, &rr);
    a.mailboxes = b.mailboxes = 100;
    for (uint32_t i = 0; i < 100; i++) {
        co_frame_t fa = frm(0x7FF - 2 * i, "AA"), fb = frm(0x7FE - 2 * i, "BB");
        co_sim_send(&a, &fa);
        co_sim_send(&b, &fb);
    }
    co_sim_set_bus_off(&a, true);
    CHECK_EQ(a.in_flight, 0);
    CHECK_EQ(co_sim_run_until(bus, 100000), CO_OK);
    CHECK_EQ(rr.n, 100);
    for (uint32_t i = 0; i < rr.n; i++) {
        CHECK_EQ(rr.f[i].id, 0x7FE - 2 * (99 - i)); /* b's frames, lowest ID first */
    }
}

/* ---- Delivery to nodes. */

typedef struct sim_node {
    example_od_t od;
    co_node_t node;
    co_sim_port_t port;
    struct sim_node *other; /* on_rpdo moves this node's RPDO1 to 0x3AB (see below) */
    uint32_t rpdos;
} sim_node_t;

static void on_rpdo(void *user, uint16_t rpdo)
{
    sim_node_t *n = user;
    (void)rpdo;
    n->rpdos++;
    if (n->other) {
        CHECK_EQ(co_node_set_uint(&n->other->node, 0x1400, 1, 0x80000000u | 0x3AB), CO_ABORT_NONE);
        CHECK_EQ(co_node_set_uint(&n->other->node, 0x1400, 1, 0x3AB), CO_ABORT_NONE);
    }
}

static void add_node_with(co_sim_bus_t *bus, sim_node_t *n, uint8_t id, co_driver_t driver)
{
    co_node_config_t cfg = {
        .node_id = id,
        .od = example_od_init(&n->od, 0),
        .driver = driver,
        .user = n,
        .on_rpdo = on_rpdo,
        .self_start = true,
    };
    CHECK_EQ(co_node_init(&n->node, &cfg), CO_OK);
    co_sim_port_bind(&n->port, &n->node);
    CHECK_EQ(co_node_start(&n->node, bus->now_us), CO_OK);
}

static void add_node(co_sim_bus_t *bus, sim_node_t *n, uint8_t id)
{
    memset(n, 0, sizeof *n);
    CHECK_EQ(co_sim_port_attach(bus, &n->port), CO_OK);
    add_node_with(bus, n, id, co_sim_port_driver(&n->port));
}

/* Send one frame from `raw` and run the bus 1 ms on. */
static void put(co_sim_bus_t *bus, co_sim_port_t *raw, co_frame_t f)
{
    CHECK_EQ(co_sim_send(raw, &f), CO_OK);
    CHECK_EQ(co_sim_run_until(bus, bus->now_us + 1000), CO_OK);
}

static void test_delivery_follows_routes(void)
{
    co_sim_bus_t *bus = new_bus(0);
    static sim_node_t n;
    co_sim_port_t raw;
    co_sim_port_attach_raw(bus, &raw, NULL, NULL);
    add_node(bus, &n, 5);
    co_sim_run_until(bus, 1000);
    CHECK(n.port.indexed); /* the node told the port its routes */
    uint32_t rx = co_node_stats(&n.node)->rx_frames;

    put(bus, &raw, frm(0x205, "01 02 03 04")); /* RPDO1 */
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, rx + 1);
    CHECK_EQ(n.rpdos, 1);
    put(bus, &raw, frm(0x206, "01 02 03 04")); /* another node's: filtered out */
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, rx + 1);

    /* RPDO1 moves to an 11-bit COB-ID, then to a 29-bit one: the bus follows each time. */
    CHECK_EQ(co_node_set_uint(&n.node, 0x1400, 1, 0x80000000u | 0x255), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&n.node, 0x1400, 1, 0x255), CO_ABORT_NONE);
    put(bus, &raw, frm(0x205, "01 02 03 04"));
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, rx + 1);
    put(bus, &raw, frm(0x255, "01 02 03 04"));
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, rx + 2);
    CHECK_EQ(n.rpdos, 2);
    CHECK_EQ(co_node_set_uint(&n.node, 0x1400, 1, 0x80000000u | 0x255), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&n.node, 0x1400, 1, 0x20000000u | 0x1234567), CO_ABORT_NONE);
    put(bus, &raw, frm(0x255, "01 02 03 04"));
    put(bus, &raw, frm(0x1234566, "01 02 03 04"));
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, rx + 2);
    put(bus, &raw, frm(0x1234567, "01 02 03 04"));
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, rx + 3);
    CHECK_EQ(n.rpdos, 3);
}

/* A driver of the application's own around a port. */
static co_err_t own_tx(void *ctx, const co_frame_t *frame) { return co_sim_send(ctx, frame); }
static void own_routes_changed(void *ctx) { co_sim_port_routes_changed(ctx); }

static void test_delivery_any_driver(void)
{
    /* A node whose driver notifies through co_sim_port_routes_changed is indexed; one whose
     * driver does not notify stays on co_node_accepts. Both get exactly their frames. */
    co_sim_bus_t *bus = new_bus(0);
    static sim_node_t notifying, silent;
    memset(&notifying, 0, sizeof notifying);
    memset(&silent, 0, sizeof silent);
    co_sim_port_t raw;
    co_sim_port_attach_raw(bus, &raw, NULL, NULL);
    co_sim_port_attach(bus, &notifying.port);
    co_sim_port_attach(bus, &silent.port);
    co_driver_t d = {.tx = own_tx, .on_routes_changed = own_routes_changed, .ctx = &notifying.port};
    add_node_with(bus, &notifying, 6, d);
    d = (co_driver_t){.tx = own_tx, .ctx = &silent.port};
    add_node_with(bus, &silent, 7, d);
    co_sim_run_until(bus, 1000);
    CHECK(notifying.port.indexed);
    CHECK(!silent.port.indexed);
    uint32_t rx6 = co_node_stats(&notifying.node)->rx_frames;
    uint32_t rx7 = co_node_stats(&silent.node)->rx_frames;
    put(bus, &raw, frm(0x206, "01 02 03 04"));
    put(bus, &raw, frm(0x207, "01 02 03 04"));
    put(bus, &raw, frm(0x208, "01 02 03 04"));
    put(bus, &raw, frm(0x000, "01 00")); /* NMT to all: both */
    CHECK_EQ(co_node_stats(&notifying.node)->rx_frames, rx6 + 2);
    CHECK_EQ(co_node_stats(&silent.node)->rx_frames, rx7 + 2);
    CHECK_EQ(notifying.rpdos, 1);
    CHECK_EQ(silent.rpdos, 1);
}

static void test_delivery_node_initialised_again(void)
{
    /* co_node_init empties a node's routes without a notification: until the node starts
     * again it takes no frame, whatever the bus's index still holds. */
    co_sim_bus_t *bus = new_bus(0);
    static sim_node_t n;
    co_sim_port_t raw;
    co_sim_port_attach_raw(bus, &raw, NULL, NULL);
    add_node(bus, &n, 5);
    co_sim_run_until(bus, 1000);
    co_node_config_t cfg = {
        .node_id = 5, .od = example_od_init(&n.od, 0), .driver = co_sim_port_driver(&n.port)};
    CHECK_EQ(co_node_init(&n.node, &cfg), CO_OK);
    put(bus, &raw, frm(0x000, "01 00"));
    put(bus, &raw, frm(0x605, "40 00 10 00 00 00 00 00"));
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, 0);
    CHECK_EQ(co_node_start(&n.node, bus->now_us), CO_OK);
    put(bus, &raw, frm(0x605, "40 00 10 00 00 00 00 00"));
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, 1);
}

static void test_delivery_routes_changed_by_earlier_receiver(void)
{
    /* Ports take a frame in attach order, each as its routes are at its turn: node 1's
     * RPDO callback moves node 2's RPDO1 onto the very COB-ID being delivered, and node 2,
     * attached after node 1, receives that same frame. */
    co_sim_bus_t *bus = new_bus(0);
    static sim_node_t first, second;
    co_sim_port_t raw;
    co_sim_port_attach_raw(bus, &raw, NULL, NULL);
    add_node(bus, &first, 1);
    add_node(bus, &second, 2);
    co_sim_run_until(bus, 1000);
    CHECK_EQ(co_node_set_uint(&first.node, 0x1400, 1, 0x80000000u | 0x3AB), CO_ABORT_NONE);
    CHECK_EQ(co_node_set_uint(&first.node, 0x1400, 1, 0x3AB), CO_ABORT_NONE);
    first.other = &second;
    put(bus, &raw, frm(0x3AB, "01 02 03 04"));
    CHECK_EQ(first.rpdos, 1);
    CHECK_EQ(second.rpdos, 1);
}

int main(void)
{
    RUN(test_bus_counts_frame_bits);
    RUN(test_arbitration_order_many);
    RUN(test_instant_order_with_delays);
    RUN(test_bus_off_leaves_order);
    RUN(test_delivery_follows_routes);
    RUN(test_delivery_any_driver);
    RUN(test_delivery_node_initialised_again);
    RUN(test_delivery_routes_changed_by_earlier_receiver);
    return check_summary();
}
