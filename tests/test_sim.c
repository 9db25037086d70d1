/* SPDX-License-Identifier: Apache-2.0 */
/* tests/test_sim.c -- the simulated bus: timing, arbitration, faults, trace, nodes on it. */
#include "canola/sim.h"
#include "check.h"
#include "example_od.h"
#include "harness.h"

#include <stdlib.h>

/* ---- A raw port that records what it receives (and may answer at once). */

#define REC_MAX 512

typedef struct rec {
    uint64_t t[REC_MAX];
    co_frame_t f[REC_MAX];
    uint32_t n;
    co_sim_port_t *echo; /* when set, send every received frame back out of this port */
} rec_t;

static void rec_rx(void *ctx, uint64_t now_us, const co_frame_t *frame)
{
    rec_t *r = ctx;
    if (r->n < REC_MAX) {
        r->t[r->n] = now_us;
        r->f[r->n] = *frame;
        r->n++;
    }
    if (r->echo) {
        (void)co_sim_send(r->echo, frame);
    }
}

/* The trace as one string, lines separated by '\n'. */
typedef struct trace_buf {
    char text[8192];
    size_t len;
    uint32_t lines;
} trace_buf_t;

static void trace_rx(void *ctx, const char *line)
{
    trace_buf_t *tb = ctx;
    int n = snprintf(tb->text + tb->len, sizeof tb->text - tb->len, "%s\n", line);
    if (n > 0 && tb->len + (size_t)n < sizeof tb->text) {
        tb->len += (size_t)n;
    }
    tb->lines++;
}

/* The bus is large; every test uses this one, freshly initialised. */
static co_sim_bus_t g_bus;

static co_sim_bus_t *new_bus(uint32_t bitrate)
{
    CHECK_EQ(co_sim_bus_init(&g_bus, bitrate), CO_OK);
    return &g_bus;
}

/* ---- A reference implementation of the wire format, written differently from sim.c:
 * the frame as a string of '0'/'1', the CRC by polynomial long division, the stuffing by
 * rewriting the string. */

static void ref_append(char *s, uint32_t value, unsigned n)
{
    size_t len = strlen(s);
    for (unsigned i = 0; i < n; i++) {
        s[len + i] = (char)('0' + ((value >> (n - 1 - i)) & 1u));
    }
    s[len + n] = '\0';
}

/* Remainder of bits * x^15 divided by x^15 + x^14 + x^10 + x^8 + x^7 + x^4 + x^3 + 1. */
static uint32_t ref_crc15(const char *bits)
{
    static const char gen[] = "1100010110011001";
    char work[256];
    size_t n = strlen(bits);
    snprintf(work, sizeof work, "%s000000000000000", bits);
    for (size_t i = 0; i < n; i++) {
        if (work[i] == '1') {
            for (size_t j = 0; j < 16; j++) {
                work[i + j] = work[i + j] == gen[j] ? '0' : '1';
            }
        }
    }
    return (uint32_t)strtoul(work + n, NULL, 2);
}

static uint32_t ref_crc15_bytes(const uint8_t *data, size_t len)
{
    char bits[256] = "";
    for (size_t i = 0; i < len; i++) {
        ref_append(bits, data[i], 8);
    }
    return ref_crc15(bits);
}

/* Frame length on the wire; *stuff gets the number of stuff bits. */
static uint32_t ref_frame_bits(const co_frame_t *f, uint32_t *stuff)
{
    char bits[256] = "0"; /* SOF */
    bool rtr = (f->flags & CO_FRAME_RTR) != 0;
    if (f->flags & CO_FRAME_EXT) {
        ref_append(bits, f->id >> 18, 11);
        ref_append(bits, 1, 1); /* SRR */
        ref_append(bits, 1, 1); /* IDE */
        ref_append(bits, f->id & 0x3FFFF, 18);
        ref_append(bits, rtr, 1);
        ref_append(bits, 0, 2); /* r1 r0 */
    } else {
        ref_append(bits, f->id, 11);
        ref_append(bits, rtr, 1);
        ref_append(bits, 0, 2); /* IDE r0 */
    }
    ref_append(bits, f->len, 4);
    for (unsigned i = 0; !rtr && i < f->len; i++) {
        ref_append(bits, f->data[i], 8);
    }
    ref_append(bits, ref_crc15(bits), 15);

    char wire[512];
    size_t w = 0;
    for (size_t i = 0; bits[i]; i++) {
        wire[w++] = bits[i];
        if (w >= 5 && memcmp(wire + w - 5, "00000", 5) == 0) {
            wire[w++] = '1';
        } else if (w >= 5 && memcmp(wire + w - 5, "11111", 5) == 0) {
            wire[w++] = '0';
        }
    }
    wire[w] = '\0';
    CHECK(strstr(wire, "000000") == NULL && strstr(wire, "111111") == NULL);
    *stuff = (uint32_t)(w - strlen(bits));
    return (uint32_t)w + 13; /* CRC delimiter, ACK, ACK delimiter, EOF 7, IFS 3 */
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
    bool ext = lcg(s) & 1;
    /* Bias towards runs of equal bits, where stuffing happens. */
    uint32_t mode = (uint32_t)(lcg(s) % 3);
    uint32_t id = mode == 0 ? 0 : mode == 1 ? (uint32_t)lcg(s) : 0xFFFFFFFFu;
    f.id = id & (ext ? CO_ID_EXT_MAX : CO_ID_STD_MAX);
    f.flags = (uint8_t)((ext ? CO_FRAME_EXT : 0) | ((lcg(s) % 5 == 0) ? CO_FRAME_RTR : 0));
    f.len = (uint8_t)(lcg(s) % 9);
    for (unsigned i = 0; i < 8; i++) {
        f.data[i] = (uint8_t)(mode == 0 ? 0 : mode == 1 ? lcg(s) : 0xFF);
        if (lcg(s) % 4 == 0) {
            f.data[i] = (uint8_t)lcg(s);
        }
    }
    return f;
}

/* ---- Frame length. */

