/* SPDX-License-Identifier: Apache-2.0 */
/*
 * port/sim/sim.c -- the simulated CAN bus; see canola/sim.h.
 *
 * The run loop visits the instants at which something happens (a node deadline, a frame
 * leaving the wire, a frame becoming ready) and at each one does everything due before
 * moving on, so a simulation is a pure function of its inputs and the seed.
 *
 * Time in the timing model: a bit lasts 1/bitrate s, which is not a whole number of
 * microseconds at every bitrate (1.25 us at 800 kbit/s). The bus therefore keeps the exact
 * end of the latest frame as microseconds plus a remainder in 1/bitrate us; back-to-back
 * frames start at the exact end of the previous one and long runs do not drift. The rest of
 * the world sees whole microseconds: a frame reaches the receivers at its end rounded up.
 *
 * Cost per frame, whatever the number of ports: the frame's length is worked out a byte at a
 * time when it is sent, the pending frames are a heap in the order they will win the bus, and
 * a completed frame goes only to the ports the delivery index names for its identifier.
 */
#include "canola/sim.h"

#include <inttypes.h>
#include <stdio.h>
#include <string.h>

_Static_assert(CO_SIM_PORTS_MAX <= 256, "port indices are stored in 8 bits");

#define STORM_EVENTS 1000000u /* events at one instant before a run gives up */
#define DEFAULT_MAILBOXES 3u
#define CRC15_POLY 0x4599u
/* After the CRC: CRC delimiter, ACK slot, ACK delimiter, EOF (7), interframe space (3). */
#define TAIL_BITS (1u + 1u + 1u + 7u + 3u)

/* ---- Frame length on the wire. */

/* A bit stream being measured: CRC over what is fed with `in_crc`, stuff bits counted. */
typedef struct wire {
    uint32_t bits; /* bits so far, stuff bits included */
    uint16_t crc;
    uint8_t level; /* level of the latest bit on the wire */
    uint8_t run;   /* bits of that level in a row (a stuff bit starts a new run) */
} wire_t;

static uint16_t crc15_bit(uint16_t crc, uint8_t bit)
{
    bool feedback = (bit ^ (crc >> 14)) & 1u;
    crc = (uint16_t)(((uint32_t)crc << 1) & 0x7FFFu);
    return feedback ? (uint16_t)(crc ^ CRC15_POLY) : crc;
}

/* One bit on the wire: 1 when a stuff bit follows it. */
static uint32_t stuff_bit(uint8_t *level, uint8_t *run, uint8_t bit)
{
    *run = (uint8_t)((*run > 0 && bit == *level) ? *run + 1 : 1);
    *level = bit;
    if (*run == 5) { /* five equal bits: the transmitter inserts the opposite level */
        *level ^= 1u;
        *run = 1;
        return 1;
    }
    return 0;
}

/* Feed the `n` low bits of `value`, most significant first. */
static void wire_put(wire_t *w, uint32_t value, unsigned n, bool in_crc)
{
    while (n-- > 0) {
        uint8_t bit = (uint8_t)((value >> n) & 1u);
        if (in_crc) {
            w->crc = crc15_bit(w->crc, bit);
        }
        w->bits += 1 + stuff_bit(&w->level, &w->run, bit);
    }
}

uint32_t co_sim_frame_bits(const co_frame_t *frame)
{
    wire_t w = {0};
    uint32_t rtr = (frame->flags & CO_FRAME_RTR) ? 1u : 0u;
    uint8_t len = frame->len > 8 ? 8 : frame->len;

    wire_put(&w, 0, 1, true); /* SOF */
    if (frame->flags & CO_FRAME_EXT) {
        wire_put(&w, (frame->id >> 18) & 0x7FFu, 11, true); /* base ID */
        wire_put(&w, 3u, 2, true);                          /* SRR, IDE: recessive */
        wire_put(&w, frame->id & 0x3FFFFu, 18, true);       /* ID extension */
        wire_put(&w, rtr << 2, 3, true);                    /* RTR, r1, r0 */
    } else {
        wire_put(&w, frame->id & 0x7FFu, 11, true);
        wire_put(&w, rtr << 2, 3, true); /* RTR, IDE, r0 */
    }
    wire_put(&w, len, 4, true); /* DLC */
    for (uint8_t i = 0; !rtr && i < len; i++) {
        wire_put(&w, frame->data[i], 8, true);
    }
    wire_put(&w, w.crc, 15, false); /* the CRC sequence is stuffed too */
    return w.bits + TAIL_BITS;
}