static void test_crc_reference(void)
{
    /* The catalogue check value of CRC-15/CAN. */
    CHECK_EQ(ref_crc15_bytes((const uint8_t *)"123456789", 9), 0x059E);
    CHECK_EQ(ref_crc15_bytes((const uint8_t *)"", 0), 0);
}

static void test_frame_bits_known(void)
{
    uint32_t stuff;
    /* ID 0, no data: SOF..DLC is 19 zeros and the CRC of zeros is 0, so 34 zeros in a row,
     * stuffed after every 5th: 6 stuff bits on the 47 bits of the bare frame. */
    co_frame_t zero = frm(0x000, "");
    CHECK_EQ(co_sim_frame_bits(&zero), 53);
    CHECK_EQ(ref_frame_bits(&zero, &stuff), 53);
    CHECK_EQ(stuff, 6);

    /* Alternating bits stuff less than runs of zeros. */
    co_frame_t alt = frm(0x555, "55 55 55 55 55 55 55 55");
    co_frame_t zeros8 = frm(0x000, "00 00 00 00 00 00 00 00");
    uint32_t alt_stuff, zero_stuff;
    CHECK_EQ(co_sim_frame_bits(&alt), ref_frame_bits(&alt, &alt_stuff));
    CHECK_EQ(co_sim_frame_bits(&zeros8), ref_frame_bits(&zeros8, &zero_stuff));
    CHECK(alt_stuff < zero_stuff);
    CHECK(co_sim_frame_bits(&alt) >= 111);
    CHECK(co_sim_frame_bits(&zeros8) <= 111 + 24);

    /* An RTR carries no data whatever its length. */
    co_frame_t rtr = frm(0x701, "R8");
    co_frame_t rtr0 = frm(0x701, "R0");
    CHECK_EQ(co_sim_frame_bits(&rtr), ref_frame_bits(&rtr, &stuff));
    CHECK(co_sim_frame_bits(&rtr) < 47 + 10);
    CHECK(co_sim_frame_bits(&rtr0) < 47 + 10);

    /* 29-bit: 20 more bits before stuffing (SRR, IDE, 18 ID bits). */
    co_frame_t ext = frm(0x18FF1234, "01 02");
    CHECK_EQ(co_sim_frame_bits(&ext), ref_frame_bits(&ext, &stuff));
    CHECK(co_sim_frame_bits(&ext) >= 67 + 16);
}

static void test_frame_bits_match_reference(void)
{
    uint64_t s = 42;
    uint32_t mismatches = 0;
    for (int i = 0; i < 20000; i++) {
        co_frame_t f = random_frame(&s);
        uint32_t stuff;
        uint32_t want = ref_frame_bits(&f, &stuff);
        uint32_t got = co_sim_frame_bits(&f);
        if (got != want && mismatches++ < 5) {
            char buf[40];
            printf("  frame %s: %u bits, reference %u\n", frame_str(&f, buf, sizeof buf), got,
                   want);
        }
        /* Bounds: unstuffed length, and at most one stuff bit per 4 bits after the first. */
        uint32_t data = (f.flags & CO_FRAME_RTR) ? 0 : f.len * 8u;
        uint32_t stuffable = ((f.flags & CO_FRAME_EXT) ? 54u : 34u) + data;
        CHECK(got >= stuffable + 13 && got <= stuffable + 13 + (stuffable - 1) / 4);
    }
    CHECK_EQ(mismatches, 0);
}

/* ---- Bus and ports. */

static void test_bus_init(void)
{
    co_sim_bus_t *bus = &g_bus;
    CHECK_EQ(co_sim_bus_init(bus, 5000), CO_ERR_ARG);
    CHECK_EQ(co_sim_bus_init(bus, 2000000), CO_ERR_ARG);
    CHECK_EQ(co_sim_bus_init(bus, 10000), CO_OK);
    CHECK_EQ(co_sim_bus_init(bus, 1000000), CO_OK);
    CHECK_EQ(co_sim_bus_init(bus, 0), CO_OK);
    CHECK_STR(bus->name, "sim0");
    CHECK_EQ(bus->now_us, 0);
    CHECK(co_sim_load(bus) == 0.0);

    static co_sim_port_t ports[CO_SIM_PORTS_MAX + 1];
    for (int i = 0; i < CO_SIM_PORTS_MAX; i++) {
        CHECK_EQ(co_sim_port_attach_raw(bus, &ports[i], NULL, NULL), CO_OK);
    }
    CHECK_EQ(co_sim_port_attach_raw(bus, &ports[CO_SIM_PORTS_MAX], NULL, NULL), CO_ERR_FULL);
    CHECK_EQ(ports[0].mailboxes, 3);
    CHECK_EQ(ports[129].index, 129);
}

static void test_run_moves_time(void)
{
    co_sim_bus_t *bus = new_bus(0);
    CHECK_EQ(co_sim_run_until(bus, 5000), CO_OK);
    CHECK_EQ(bus->now_us, 5000);
    CHECK_EQ(co_sim_run_until(bus, 100), CO_OK); /* never backwards */
    CHECK_EQ(bus->now_us, 5000);
}

static void test_send_rejects_bad_frames(void)
{
    co_sim_bus_t *bus = new_bus(0);
    co_sim_port_t a;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_frame_t f = frm(0x800, "");
    f.flags = 0; /* 0x800 does not fit 11 bits */
    CHECK_EQ(co_sim_send(&a, &f), CO_ERR_ARG);
    f = frm(0x100, "");
    f.len = 9;
    CHECK_EQ(co_sim_send(&a, &f), CO_ERR_ARG);
    CHECK_EQ(a.in_flight, 0);
}

/* ---- Instant mode. */