/* The same length a byte at a time, with the bus's tables (built from the functions above at
 * co_sim_bus_init). The CRC reads the frame's bits in whole bytes from the right: leading
 * zeros leave a CRC at zero, so the header is padded in front to whole bytes and the data
 * bytes follow as they are. The stuffing reads the bits from SOF in whole bytes, and the few
 * bits after the last whole byte one by one. */

/* State of the stuffing between bytes: level * 5 + run (run 0: no bit yet). */
#define STUFF_STATES 10u

static void build_wire_tables(co_sim_bus_t *bus)
{
    for (uint32_t b = 0; b < 256; b++) {
        wire_t w = {0};
        wire_put(&w, b, 8, true);
        bus->crc15_table[b] = w.crc;
        for (uint8_t state = 0; state < STUFF_STATES; state++) {
            wire_t x = {.level = (uint8_t)(state / 5u), .run = (uint8_t)(state % 5u)};
            wire_put(&x, b, 8, false);
            bus->stuff_table[state][b] = (uint8_t)((x.bits - 8u) << 4 | (x.level * 5u + x.run));
        }
    }
}

static uint16_t crc15_byte(const co_sim_bus_t *bus, uint16_t crc, uint8_t byte)
{
    uint32_t top = ((uint32_t)crc >> 7 ^ byte) & 0xFFu;
    return (uint16_t)(((uint32_t)crc << 8 & 0x7FFFu) ^ bus->crc15_table[top]);
}

/* The stuffing of a bit stream fed in pieces. */
typedef struct stuffing {
    uint64_t acc;  /* the latest bits; the low `rest` are not counted yet */
    uint32_t rest; /* < 8 between calls */
    uint32_t bits; /* bits counted, stuff bits included */
    uint8_t state;
} stuffing_t;

static void stuff_byte(const co_sim_bus_t *bus, stuffing_t *s, uint8_t byte)
{
    uint8_t e = bus->stuff_table[s->state][byte];
    s->bits += 8u + (e >> 4);
    s->state = e & 15u;
}

/* Feed the `n` (<= 32) low bits of `value`. */
static void stuff_feed(const co_sim_bus_t *bus, stuffing_t *s, uint32_t value, unsigned n)
{
    s->acc = (s->acc << n) | (value & (uint32_t)((1ull << n) - 1u));
    s->rest += n;
    while (s->rest >= 8) {
        s->rest -= 8;
        stuff_byte(bus, s, (uint8_t)(s->acc >> s->rest));
    }
}

static uint32_t frame_bits_fast(const co_sim_bus_t *bus, const co_frame_t *frame)
{
    uint32_t rtr = (frame->flags & CO_FRAME_RTR) ? 1u : 0u;
    uint8_t len = frame->len > 8 ? 8 : frame->len;
    uint8_t data_len = rtr ? 0 : len;
    stuffing_t s = {0};
    uint16_t crc = 0;
    if (frame->flags & CO_FRAME_EXT) { /* SOF, base ID, SRR, IDE, ID extension; RTR r1 r0, DLC */
        uint32_t id = ((frame->id >> 18) & 0x7FFu) << 20 | 3u << 18 | (frame->id & 0x3FFFFu);
        uint32_t tail = rtr << 6 | len;
        crc = crc15_byte(bus, crc, (uint8_t)(id >> 25)); /* 39 bits in 5 bytes: 1 bit of pad */
        crc = crc15_byte(bus, crc, (uint8_t)(id >> 17));
        crc = crc15_byte(bus, crc, (uint8_t)(id >> 9));
        crc = crc15_byte(bus, crc, (uint8_t)(id >> 1));
        crc = crc15_byte(bus, crc, (uint8_t)(id << 7 | tail));
        stuff_feed(bus, &s, id, 32);
        stuff_feed(bus, &s, tail, 7);
    } else {                                                        /* SOF, ID, RTR IDE r0, DLC */
        uint32_t head = (frame->id & 0x7FFu) << 7 | rtr << 6 | len; /* 19 bits: 5 of pad */
        crc = crc15_byte(bus, crc, (uint8_t)(head >> 16));
        crc = crc15_byte(bus, crc, (uint8_t)(head >> 8));
        crc = crc15_byte(bus, crc, (uint8_t)head);
        stuff_feed(bus, &s, head, 19);
    }
    for (uint8_t i = 0; i < data_len; i++) { /* whole bytes: `rest` stays as it is */
        crc = crc15_byte(bus, crc, frame->data[i]);
        s.acc = s.acc << 8 | frame->data[i];
        stuff_byte(bus, &s, (uint8_t)(s.acc >> s.rest));
    }
    stuff_feed(bus, &s, crc, 15);
    uint8_t level = (uint8_t)(s.state / 5u);
    uint8_t run = (uint8_t)(s.state % 5u);
    for (uint32_t k = s.rest; k-- > 0;) {
        s.bits += 1 + stuff_bit(&level, &run, (uint8_t)((s.acc >> k) & 1u));
    }
    return s.bits + TAIL_BITS;
}

/* The arbitration field as a number, first bit most significant: the lowest value wins (0 is
 * dominant). A standard frame's IDE (0) beats the SRR/IDE (1 1) of an extended frame with the
 * same base ID; a data frame beats a remote frame with the same ID. */
static uint32_t arbitration_key(const co_frame_t *f)
{
    uint32_t rtr = (f->flags & CO_FRAME_RTR) ? 1u : 0u;
    if (f->flags & CO_FRAME_EXT) {
        return ((f->id >> 18) & 0x7FFu) << 21 | 3u << 19 | (f->id & 0x3FFFFu) << 1 | rtr;
    }
    return (f->id & 0x7FFu) << 21 | rtr << 20;
}

/* Send order, robust to the sequence number wrapping. */
static bool seq_before(uint32_t a, uint32_t b) { return (int32_t)(a - b) < 0; }

/* ---- Exact time of the timing model: us + rem / bitrate microseconds, rem < bitrate. */

typedef struct exact {
    uint64_t us;
    uint32_t rem;
} exact_t;

static exact_t exact_add_bits(exact_t t, uint32_t bits, uint32_t bitrate)
{
    uint64_t total = t.rem + (uint64_t)bits * 1000000u;
    t.us += total / bitrate;
    t.rem = (uint32_t)(total % bitrate);
    return t;
}

static uint64_t exact_ceil(exact_t t) { return t.us + (t.rem > 0); }

/* floor(bits * 10^6 / bitrate) without overflowing for any realistic bit count. */
static uint64_t bits_to_us(uint64_t bits, uint32_t bitrate)
{
    return bits / bitrate * 1000000u + bits % bitrate * 1000000u / bitrate;
}

/* ---- Fault injection: splitmix64, whose state is the bus's `rng`. */

static uint64_t rng_next(co_sim_bus_t *bus)
{
    uint64_t z = (bus->rng += 0x9E3779B97F4A7C15u);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9u;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBu;
    return z ^ (z >> 31);
}

/* True with probability p. Draws nothing when p is 0, so an unused fault leaves the
 * sequence of the others alone. */
static bool rng_chance(co_sim_bus_t *bus, double p)
{
    return p > 0.0 && (double)(rng_next(bus) >> 11) * 0x1p-53 < p;
}

static double clamp_p(double p) { return p > 0.0 ? (p < 1.0 ? p : 1.0) : 0.0; }