static void test_instant_order(void)
{
    co_sim_bus_t *bus = new_bus(0);
    static rec_t ra, rb, rc;
    memset(&ra, 0, sizeof ra), memset(&rb, 0, sizeof rb), memset(&rc, 0, sizeof rc);
    co_sim_port_t a, b, c;
    co_sim_port_attach_raw(bus, &a, rec_rx, &ra);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_sim_port_attach_raw(bus, &c, rec_rx, &rc);

    CHECK_EQ(co_sim_run_until(bus, 1000), CO_OK);
    co_frame_t f3 = frm(0x300, "03"), f1 = frm(0x100, "01"), f2 = frm(0x200, "02");
    co_frame_t fb = frm(0x050, "");
    CHECK_EQ(co_sim_send(&a, &f3), CO_OK);
    CHECK_EQ(co_sim_send(&a, &f1), CO_OK);
    CHECK_EQ(co_sim_send(&b, &fb), CO_OK);
    CHECK_EQ(co_sim_send(&a, &f2), CO_OK);
    CHECK_EQ(co_sim_run_until(bus, 2000), CO_OK);

    /* Send order, not ID order; everyone at the instant of sending; not to the sender. */
    CHECK_EQ(rc.n, 4);
    CHECK_EQ(rc.f[0].id, 0x300);
    CHECK_EQ(rc.f[1].id, 0x100);
    CHECK_EQ(rc.f[2].id, 0x050);
    CHECK_EQ(rc.f[3].id, 0x200);
    CHECK_EQ(rc.t[0], 1000);
    CHECK_EQ(rc.t[3], 1000);
    CHECK_EQ(rb.n, 3);
    CHECK_EQ(ra.n, 1);
    CHECK_EQ(ra.f[0].id, 0x050);
    CHECK_EQ(bus->stats.frames, 4);
    CHECK_EQ(bus->stats.busy_us, 0);
    CHECK_EQ(a.in_flight, 0);
}

static void test_instant_reply_same_instant(void)
{
    co_sim_bus_t *bus = new_bus(0);
    static rec_t ra, rb;
    memset(&ra, 0, sizeof ra), memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, rec_rx, &ra);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    rb.echo = &b; /* b answers every frame at once */
    co_frame_t f = frm(0x123, "AA");
    co_sim_send(&a, &f);
    CHECK_EQ(co_sim_run_until(bus, 10), CO_OK);
    CHECK_EQ(rb.n, 1);
    CHECK_EQ(ra.n, 1);
    CHECK_EQ(ra.t[0], 0);
}

static void test_mailboxes(void)
{
    co_sim_bus_t *bus = new_bus(125000);
    static rec_t rb;
    memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_frame_t f = frm(0x181, "01 02");
    CHECK_EQ(co_sim_send(&a, &f), CO_OK);
    CHECK_EQ(co_sim_send(&a, &f), CO_OK);
    CHECK_EQ(co_sim_send(&a, &f), CO_OK);
    CHECK_EQ(co_sim_send(&a, &f), CO_ERR_BUSY);
    CHECK_EQ(bus->stats.refused, 1);
    CHECK_EQ(a.in_flight, 3);

    /* A slot frees when the first frame leaves the wire, not before. */
    uint64_t first_end = co_sim_frame_bits(&f) * 8u;
    CHECK_EQ(co_sim_run_until(bus, first_end - 1), CO_OK);
    CHECK_EQ(co_sim_send(&a, &f), CO_ERR_BUSY);
    CHECK_EQ(co_sim_run_until(bus, first_end), CO_OK);
    CHECK_EQ(rb.n, 1);
    CHECK_EQ(a.in_flight, 2);
    CHECK_EQ(co_sim_send(&a, &f), CO_OK);
    CHECK_EQ(bus->stats.refused, 2);

    /* A single mailbox. */
    co_sim_run_until(bus, 10000);
    a.mailboxes = 1;
    CHECK_EQ(co_sim_send(&a, &f), CO_OK);
    CHECK_EQ(co_sim_send(&a, &f), CO_ERR_BUSY);
}

/* A raw port hears of its own frames leaving the wire (`sent`), at the instant the others
 * receive them, and not of frames it never got onto the wire. */
static void test_raw_port_sent(void)
{
    co_sim_bus_t *bus = new_bus(125000);
    static rec_t ra, rb;
    memset(&ra, 0, sizeof ra);
    memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, rec_rx, &ra);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    a.sent = rec_rx; /* into ra: a receives nothing else here */
    co_frame_t f = frm(0x181, "01 02");
    co_frame_t g = frm(0x182, "03");
    CHECK_EQ(co_sim_send(&a, &f), CO_OK);
    CHECK_EQ(co_sim_send(&a, &g), CO_OK);
    CHECK_EQ(co_sim_run_until(bus, 5000), CO_OK);
    CHECK_EQ(ra.n, 2);
    CHECK_EQ(rb.n, 2);
    CHECK_EQ(ra.f[0].id, 0x181);
    CHECK_EQ(ra.f[1].id, 0x182);
    CHECK_EQ(ra.t[0], rb.t[0]);
    CHECK_EQ(ra.t[1], rb.t[1]);
    /* a frame discarded by a bus-off port never leaves */
    co_sim_set_bus_off(&a, true);
    CHECK_EQ(co_sim_send(&a, &f), CO_OK);
    CHECK_EQ(co_sim_run_until(bus, 10000), CO_OK);
    CHECK_EQ(ra.n, 2);
}

static void test_pending_overflow(void)
{
    co_sim_bus_t *bus = new_bus(10000);
    static co_sim_port_t ports[5];
    co_frame_t f = frm(0x100, "");
    uint32_t ok = 0, busy = 0;
    for (int p = 0; p < 5; p++) {
        co_sim_port_attach_raw(bus, &ports[p], NULL, NULL);
        ports[p].mailboxes = 255;
        for (int i = 0; i < 255; i++) {
            co_err_t err = co_sim_send(&ports[p], &f);
            ok += err == CO_OK;
            busy += err == CO_ERR_BUSY;
        }
    }
    CHECK_EQ(ok, CO_SIM_PENDING_MAX);
    CHECK_EQ(busy, 5 * 255 - CO_SIM_PENDING_MAX);
    CHECK_EQ(bus->stats.overflow, busy);
    CHECK_EQ(bus->stats.refused, 0);
}

static void test_storm_guard(void)
{
    co_sim_bus_t *bus = new_bus(0);
    static rec_t ra, rb;
    memset(&ra, 0, sizeof ra), memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, rec_rx, &ra);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    ra.echo = &a;
    rb.echo = &b; /* ping-pong forever, all at one instant */
    co_sim_run_until(bus, 700);
    co_frame_t f = frm(0x001, "");
    co_sim_send(&a, &f);
    CHECK_EQ(co_sim_run_until(bus, 1000), CO_ERR_STATE);
    CHECK_EQ(bus->now_us, 700);
    CHECK_EQ(bus->stats.frames, 1000000);
}

/* ---- Timing model. */

/* Three ports queue frames at the same instant; a fourth watches. */
static void check_arbitration(uint32_t bitrate, uint32_t us_per_bit)
{
    co_sim_bus_t *bus = new_bus(bitrate);
    static rec_t rd;
    memset(&rd, 0, sizeof rd);
    co_sim_port_t a, b, c, d;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, NULL, NULL);
    co_sim_port_attach_raw(bus, &c, NULL, NULL);
    co_sim_port_attach_raw(bus, &d, rec_rx, &rd);
    co_frame_t f3 = frm(0x300, "03 03 03"), f1 = frm(0x100, "01"), f2 = frm(0x200, "");
    co_frame_t f0 = frm(0x050, "00 00 00 00 00 00 00 00");
    co_sim_send(&a, &f3);
    co_sim_send(&b, &f1);
    co_sim_send(&c, &f2);
    /* While 0x100 is on the wire, 0x050 becomes ready: it cannot preempt, but it wins the
     * next arbitration against the frames that waited longer. */
    CHECK_EQ(co_sim_run_until(bus, 10), CO_OK);
    co_sim_send(&a, &f0);
    CHECK_EQ(co_sim_run_until(bus, 100000), CO_OK);

    uint64_t t1 = co_sim_frame_bits(&f1) * us_per_bit;
    uint64_t t0 = t1 + co_sim_frame_bits(&f0) * us_per_bit;
    uint64_t t2 = t0 + co_sim_frame_bits(&f2) * us_per_bit;
    uint64_t t3 = t2 + co_sim_frame_bits(&f3) * us_per_bit;
    CHECK_EQ(rd.n, 4);
    CHECK_EQ(rd.f[0].id, 0x100);
    CHECK_EQ(rd.t[0], t1);
    CHECK_EQ(rd.f[1].id, 0x050);
    CHECK_EQ(rd.t[1], t0);
    CHECK_EQ(rd.f[2].id, 0x200);
    CHECK_EQ(rd.t[2], t2);
    CHECK_EQ(rd.f[3].id, 0x300);
    CHECK_EQ(rd.t[3], t3);
    CHECK_EQ(bus->stats.busy_us, t3);
    CHECK_EQ(bus->stats.bits, t3 / us_per_bit);
}

static void test_arbitration_125k(void) { check_arbitration(125000, 8); }
static void test_arbitration_1m(void) { check_arbitration(1000000, 1); }

static void test_arbitration_ext_std(void)
{
    co_sim_bus_t *bus = new_bus(500000);
    static rec_t rd;
    memset(&rd, 0, sizeof rd);
    co_sim_port_t a, b, d;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, NULL, NULL);
    co_sim_port_attach_raw(bus, &d, rec_rx, &rd);
    a.mailboxes = 4;
    b.mailboxes = 4;
    co_frame_t ext_same = frm((0x123u << 18) | 0x00001, "");  /* base 0x123, 29-bit */
    co_frame_t ext_low = frm((0x122u << 18) | 0x3FFFF, "");   /* base 0x122 */
    co_frame_t ext_same0 = frm((0x123u << 18) | 0x00000, ""); /* lower extension */
    co_frame_t std = frm(0x123, "");
    co_frame_t std_rtr = frm(0x123, "R0");
    co_sim_send(&a, &ext_same);
    co_sim_send(&a, &std_rtr);
    co_sim_send(&b, &ext_low);
    co_sim_send(&b, &std);
    co_sim_send(&b, &ext_same0);
    CHECK_EQ(co_sim_run_until(bus, 100000), CO_OK);
    CHECK_EQ(rd.n, 5);
    CHECK_EQ(rd.f[0].id, ext_low.id);       /* the base ID decides first */
    CHECK_EQ(rd.f[1].id, 0x123);            /* same base: 11-bit beats 29-bit, */
    CHECK(!(rd.f[1].flags & CO_FRAME_RTR)); /* data beats remote */
    CHECK_EQ(rd.f[2].id, 0x123);
    CHECK(rd.f[2].flags & CO_FRAME_RTR);
    CHECK_EQ(rd.f[3].id, ext_same0.id); /* then the full 29-bit ID */
    CHECK_EQ(rd.f[4].id, ext_same.id);
}

static void test_idle_bus_starts_when_ready(void)
{
    co_sim_bus_t *bus = new_bus(125000);
    static rec_t rb;
    memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_frame_t f = frm(0x701, "05");
    co_sim_run_until(bus, 500);
    co_sim_send(&a, &f);
    co_sim_run_until(bus, 100000);
    CHECK_EQ(rb.n, 1);
    CHECK_EQ(rb.t[0], 500 + co_sim_frame_bits(&f) * 8u);
    CHECK_EQ(bus->stats.busy_us, co_sim_frame_bits(&f) * 8u);
    /* Load: busy time over elapsed time. */
    double want = (double)(co_sim_frame_bits(&f) * 8u) / 100000.0;
    CHECK(co_sim_load(bus) > want - 1e-12 && co_sim_load(bus) < want + 1e-12);
}