static bool fault_drops(co_sim_bus_t *bus)
{
    bus->sent_count++;
    bool nth = bus->drop_nth != 0 && bus->sent_count == bus->drop_nth;
    bool random = rng_chance(bus, bus->drop_p);
    return nth || random;
}

/* Flip one data bit: an error that CAN's CRC would have missed. */
static void fault_corrupt(co_sim_bus_t *bus, co_frame_t *f)
{
    if ((f->flags & CO_FRAME_RTR) || f->len == 0 || !rng_chance(bus, bus->corrupt_p)) {
        return;
    }
    uint32_t bit = (uint32_t)(rng_next(bus) % (f->len * 8u));
    f->data[bit / 8] = (uint8_t)(f->data[bit / 8] ^ (1u << (bit % 8)));
    bus->stats.corrupted++;
}

/* ---- Bus and ports. */

co_err_t co_sim_bus_init(co_sim_bus_t *bus, uint32_t bitrate)
{
    if (!bus || (bitrate != 0 && (bitrate < 10000 || bitrate > 1000000))) {
        return CO_ERR_ARG;
    }
    memset(bus, 0, sizeof *bus);
    bus->bitrate = bitrate;
    strcpy(bus->name, "sim0");
    build_wire_tables(bus);
    return CO_OK;
}

/* ---- The delivery index: which ports a frame goes to. */

static uint64_t port_bit(const co_sim_port_t *port) { return 1ull << (port->index % 64u); }

static void portset_put(co_sim_portset_t *set, const co_sim_port_t *port, bool member)
{
    uint64_t *word = &set->bits[port->index / 64u];
    *word = member ? *word | port_bit(port) : *word & ~port_bit(port);
}

/* Enter a node port's routes into the index, or (not indexed) make it see every frame. */
static void index_port(co_sim_bus_t *bus, const co_sim_port_t *port)
{
    for (uint32_t id = 0; id <= CO_ID_STD_MAX; id++) {
        portset_put(&bus->receivers[id], port, false);
    }
    portset_put(&bus->ext_receivers, port, false);
    portset_put(&bus->every_frame, port, port->node && !port->indexed);
    if (!port->node || !port->indexed) {
        return;
    }
    uint32_t count = co_node_route_count(port->node);
    for (uint32_t i = 0; i < count; i++) {
        uint32_t key = co_node_route_id(port->node, i); /* bit 31: a 29-bit identifier */
        portset_put(key & 0x80000000u ? &bus->ext_receivers : &bus->receivers[key & CO_ID_STD_MAX],
                    port, true);
    }
}

void co_sim_port_routes_changed(co_sim_port_t *port)
{
    if (port && port->bus && port->node) { /* before co_sim_port_bind: bind indexes it */
        port->indexed = true;
        index_port(port->bus, port);
    }
}

/* Attaching resets the port: set `mailboxes` afterwards. */
static co_err_t attach(co_sim_bus_t *bus, co_sim_port_t *port)
{
    if (!bus || !port) {
        return CO_ERR_ARG;
    }
    if (bus->port_count >= CO_SIM_PORTS_MAX) {
        return CO_ERR_FULL;
    }
    memset(port, 0, sizeof *port);
    port->bus = bus;
    port->mailboxes = DEFAULT_MAILBOXES;
    port->index = (uint8_t)bus->port_count;
    bus->ports[bus->port_count++] = port;
    return CO_OK;
}

co_err_t co_sim_port_attach(co_sim_bus_t *bus, co_sim_port_t *port) { return attach(bus, port); }

co_err_t co_sim_port_attach_raw(co_sim_bus_t *bus, co_sim_port_t *port, co_sim_rx_fn rx, void *ctx)
{
    co_err_t err = attach(bus, port);
    if (err == CO_OK) {
        port->rx = rx;
        port->rx_ctx = ctx;
        portset_put(&bus->every_frame, port, true);
    }
    return err;
}

static co_err_t port_tx(void *ctx, const co_frame_t *frame) { return co_sim_send(ctx, frame); }

static void port_routes_changed(void *ctx) { co_sim_port_routes_changed(ctx); }