static void test_fractional_bit_time_no_drift(void)
{
    /* 800 kbit/s: 1.25 us a bit. 200 frames back to back; each arrives at its exact end
     * rounded up, with no rounding carried from frame to frame. */
    co_sim_bus_t *bus = new_bus(800000);
    static rec_t rb;
    memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    a.mailboxes = 200;
    uint64_t s = 7;
    static co_frame_t sent[200];
    for (int i = 0; i < 200; i++) {
        sent[i] = random_frame(&s);
        sent[i].id = (sent[i].flags & CO_FRAME_EXT) ? 0x1FFFFFFF : 0x7FF; /* keep send order */
        sent[i].flags &= (uint8_t)~CO_FRAME_RTR;
        CHECK_EQ(co_sim_send(&a, &sent[i]), CO_OK);
    }
    CHECK_EQ(co_sim_run_until(bus, 1000000), CO_OK);
    CHECK_EQ(rb.n, 200);
    /* Standard frames (lower arbitration key) go first, each group in send order. */
    uint64_t bits = 0;
    uint32_t k = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (int i = 0; i < 200; i++) {
            bool ext = (sent[i].flags & CO_FRAME_EXT) != 0;
            if (ext != (pass == 1)) {
                continue;
            }
            bits += co_sim_frame_bits(&sent[i]);
            CHECK_EQ(rb.f[k].id, sent[i].id);
            CHECK_EQ(rb.t[k], (bits * 5 + 3) / 4); /* ceil(bits * 1.25) */
            k++;
        }
    }
    CHECK_EQ(bus->stats.busy_us, bits * 5 / 4);
    CHECK_EQ(bus->stats.bits, bits);
}

/* ---- Faults. */

static void test_drop_nth(void)
{
    co_sim_bus_t *bus = new_bus(125000);
    static rec_t rb;
    memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_frame_t f1 = frm(0x101, "01"), f2 = frm(0x102, "02"), f3 = frm(0x103, "03");
    co_sim_drop_nth(bus, 2);
    co_sim_send(&a, &f1);
    co_sim_send(&a, &f2);
    co_sim_send(&a, &f3);
    CHECK_EQ(co_sim_run_until(bus, 100000), CO_OK);
    CHECK_EQ(rb.n, 2);
    CHECK_EQ(rb.f[0].id, 0x101);
    CHECK_EQ(rb.f[1].id, 0x103);
    /* The dropped frame still took its time on the wire. */
    uint32_t total = co_sim_frame_bits(&f1) + co_sim_frame_bits(&f2) + co_sim_frame_bits(&f3);
    CHECK_EQ(rb.t[1], total * 8u);
    CHECK_EQ(bus->stats.dropped, 1);
    CHECK_EQ(bus->stats.frames, 3);
    CHECK_EQ(a.in_flight, 0);

    /* Once only; and counting restarts when set again. */
    co_sim_send(&a, &f1);
    co_sim_send(&a, &f2);
    co_sim_run_until(bus, 200000);
    CHECK_EQ(rb.n, 4);
    co_sim_drop_nth(bus, 1);
    co_sim_send(&a, &f1);
    co_sim_send(&a, &f2);
    co_sim_run_until(bus, 300000);
    CHECK_EQ(rb.n, 5);
    CHECK_EQ(rb.f[4].id, 0x102);
    CHECK_EQ(bus->stats.dropped, 2);
}

/* 300 frames through a bus dropping with probability p: a bitmap of which arrived. */
static uint32_t run_drops(uint64_t seed, double p, uint8_t *arrived)
{
    co_sim_bus_t *bus = new_bus(0);
    static rec_t rb;
    memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_sim_seed(bus, seed);
    co_sim_drop_probability(bus, p);
    memset(arrived, 0, 300);
    for (int i = 0; i < 300; i++) {
        co_frame_t f = frm(0x100, "00 00");
        co_put_u16(f.data, (uint16_t)i);
        co_sim_send(&a, &f);
        co_sim_run_until(bus, bus->now_us + 1);
    }
    for (uint32_t i = 0; i < rb.n; i++) {
        arrived[co_get_u16(rb.f[i].data)] = 1;
    }
    CHECK_EQ(bus->stats.dropped + rb.n, 300);
    return rb.n;
}

static void test_drop_probability(void)
{
    static uint8_t x[300], y[300], z[300];
    uint32_t nx = run_drops(1234, 0.3, x);
    uint32_t ny = run_drops(1234, 0.3, y);
    uint32_t nz = run_drops(99, 0.3, z);
    CHECK_EQ(nx, ny);
    CHECK(memcmp(x, y, sizeof x) == 0); /* same seed: same frames lost */
    CHECK(memcmp(x, z, sizeof x) != 0); /* another seed: others */
    CHECK(nx > 150 && nx < 270);
    CHECK(nz > 150 && nz < 270);
    CHECK_EQ(run_drops(5, 0.0, x), 300);
    CHECK_EQ(run_drops(5, 1.0, x), 0);
}

static void test_corrupt(void)
{
    co_sim_bus_t *bus = new_bus(0);
    static rec_t rb;
    memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_sim_seed(bus, 1);
    co_sim_corrupt_probability(bus, 1.0);
    co_frame_t data = frm(0x200, "11 22 33 44 55 66 77 88");
    co_frame_t empty = frm(0x201, "");
    co_frame_t rtr = frm(0x202, "R4");
    for (int i = 0; i < 20; i++) {
        co_sim_send(&a, &data);
        co_sim_send(&a, &empty);
        co_sim_send(&a, &rtr);
        co_sim_run_until(bus, bus->now_us + 1);
    }
    CHECK_EQ(rb.n, 60);
    CHECK_EQ(bus->stats.corrupted, 20);
    uint32_t flipped_positions = 0;
    uint64_t seen = 0;
    for (uint32_t i = 0; i < rb.n; i++) {
        const co_frame_t *f = &rb.f[i];
        if (f->id != 0x200) {
            CHECK_EQ(f->len, f->id == 0x202 ? 4 : 0);
            continue;
        }
        CHECK_EQ(f->len, 8);
        uint32_t diff_bits = 0;
        for (int j = 0; j < 8; j++) {
            uint8_t d = (uint8_t)(f->data[j] ^ data.data[j]);
            for (int k = 0; k < 8; k++) {
                if (d & (1u << k)) {
                    diff_bits++;
                    if (!(seen & (1ull << (j * 8 + k)))) {
                        flipped_positions++;
                        seen |= 1ull << (j * 8 + k);
                    }
                }
            }
        }
        CHECK_EQ(diff_bits, 1);
    }
    CHECK(flipped_positions > 5); /* not the same bit every time */
}

static void test_delay(void)
{
    co_sim_bus_t *bus = new_bus(0);
    static rec_t rb;
    memset(&rb, 0, sizeof rb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_sim_delay(bus, 250);
    co_frame_t f = frm(0x181, "01");
    co_sim_send(&a, &f);
    co_sim_run_until(bus, 249);
    CHECK_EQ(rb.n, 0);
    co_sim_run_until(bus, 1000);
    CHECK_EQ(rb.n, 1);
    CHECK_EQ(rb.t[0], 250);

    /* In the timing model the frame starts late, then takes its time. */
    bus = new_bus(250000);
    memset(&rb, 0, sizeof rb);
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_sim_delay(bus, 250);
    co_sim_send(&a, &f);
    co_sim_run_until(bus, 10000);
    CHECK_EQ(rb.n, 1);
    CHECK_EQ(rb.t[0], 250 + co_sim_frame_bits(&f) * 4u);

    /* A frame not ready yet does not take part in arbitration, whatever its ID. */
    bus = new_bus(125000);
    memset(&rb, 0, sizeof rb);
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_sim_delay(bus, 1000);
    co_frame_t low = frm(0x700, "01 02 03 04 05 06 07 08"), high = frm(0x001, "");
    co_sim_send(&a, &low); /* ready at 1000 */
    co_sim_run_until(bus, 500);
    co_sim_send(&a, &high); /* ready at 1500, while `low` is on the wire */
    co_sim_run_until(bus, 10000);
    uint64_t low_end = 1000 + co_sim_frame_bits(&low) * 8u;
    CHECK(low_end > 1500);
    CHECK_EQ(rb.n, 2);
    CHECK_EQ(rb.f[0].id, 0x700);
    CHECK_EQ(rb.t[0], low_end);
    CHECK_EQ(rb.t[1], low_end + co_sim_frame_bits(&high) * 8u);
}

static void test_reply_after_fractional_end(void)
{
    /* At 800 kbit/s a frame may end between two microseconds. A reply sent when it is
     * delivered (the next whole microsecond) comes too late for the arbitration that began
     * at the exact end: the frame that was waiting goes first. */
    co_sim_bus_t *bus = new_bus(800000);
    static rec_t rb, rc;
    memset(&rb, 0, sizeof rb), memset(&rc, 0, sizeof rc);
    co_sim_port_t a, b, c;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_sim_port_attach_raw(bus, &c, rec_rx, &rc);
    co_frame_t first = frm(0x300, "01");
    co_frame_t waiting = frm(0x400, "02");
    uint32_t bits1 = co_sim_frame_bits(&first), bits2 = co_sim_frame_bits(&waiting);
    CHECK(bits1 % 4 != 0); /* ends between whole microseconds */
    rb.echo = &b; /* b repeats what it hears: its 0x300 would beat 0x400 if ready in time */
    co_sim_send(&a, &first);
    co_sim_send(&a, &waiting);
    co_sim_run_until(bus, 100000);
    CHECK_EQ(rc.n, 4);
    CHECK_EQ(rc.f[0].id, 0x300);
    CHECK_EQ(rc.t[0], (bits1 * 5u + 3) / 4);
    CHECK_EQ(rc.f[1].id, 0x400);
    CHECK_EQ(rc.t[1], ((bits1 + bits2) * 5u + 3) / 4);
    CHECK_EQ(rc.f[2].id, 0x300);
    CHECK_EQ(rc.t[2], ((bits1 + bits2 + bits1) * 5u + 3) / 4);
    CHECK_EQ(rc.f[3].id, 0x400);

    /* A frame ready at the whole microsecond before that end starts at the end, not
     * before: the bus is still busy. */
    bus = new_bus(800000);
    memset(&rc, 0, sizeof rc);
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &c, rec_rx, &rc);
    co_sim_send(&a, &first);
    co_sim_run_until(bus, bits1 * 5u / 4); /* floor of the end */
    co_sim_send(&a, &waiting);
    co_sim_run_until(bus, 100000);
    CHECK_EQ(rc.n, 2);
    CHECK_EQ(rc.t[1], ((bits1 + bits2) * 5u + 3) / 4);
}

static void test_bus_off(void)
{
    co_sim_bus_t *bus = new_bus(125000);
    static rec_t ra, rb, rc;
    memset(&ra, 0, sizeof ra), memset(&rb, 0, sizeof rb), memset(&rc, 0, sizeof rc);
    co_sim_port_t a, b, c;
    co_sim_port_attach_raw(bus, &a, rec_rx, &ra);
    co_sim_port_attach_raw(bus, &b, rec_rx, &rb);
    co_sim_port_attach_raw(bus, &c, rec_rx, &rc);
    co_frame_t fa = frm(0x1A, "AA"), fb = frm(0x1B, "BB");

    /* Frames waiting in a mailbox when the port goes bus-off are abandoned. */
    co_sim_send(&a, &fa);
    co_sim_send(&a, &fa);
    co_sim_set_bus_off(&a, true);
    CHECK_EQ(a.in_flight, 0);
    CHECK_EQ(bus->pending_count, 0);

    /* Bus-off: sends are taken and vanish, nothing is received. */
    for (int i = 0; i < 5; i++) {
        CHECK_EQ(co_sim_send(&a, &fa), CO_OK);
    }
    CHECK_EQ(co_sim_send(&b, &fb), CO_OK);
    co_sim_run_until(bus, 10000);
    CHECK_EQ(ra.n, 0);
    CHECK_EQ(rb.n, 0);
    CHECK_EQ(rc.n, 1);
    CHECK_EQ(rc.f[0].id, 0x1B);
    CHECK_EQ(bus->stats.frames, 1);

    /* Back on the bus. */
    co_sim_set_bus_off(&a, false);
    co_sim_send(&a, &fa);
    co_sim_send(&b, &fb);
    co_sim_run_until(bus, 20000);
    CHECK_EQ(ra.n, 1);
    CHECK_EQ(rb.n, 1);
    CHECK_EQ(rc.n, 3);
}