/* A node's next poll; the bus keeps a lower bound of them all, so that instants with no
 * poll due skip the scan of every port (a big network has one frame per instant). */
static void set_due(co_sim_port_t *port, uint64_t due_us)
{
    port->node_due_us = due_us;
    if (due_us < port->bus->due_min_us) {
        port->bus->due_min_us = due_us;
    }
}

co_driver_t co_sim_port_driver(co_sim_port_t *port)
{
    co_driver_t d = {.tx = port_tx, .on_routes_changed = port_routes_changed, .ctx = port};
    return d;
}

void co_sim_port_bind(co_sim_port_t *port, co_node_t *node)
{
    port->node = node;
    /* Whether this node notifies is unknown until it does: it sees every frame until then. */
    port->indexed = false;
    index_port(port->bus, port);
    set_due(port, 0); /* unknown: poll at the next instant the bus runs */
}

/* ---- The pending frames: a binary heap whose top is the frame that goes next when it is
 * ready (timing model: the lowest arbitration key; instant delivery: the oldest; ties: the
 * oldest). Selection takes the top when it is ready, and only otherwise (a frame sent with a
 * delay, or after the instant arbitration began) looks through them all. */

static bool goes_before(const co_sim_bus_t *bus, const co_sim_pending_t *a,
                        const co_sim_pending_t *b)
{
    if (bus->bitrate && a->key != b->key) {
        return a->key < b->key;
    }
    return seq_before(a->seq, b->seq);
}