/* ---- Trace. */

static void test_format(void)
{
    char buf[96];
    co_frame_t f = frm(0x701, "05");
    CHECK_STR(co_sim_format(buf, sizeof buf, 1000, "sim0", &f), "(0.001000) sim0 701#05");
    f = frm(0x18FF1234, "01 02");
    CHECK_STR(co_sim_format(buf, sizeof buf, 1000, "sim0", &f), "(0.001000) sim0 18FF1234#0102");
    f = frm(0x00000001, "");
    f.flags = CO_FRAME_EXT;
    CHECK_STR(co_sim_format(buf, sizeof buf, 0, "can1", &f), "(0.000000) can1 00000001#");
    f = frm(0x701, "R0");
    CHECK_STR(co_sim_format(buf, sizeof buf, 12345678901ull, "sim0", &f),
              "(12345.678901) sim0 701#R");
    f = frm(0x701, "R1");
    CHECK_STR(co_sim_format(buf, sizeof buf, 2000000, "sim0", &f), "(2.000000) sim0 701#R1");
    f = frm(0x00A, "de ad be ef 00 01 ab cd");
    CHECK_STR(co_sim_format(buf, sizeof buf, 999999, "sim0", &f),
              "(0.999999) sim0 00A#DEADBEEF0001ABCD");
    /* A short buffer gets a terminated prefix. */
    char small[8];
    CHECK_STR(co_sim_format(small, sizeof small, 0, "sim0", &f), "(0.0000");
}

static void test_trace(void)
{
    co_sim_bus_t *bus = new_bus(0);
    static trace_buf_t tb;
    memset(&tb, 0, sizeof tb);
    co_sim_port_t a, b;
    co_sim_port_attach_raw(bus, &a, NULL, NULL);
    co_sim_port_attach_raw(bus, &b, NULL, NULL);
    co_sim_set_trace(bus, trace_rx, &tb);
    co_sim_run_until(bus, 1000);
    co_frame_t f1 = frm(0x701, "05"), f2 = frm(0x18FF1234, "01 02"), f3 = frm(0x701, "R0");
    co_frame_t f4 = frm(0x701, "R1");
    co_sim_send(&a, &f1);
    co_sim_send(&b, &f2);
    co_sim_run_until(bus, 2500);
    co_sim_drop_nth(bus, 1); /* dropped frames are not traced */
    co_sim_send(&a, &f1);
    co_sim_send(&a, &f3);
    co_sim_send(&a, &f4);
    co_sim_run_until(bus, 3000);
    CHECK_STR(tb.text, "(0.001000) sim0 701#05\n"
                       "(0.001000) sim0 18FF1234#0102\n"
                       "(0.002500) sim0 701#R\n"
                       "(0.002500) sim0 701#R1\n");
    co_sim_set_trace(bus, NULL, NULL);
    co_sim_send(&a, &f1);
    co_sim_run_until(bus, 4000);
    CHECK_EQ(tb.lines, 4);
}

/* ---- Real nodes on the bus. */

typedef struct sim_node {
    example_od_t od;
    co_node_t node;
    co_sim_port_t port;
} sim_node_t;

static void add_node(co_sim_bus_t *bus, sim_node_t *n, uint8_t id, uint16_t hb_ms)
{
    memset(n, 0, sizeof *n);
    CHECK_EQ(co_sim_port_attach(bus, &n->port), CO_OK);
    co_node_config_t cfg = {
        .node_id = id,
        .od = example_od_init(&n->od, hb_ms),
        .driver = co_sim_port_driver(&n->port),
    };
    CHECK_EQ(co_node_init(&n->node, &cfg), CO_OK);
    co_sim_port_bind(&n->port, &n->node);
    CHECK_EQ(co_node_start(&n->node, bus->now_us), CO_OK);
}

static void test_node_heartbeat(void)
{
    co_sim_bus_t *bus = new_bus(0);
    static trace_buf_t tb;
    static sim_node_t n;
    memset(&tb, 0, sizeof tb);
    co_sim_set_trace(bus, trace_rx, &tb);
    add_node(bus, &n, 5, 100);
    CHECK_EQ(co_sim_run_until(bus, 350000), CO_OK);
    CHECK_STR(tb.text, "(0.000000) sim0 705#00\n"
                       "(0.100000) sim0 705#7F\n"
                       "(0.200000) sim0 705#7F\n"
                       "(0.300000) sim0 705#7F\n");
    CHECK_EQ(bus->now_us, 350000);
}

static void test_node_heartbeat_timed(void)
{
    /* At 125 kbit/s each frame arrives when its last bit (and the IFS) has passed. */
    co_sim_bus_t *bus = new_bus(125000);
    static trace_buf_t tb;
    static sim_node_t n;
    memset(&tb, 0, sizeof tb);
    co_sim_set_trace(bus, trace_rx, &tb);
    add_node(bus, &n, 5, 100);
    CHECK_EQ(co_sim_run_until(bus, 250000), CO_OK);
    co_frame_t boot = frm(0x705, "00"), hb = frm(0x705, "7F");
    char want[256];
    uint32_t tb0 = co_sim_frame_bits(&boot) * 8u, th = co_sim_frame_bits(&hb) * 8u;
    snprintf(want, sizeof want,
             "(0.%06u) sim0 705#00\n(0.%06u) sim0 705#7F\n(0.%06u) sim0 705#7F\n", tb0, 100000 + th,
             200000 + th);
    CHECK_STR(tb.text, want);
    double load = co_sim_load(bus);
    double expect = (double)(tb0 + 2 * th) / 250000.0;
    CHECK(load > expect - 1e-9 && load < expect + 1e-9);
}

static void test_node_acceptance(void)
{
    co_sim_bus_t *bus = new_bus(0);
    static rec_t rr;
    static sim_node_t n;
    memset(&rr, 0, sizeof rr);
    co_sim_port_t raw;
    CHECK_EQ(co_sim_port_attach_raw(bus, &raw, rec_rx, &rr), CO_OK);
    add_node(bus, &n, 5, 0);
    co_sim_run_until(bus, 1000);
    CHECK_EQ(rr.n, 1); /* boot-up */
    CHECK_EQ(rr.f[0].id, 0x705);

    /* Not routed by the node: its controller filters it out. */
    co_frame_t other = frm(0x123, "01 02");
    co_sim_send(&raw, &other);
    co_sim_run_until(bus, 2000);
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, 0);

    /* NMT start for node 5 passes and takes effect at once. */
    co_frame_t start = frm(0x000, "01 05");
    co_sim_send(&raw, &start);
    co_sim_run_until(bus, 3000);
    CHECK_EQ(co_node_stats(&n.node)->rx_frames, 1);
    CHECK_EQ(co_nmt_state(&n.node), CO_NMT_OPERATIONAL);
}

static void test_node_set_by_application(void)
{
    /* The application changes the node between runs (new heartbeat period): the new
     * deadline is honoured. */
    co_sim_bus_t *bus = new_bus(0);
    static rec_t rr;
    static sim_node_t n;
    memset(&rr, 0, sizeof rr);
    co_sim_port_t raw;
    co_sim_port_attach_raw(bus, &raw, rec_rx, &rr);
    add_node(bus, &n, 9, 0);
    co_sim_run_until(bus, 1000);
    CHECK_EQ(rr.n, 1);
    CHECK_EQ(co_node_set_uint(&n.node, 0x1017, 0, 10), CO_ABORT_NONE);
    co_sim_run_until(bus, 35000);
    /* The run ended by telling the node the time (1000 us): the new period counts from
     * there. */
    CHECK_EQ(rr.n, 4);
    CHECK_EQ(rr.t[1], 11000);
    CHECK_EQ(rr.t[3], 31000);
}

static void test_node_mailbox_refill(void)
{
    /* One mailbox: the node queues what the port refuses and sends it when the slot frees,
     * lowest COB-ID first. */
    co_sim_bus_t *bus = new_bus(125000);
    static rec_t rr;
    static sim_node_t n;
    memset(&rr, 0, sizeof rr);
    co_sim_port_t raw;
    co_sim_port_attach_raw(bus, &raw, rec_rx, &rr);
    add_node(bus, &n, 3, 0);
    n.port.mailboxes = 1;
    co_sim_run_until(bus, 1000); /* boot-up gone */
    co_frame_t f1 = frm(0x183, "01"), f2 = frm(0x283, "02"), f3 = frm(0x203, "03");
    CHECK_EQ(co_node_send(&n.node, &f1), CO_OK);
    CHECK_EQ(co_node_send(&n.node, &f2), CO_OK);
    CHECK_EQ(co_node_send(&n.node, &f3), CO_OK);
    CHECK(co_node_stats(&n.node)->tx_queued >= 2);
    CHECK(bus->stats.refused >= 1);
    co_sim_run_until(bus, 100000);
    CHECK_EQ(rr.n, 4);
    CHECK_EQ(rr.f[1].id, 0x183);
    CHECK_EQ(rr.f[2].id, 0x203);
    CHECK_EQ(rr.f[3].id, 0x283);
    /* Back to back: each starts as the previous leaves the wire. */
    uint64_t t = 1000;
    for (int i = 1; i < 4; i++) {
        t += co_sim_frame_bits(&rr.f[i]) * 8u;
        CHECK_EQ(rr.t[i], t);
    }
}

static void test_two_nodes_heartbeat_consumer(void)
{
    co_sim_bus_t *bus = new_bus(250000);
    static sim_node_t p, c;
    add_node(bus, &p, 1, 50);
    add_node(bus, &c, 2, 0);
    /* Node 2 consumes node 1's heartbeat with 120 ms. */
    CHECK_EQ(co_node_set_uint(&c.node, 0x1016, 1, (1u << 16) | 120u), CO_ABORT_NONE);
    co_sim_run_until(bus, 300000);
    CHECK_EQ(co_hb_remote_state(&c.node, 1), CO_NMT_PRE_OPERATIONAL);
    CHECK(co_node_stats(&c.node)->rx_frames >= 5);
    CHECK_EQ(co_node_stats(&p.node)->rx_frames, 0); /* node 1 listens to none of it */
}

int main(void)
{
    RUN(test_crc_reference);
    RUN(test_frame_bits_known);
    RUN(test_frame_bits_match_reference);
    RUN(test_bus_init);
    RUN(test_run_moves_time);
    RUN(test_send_rejects_bad_frames);
    RUN(test_instant_order);
    RUN(test_instant_reply_same_instant);
    RUN(test_mailboxes);
    RUN(test_raw_port_sent);
    RUN(test_pending_overflow);
    RUN(test_storm_guard);
    RUN(test_arbitration_125k);
    RUN(test_arbitration_1m);
    RUN(test_arbitration_ext_std);
    RUN(test_idle_bus_starts_when_ready);
    RUN(test_fractional_bit_time_no_drift);
    RUN(test_drop_nth);
    RUN(test_drop_probability);
    RUN(test_corrupt);
    RUN(test_delay);
    RUN(test_reply_after_fractional_end);
    RUN(test_bus_off);
    RUN(test_format);
    RUN(test_trace);
    RUN(test_node_heartbeat);
    RUN(test_node_heartbeat_timed);
    RUN(test_node_acceptance);
    RUN(test_node_set_by_application);
    RUN(test_node_mailbox_refill);
    RUN(test_two_nodes_heartbeat_consumer);
    return check_summary();
}