static void heap_up(co_sim_bus_t *bus, uint32_t i)
{
    co_sim_pending_t p = bus->pending[i];
    while (i > 0 && goes_before(bus, &p, &bus->pending[(i - 1) / 2])) {
        bus->pending[i] = bus->pending[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    bus->pending[i] = p;
}

static void heap_down(co_sim_bus_t *bus, uint32_t i)
{
    co_sim_pending_t p = bus->pending[i];
    for (uint32_t child; (child = 2 * i + 1) < bus->pending_count; i = child) {
        if (child + 1 < bus->pending_count &&
            goes_before(bus, &bus->pending[child + 1], &bus->pending[child])) {
            child++;
        }
        if (!goes_before(bus, &bus->pending[child], &p)) {
            break;
        }
        bus->pending[i] = bus->pending[child];
    }
    bus->pending[i] = p;
}

static void pending_push(co_sim_bus_t *bus, const co_sim_pending_t *p)
{
    bus->pending[bus->pending_count++] = *p;
    heap_up(bus, bus->pending_count - 1);
}

/* Remove and return the i-th entry; the last one fills its place. */
static co_sim_pending_t pending_take(co_sim_bus_t *bus, uint32_t i)
{
    co_sim_pending_t p = bus->pending[i];
    if (i < --bus->pending_count) {
        bus->pending[i] = bus->pending[bus->pending_count];
        heap_up(bus, i);
        heap_down(bus, i);
    }
    return p;
}

co_err_t co_sim_send(co_sim_port_t *port, const co_frame_t *frame)
{
    if (!port || !port->bus || !frame || frame->len > 8 ||
        frame->id > ((frame->flags & CO_FRAME_EXT) ? CO_ID_EXT_MAX : CO_ID_STD_MAX)) {
        return CO_ERR_ARG;
    }
    co_sim_bus_t *bus = port->bus;
    if (port->bus_off) {
        return CO_OK; /* a bus-off controller takes the frame and sends nothing */
    }
    if (port->in_flight >= port->mailboxes) {
        bus->stats.refused++;
        return CO_ERR_BUSY;
    }
    if (bus->pending_count >= CO_SIM_PENDING_MAX) {
        bus->stats.overflow++;
        return CO_ERR_BUSY;
    }
    co_sim_pending_t p = {.frame = *frame,
                          .ready_us = bus->now_us + bus->delay_us,
                          .seq = bus->seq++,
                          .bits = frame_bits_fast(bus, frame), /* arbitration and completion */
                          .key = arbitration_key(frame),
                          .port = port->index};
    pending_push(bus, &p);
    port->in_flight++;
    return CO_OK;
}

void co_sim_set_bus_off(co_sim_port_t *port, bool bus_off)
{
    port->bus_off = bus_off;
    co_sim_bus_t *bus = port->bus;
    if (!bus_off || !bus) {
        return;
    }
    /* A controller going bus-off abandons what waits in its mailboxes; a frame already on
     * the wire finishes. */
    uint32_t kept = 0;
    for (uint32_t i = 0; i < bus->pending_count; i++) {
        if (bus->pending[i].port == port->index) {
            port->in_flight--;
        } else {
            bus->pending[kept++] = bus->pending[i];
        }
    }
    bus->pending_count = kept;
    for (uint32_t i = kept / 2; i-- > 0;) {
        heap_down(bus, i);
    }
}

/* ---- Delivery. */

static void trace_frame(const co_sim_bus_t *bus, uint64_t t, const co_frame_t *f)
{
    if (bus->trace) {
        char line[96];
        bus->trace(bus->trace_ctx, co_sim_format(line, sizeof line, t, bus->name, f));
    }
}

static void receive(co_sim_port_t *port, uint64_t t, const co_frame_t *f)
{
    if (port->bus_off) {
        return;
    }
    if (port->node) {
        /* The controller's acceptance filter. The index named this port, but a node
         * initialised again since its last notification may have dropped the route. */
        if (co_node_accepts(port->node, f)) {
            co_node_ingest(port->node, t, f);
            set_due(port, co_node_poll(port->node, t));
        }
    } else if (port->rx) {
        port->rx(port->rx_ctx, t, f);
    }
}

/* Hand a frame to the ports the index names for it, all but the sender, in the order they
 * were attached. The index is read afresh after each port: a receiver's callbacks may change
 * the routes of a port further on, which then receives as its routes are at its turn. */
static void deliver(co_sim_bus_t *bus, uint64_t t, const co_frame_t *f, uint32_t sender)
{
    const co_sim_portset_t *named =
        (f->flags & CO_FRAME_EXT) ? &bus->ext_receivers : &bus->receivers[f->id & CO_ID_STD_MAX];
    for (uint32_t w = 0; w < CO_SIM_PORT_WORDS; w++) {
        uint64_t after = ~0ull; /* the ports of this word not visited yet */
        uint64_t todo;
        while ((todo = (named->bits[w] | bus->every_frame.bits[w]) & after) != 0) {
            uint32_t b = (uint32_t)__builtin_ctzll(todo);
            after = b == 63 ? 0 : ~0ull << (b + 1);
            uint32_t i = w * 64u + b;
            if (i != sender) {
                receive(bus->ports[i], t, f);
            }
        }
    }
}

/* A frame has left the wire at `t`: apply the faults, hand it to every other port, free
 * the sender's mailbox and let its node send what it queued meanwhile. */
static void complete(co_sim_bus_t *bus, uint64_t t, const co_sim_pending_t *p)
{
    co_frame_t frame = p->frame;
    bus->stats.frames++;
    bus->stats.bits += p->bits;
    if (bus->bitrate) {
        bus->stats.busy_us = bits_to_us(bus->stats.bits, bus->bitrate);
    }
    if (fault_drops(bus)) {
        bus->stats.dropped++;
    } else {
        fault_corrupt(bus, &frame);
        trace_frame(bus, t, &frame);
        deliver(bus, t, &frame, p->port);
    }
    co_sim_port_t *sender = bus->ports[p->port];
    sender->in_flight--;
    if (sender->node) {
        set_due(sender, co_node_poll(sender->node, t));
    } else if (sender->sent) {
        sender->sent(sender->rx_ctx, t, &p->frame);
    }
}

/* Index of the next frame to complete at `t`, or -1: in instant mode the oldest ready
 * frame; in the timing model the frame on the wire once its end has come. */
static int32_t next_completion(const co_sim_bus_t *bus, uint64_t t)
{
    if (bus->bitrate) {
        exact_t end = {bus->idle_at_us, bus->idle_rem};
        return (bus->transmitting && exact_ceil(end) <= t) ? 0 : -1;
    }
    if (bus->pending_count > 0 && bus->pending[0].ready_us <= t) {
        return 0; /* the oldest frame, ready */
    }
    int32_t best = -1;
    for (uint32_t i = 0; i < bus->pending_count; i++) {
        const co_sim_pending_t *p = &bus->pending[i];
        if (p->ready_us <= t && (best < 0 || seq_before(p->seq, bus->pending[best].seq))) {
            best = (int32_t)i;
        }
    }
    return best;
}

static co_sim_pending_t take_completion(co_sim_bus_t *bus, int32_t i)
{
    if (bus->bitrate) {
        bus->transmitting = false;
        return bus->on_bus;
    }
    return pending_take(bus, (uint32_t)i);
}

static uint64_t first_ready(const co_sim_bus_t *bus)
{
    uint64_t first = CO_TIME_NEVER;
    for (uint32_t i = 0; i < bus->pending_count; i++) {
        first = bus->pending[i].ready_us < first ? bus->pending[i].ready_us : first;
    }
    return first;
}

/* Timing model: when the bus falls idle (or was idle when a frame became ready), the frames
 * ready by then arbitrate; the winner occupies the wire for its length. Called once all
 * else at `t` is done, so every frame ready at `t` takes part. */
static void start_transmission(co_sim_bus_t *bus, uint64_t t)
{
    if (bus->transmitting || bus->pending_count == 0) {
        return;
    }
    exact_t start = {bus->idle_at_us, bus->idle_rem};
    /* A top ready by the end of the previous frame wins: no other can start the bus sooner. */
    bool top_ready = bus->pending[0].ready_us <= start.us;
    uint64_t first = top_ready ? start.us : first_ready(bus);
    if (first > start.us) {
        start = (exact_t){first, 0}; /* the bus was idle: the frame starts when ready */
    }
    if (exact_ceil(start) > t) {
        return;
    }
    uint32_t best = 0;
    for (uint32_t i = 1; !top_ready && i < bus->pending_count; i++) {
        const co_sim_pending_t *p = &bus->pending[i];
        if (p->ready_us <= start.us &&
            (bus->pending[best].ready_us > start.us || goes_before(bus, p, &bus->pending[best]))) {
            best = i; /* the winner among the frames ready when arbitration began */
        }
    }
    bus->on_bus = pending_take(bus, best);
    bus->transmitting = true;
    exact_t end = exact_add_bits(start, bus->on_bus.bits, bus->bitrate);
    bus->idle_at_us = end.us;
    bus->idle_rem = end.rem;
}

/* Do everything due at `t`: completions, then node deadlines, again until quiet; then
 * arbitration. Counts events against the storm guard. */
static co_err_t run_instant(co_sim_bus_t *bus, uint64_t t)
{
    uint32_t events = 0;
    bool busy;
    do {
        busy = false;
        for (int32_t i; (i = next_completion(bus, t)) >= 0;) {
            if (++events > STORM_EVENTS) {
                return CO_ERR_STATE;
            }
            co_sim_pending_t p = take_completion(bus, i);
            complete(bus, t, &p);
            busy = true;
        }
        if (bus->due_min_us > t) {
            continue; /* no node has a poll due: no scan (busy says whether to go on) */
        }
        uint64_t due_min = CO_TIME_NEVER;
        for (uint32_t i = 0; i < bus->port_count; i++) {
            co_sim_port_t *port = bus->ports[i];
            if (port->node && port->node_due_us <= t) {
                if (++events > STORM_EVENTS) {
                    return CO_ERR_STATE;
                }
                port->node_due_us = co_node_poll(port->node, t);
                busy = true;
            }
            if (port->node && port->node_due_us < due_min) {
                due_min = port->node_due_us;
            }
        }
        bus->due_min_us = due_min; /* exact again: polls only change their own node's */
    } while (busy);
    if (bus->bitrate) {
        start_transmission(bus, t);
    }
    return CO_OK;
}

/* The next instant at which something happens, CO_TIME_NEVER if none. */
static uint64_t next_event(const co_sim_bus_t *bus)
{
    /* A lower bound: at worst an instant with nothing due, which only rescans. */
    uint64_t next = bus->due_min_us;
    /* With nothing on the wire the bus has been idle since the latest instant handled, so
     * the next frame starts when it is ready. */
    exact_t end = {bus->idle_at_us, bus->idle_rem};
    uint64_t frames = bus->transmitting ? exact_ceil(end) : first_ready(bus);
    return frames < next ? frames : next;
}

co_err_t co_sim_run_until(co_sim_bus_t *bus, uint64_t until_us)
{
    if (!bus) {
        return CO_ERR_ARG;
    }
    if (until_us < bus->now_us) {
        return CO_OK; /* time never goes back */
    }
    /* The application may have called its nodes since the last run (new deadlines, frames
     * queued): poll each once at the start. */
    for (uint32_t i = 0; i < bus->port_count; i++) {
        if (bus->ports[i]->node && bus->ports[i]->node_due_us > bus->now_us) {
            set_due(bus->ports[i], bus->now_us);
        }
    }
    for (uint64_t t = bus->now_us;;) {
        bus->now_us = t; /* frames sent while handling `t` leave at `t` */
        co_err_t err = run_instant(bus, t);
        if (err != CO_OK) {
            return err;
        }
        t = next_event(bus);
        if (t == CO_TIME_NEVER || t > until_us) {
            break;
        }
    }
    bus->now_us = until_us;
    /* Tell every node the time, so that what the application calls between runs (start a
     * transfer, write an object) times itself from now, not from the node's last event. */
    for (uint32_t i = 0; i < bus->port_count; i++) {
        co_sim_port_t *port = bus->ports[i];
        if (port->node) {
            set_due(port, co_node_poll(port->node, until_us));
        }
    }
    return CO_OK;
}

/* ---- Settings. */

void co_sim_seed(co_sim_bus_t *bus, uint64_t seed) { bus->rng = seed; }

void co_sim_drop_nth(co_sim_bus_t *bus, uint64_t n)
{
    bus->drop_nth = n;
    bus->sent_count = 0;
}

void co_sim_drop_probability(co_sim_bus_t *bus, double p) { bus->drop_p = clamp_p(p); }
void co_sim_corrupt_probability(co_sim_bus_t *bus, double p) { bus->corrupt_p = clamp_p(p); }
void co_sim_delay(co_sim_bus_t *bus, uint64_t delay_us) { bus->delay_us = delay_us; }

void co_sim_set_trace(co_sim_bus_t *bus, co_sim_trace_fn fn, void *ctx)
{
    bus->trace = fn;
    bus->trace_ctx = ctx;
}

/* ---- Output. */

char *co_sim_format(char *buf, size_t cap, uint64_t t_us, const char *ifname,
                    const co_frame_t *frame)
{
    char payload[20] = "R";
    uint8_t len = frame->len > 8 ? 8 : frame->len;
    if (frame->flags & CO_FRAME_RTR) {
        if (len) {
            snprintf(payload, sizeof payload, "R%u", (unsigned)len);
        }
    } else {
        payload[0] = '\0';
        for (uint8_t i = 0; i < len; i++) {
            snprintf(payload + 2 * i, 3, "%02X", (unsigned)frame->data[i]);
        }
    }
    snprintf(buf, cap, "(%" PRIu64 ".%06" PRIu64 ") %s %0*" PRIX32 "#%s", t_us / 1000000u,
             t_us % 1000000u, ifname ? ifname : "", (frame->flags & CO_FRAME_EXT) ? 8 : 3,
             frame->id, payload);
    return buf;
}

const co_sim_stats_t *co_sim_stats(const co_sim_bus_t *bus) { return &bus->stats; }

double co_sim_load(const co_sim_bus_t *bus)
{
    return bus->now_us ? (double)bus->stats.busy_us / (double)bus->now_us : 0.0;
}
