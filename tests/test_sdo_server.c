/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_sdo_server.c -- the SDO server (channel 0 of node 5: requests on 0x605,
 * responses on 0x585): expedited, segmented and block transfer in both
 * directions, every abort code it produces, time-outs, NMT gating.
 *
 * Responses are checked byte for byte as candump strings ("585#4300200078563412").
 * Two dictionaries serve: the example OD of the harness, and a small "rig" OD
 * built here for what the example lacks (a BOOLEAN, 3-byte values, a string larger
 * than the channel buffer, a RAM DOMAIN larger than it with a check hook, a check hook,
 * and DOMAINs whose hooks stream a
 * pseudo-random byte sequence of any length, to push large transfers through the
 * small channel buffer).
 */
#include "check.h"
#include "harness.h"

#define MS 1000ull
#define KIB 1024u

static char dump[8192];

/* ---- An independent CRC-16-CCITT (polynomial 0x1021, initial 0), bit by bit. */

static uint16_t crc_bitwise(uint16_t crc, const uint8_t *data, uint32_t len)
{
    for (uint32_t i = 0; i < len; i++) {
        crc ^= (uint16_t)(data[i] << 8);
        for (int bit = 0; bit < 8; bit++) {
            crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
        }
    }
    return crc;
}

/* ---- The byte sequence the streaming entries produce and expect. */

static uint8_t gen(uint32_t i)
{
    uint32_t x = i * 2654435761u;
    x ^= x >> 15;
    return (uint8_t)(x ^ (x >> 7) ^ i);
}

/* Byte i of a data set: `bytes` when given, else the generator. */
static uint8_t byte_at(const uint8_t *bytes, uint32_t i) { return bytes ? bytes[i] : gen(i); }

static uint16_t crc_of(const uint8_t *bytes, uint32_t len)
{
    uint16_t crc = 0;
    for (uint32_t i = 0; i < len; i++) {
        uint8_t b = byte_at(bytes, i);
        crc = crc_bitwise(crc, &b, 1);
    }
    return crc;
}

/* ---- The rig: a node with its own small dictionary. */

#define RIG_BOOL 0x2100    /* BOOLEAN rw */
#define RIG_ABC 0x2101     /* VISIBLE_STRING, capacity 3, "abc" */
#define RIG_U24 0x2102     /* UNSIGNED24 rw */
#define RIG_BIG 0x2103     /* VISIBLE_STRING, capacity 1000 (> CO_SDO_BUF_SIZE), no hooks */
#define RIG_STREAM 0x2104  /* DOMAIN rw, no storage: read and write hooks stream gen() */
#define RIG_UNSIZED 0x2105 /* DOMAIN ro, read hook with size CO_OD_SIZE_UNKNOWN */
#define RIG_CHECKED 0x2106 /* UNSIGNED32 rw with a check hook */
#define RIG_UNICODE 0x2107 /* UNICODE_STRING, capacity 8 */
#define RIG_BLOB 0x2108    /* DOMAIN in RAM, capacity 2000 (> CO_SDO_BUF_SIZE), check hook */
#define RIG_BIG_CAP 1000u
#define RIG_BLOB_CAP 2000u
#define RIG_ENTRIES 9

typedef struct rig {
    fake_bus_t bus;
    co_node_t node;
    co_node_config_t cfg;
    co_od_entry_t entries[RIG_ENTRIES];
    uint8_t flag;
    char abc[3];
    uint32_t u24;
    char big[RIG_BIG_CAP];
    uint32_t checked;
    uint8_t unicode[8];
    uint8_t blob_bytes[RIG_BLOB_CAP];
    co_od_domain_t blob;
    /* read hooks */
    uint32_t up_len;       /* bytes of gen() the read hooks produce */
    co_abort_t read_abort; /* returned by the read hooks when not 0 */
    uint32_t max_read_cap; /* largest piece asked for */
    /* write hook */
    co_abort_t write_abort; /* returned by the write hook when not 0 */
    uint32_t taken;         /* bytes the write hook took */
    uint32_t pieces;
    uint32_t max_piece;
    uint32_t total;      /* `total` of the latest piece */
    uint32_t lasts;      /* pieces flagged last */
    uint32_t mismatches; /* bytes or offsets that differ from gen() */
    /* check hook */
    co_abort_t check_abort;
    uint32_t checks;
} rig_t;

static co_abort_t rig_read(void *ctx, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                           uint32_t cap, uint32_t *n, uint32_t *total)
{
    rig_t *r = ctx;
    if (cap > r->max_read_cap) {
        r->max_read_cap = cap;
    }
    if (r->read_abort != CO_ABORT_NONE) {
        return r->read_abort;
    }
    uint32_t left = offset < r->up_len ? r->up_len - offset : 0;
    uint32_t k = left < cap ? left : cap;
    for (uint32_t i = 0; i < k; i++) {
        buf[i] = gen(offset + i);
    }
    *n = k;
    *total = entry->index == RIG_UNSIZED ? CO_OD_SIZE_UNKNOWN : r->up_len;
    return CO_ABORT_NONE;
}

static co_abort_t rig_write(void *ctx, const co_od_entry_t *entry, uint32_t offset,
                            const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    (void)entry;
    rig_t *r = ctx;
    if (r->write_abort != CO_ABORT_NONE) {
        return r->write_abort;
    }
    if (offset != r->taken) {
        r->mismatches++;
    }
    for (uint32_t i = 0; i < n; i++) {
        r->mismatches += data[i] != gen(offset + i);
    }
    r->taken += n;
    r->pieces++;
    if (n > r->max_piece) {
        r->max_piece = n;
    }
    r->total = total;
    r->lasts += last;
    return CO_ABORT_NONE;
}

static co_abort_t rig_check(void *ctx, const co_od_entry_t *entry, const uint8_t *data,
                            uint32_t len)
{
    (void)entry;
    (void)data;
    (void)len;
    rig_t *r = ctx;
    r->checks++;
    return r->check_abort;
}

static const co_od_hooks_t k_stream_hooks = {.read = rig_read, .write = rig_write};
static const co_od_hooks_t k_read_hooks = {.read = rig_read};
static const co_od_hooks_t k_check_hooks = {.check = rig_check};

/* What the write hook saw, forgotten between transfers. */
static void rig_forget(rig_t *r)
{
    r->taken = 0;
    r->pieces = 0;
    r->max_piece = 0;
    r->total = 0;
    r->lasts = 0;
    r->mismatches = 0;
    r->max_read_cap = 0;
}

/* ---- The server under test, with the time of the next request. */

typedef struct srv {
    co_node_t *node;
    fake_bus_t *bus;
    uint64_t now;
} srv_t;

/* Node 5 on the example OD, pre-operational, bus cleared. */
static srv_t example_srv(test_node_t *t)
{
    test_node_init(t, 5, 0);
    co_node_start(&t->node, 0);
    fake_clear(&t->bus);
    return (srv_t){&t->node, &t->bus, 0};
}

/* Node 5 on the rig OD (time-out `timeout_ms`, 0 = default), pre-operational. */
static srv_t rig_srv(rig_t *r, uint16_t timeout_ms)
{
    memset(r, 0, sizeof *r);
    memcpy(r->abc, "abc", 3);
    uint32_t n = 0;
    r->entries[n++] = (co_od_entry_t){
        .index = RIG_BOOL, .type = CO_TYPE_BOOLEAN, .attr = CO_OD_RW, .size = 1, .value = &r->flag};
    r->entries[n++] = (co_od_entry_t){.index = RIG_ABC,
                                      .type = CO_TYPE_VISIBLE_STRING,
                                      .attr = CO_OD_RW,
                                      .size = 3,
                                      .value = r->abc};
    r->entries[n++] = (co_od_entry_t){.index = RIG_U24,
                                      .type = CO_TYPE_UNSIGNED24,
                                      .attr = CO_OD_RW,
                                      .size = 3,
                                      .value = &r->u24};
    r->entries[n++] = (co_od_entry_t){.index = RIG_BIG,
                                      .type = CO_TYPE_VISIBLE_STRING,
                                      .attr = CO_OD_RW,
                                      .size = RIG_BIG_CAP,
                                      .value = r->big};
    r->entries[n++] = (co_od_entry_t){.index = RIG_STREAM,
                                      .type = CO_TYPE_DOMAIN,
                                      .attr = CO_OD_RW,
                                      .size = 0x7FFFFFFFu,
                                      .hooks = &k_stream_hooks};
    r->entries[n++] = (co_od_entry_t){.index = RIG_UNSIZED,
                                      .type = CO_TYPE_DOMAIN,
                                      .attr = CO_OD_RO,
                                      .size = 0x7FFFFFFFu,
                                      .hooks = &k_read_hooks};
    r->entries[n++] = (co_od_entry_t){.index = RIG_CHECKED,
                                      .type = CO_TYPE_UNSIGNED32,
                                      .attr = CO_OD_RW,
                                      .size = 4,
                                      .value = &r->checked,
                                      .hooks = &k_check_hooks};
    r->entries[n++] = (co_od_entry_t){.index = RIG_UNICODE,
                                      .type = CO_TYPE_UNICODE_STRING,
                                      .attr = CO_OD_RW,
                                      .size = 8,
                                      .value = r->unicode};
    r->blob = (co_od_domain_t){.data = r->blob_bytes};
    r->entries[n++] = (co_od_entry_t){.index = RIG_BLOB,
                                      .type = CO_TYPE_DOMAIN,
                                      .attr = CO_OD_RW,
                                      .size = RIG_BLOB_CAP,
                                      .value = &r->blob,
                                      .hooks = &k_check_hooks};
    r->cfg.node_id = 5;
    r->cfg.od = (co_od_t){.entries = r->entries, .count = n, .hook_ctx = r};
    r->cfg.driver = fake_driver(&r->bus);
    r->cfg.sdo_timeout_ms = timeout_ms;
    CHECK_EQ(co_node_init(&r->node, &r->cfg), CO_OK);
    CHECK_EQ(co_node_start(&r->node, 0), CO_OK);
    fake_clear(&r->bus);
    return (srv_t){&r->node, &r->bus, 0};
}

/* ---- Requests and responses. */

/* A request from hex bytes ("40 00 20 00 00 00 00 00") at s->now. */
static void req(srv_t *s, const char *hex)
{
    co_frame_t f = frm(0x605, hex);
    co_node_ingest(s->node, s->now, &f);
}

/* A request from 8 bytes. */
static void req_data(srv_t *s, const uint8_t d[8])
{
    co_frame_t f = {.id = 0x605, .len = 8};
    memcpy(f.data, d, 8);
    co_node_ingest(s->node, s->now, &f);
}

/* An NMT command to the node at s->now. */
static void nmt(srv_t *s, const char *hex)
{
    co_frame_t f = frm(0x000, hex);
    co_node_ingest(s->node, s->now, &f);
}

/* What the node sent since the last look ("" for nothing); clears the record. */
static const char *sent(srv_t *s)
{
    fake_dump(s->bus, dump, sizeof dump);
    fake_clear(s->bus);
    return dump;
}

#define EXPECT(s, want) CHECK_STR(sent(s), want)
#define XFER(s, request, want)                                                                     \
    do {                                                                                           \
        req(s, request);                                                                           \
        EXPECT(s, want);                                                                           \
    } while (0)

/* True when exactly one frame went out, on 0x585, 8 bytes long, holding `want`; clears. */
static bool got(srv_t *s, const uint8_t want[8])
{
    bool ok = s->bus->count == 1 && s->bus->frames[0].id == 0x585 && s->bus->frames[0].len == 8 &&
              s->bus->frames[0].flags == 0 && memcmp(s->bus->frames[0].data, want, 8) == 0;
    fake_clear(s->bus);
    return ok;
}

/* A request with a multiplexer and a 32-bit tail. */
static void req_mux(srv_t *s, uint8_t cmd, uint16_t index, uint8_t sub, uint32_t tail)
{
    uint8_t d[8] = {cmd, (uint8_t)index, (uint8_t)(index >> 8), sub};
    co_put_u32(&d[4], tail);
    req_data(s, d);
}

/* True when the response is cmd + index + sub + tail. */
static bool got_mux(srv_t *s, uint8_t cmd, uint16_t index, uint8_t sub, uint32_t tail)
{
    uint8_t d[8] = {cmd, (uint8_t)index, (uint8_t)(index >> 8), sub};
    co_put_u32(&d[4], tail);
    return got(s, d);
}

/* ---- Clients written from the protocol, for transfers of many frames. Each returns the
 * number of frames that were not what CiA 301 says (0 = the whole transfer was right). */

/* Segmented download of `len` bytes (sized), every response checked. */
static uint32_t client_segmented_download(srv_t *s, uint16_t index, uint8_t sub,
                                          const uint8_t *bytes, uint32_t len)
{
    uint32_t bad = 0;
    req_mux(s, 0x21, index, sub, len);
    bad += !got_mux(s, 0x60, index, sub, 0);
    uint32_t off = 0;
    uint8_t toggle = 0;
    bool last = false;
    while (!last) {
        uint32_t n = len - off < 7 ? len - off : 7;
        last = off + n == len;
        uint8_t d[8] = {(uint8_t)((toggle << 4) | ((7 - n) << 1) | (last ? 1 : 0))};
        for (uint32_t i = 0; i < n; i++) {
            d[1 + i] = byte_at(bytes, off + i);
        }
        req_data(s, d);
        uint8_t want[8] = {(uint8_t)(0x20 | (toggle << 4))};
        bad += !got(s, want);
        off += n;
        toggle ^= 1;
    }
    return bad;
}

/* Segmented upload of a value of `len` bytes, size indicated, every segment checked. */
static uint32_t client_segmented_upload(srv_t *s, uint16_t index, uint8_t sub, const uint8_t *bytes,
                                        uint32_t len)
{
    uint32_t bad = 0;
    req_mux(s, 0x40, index, sub, 0);
    bad += !got_mux(s, 0x41, index, sub, len);
    uint32_t off = 0;
    uint8_t toggle = 0;
    bool last = false;
    while (!last) {
        uint8_t r[8] = {(uint8_t)(0x60 | (toggle << 4))};
        req_data(s, r);
        uint32_t n = len - off < 7 ? len - off : 7;
        last = off + n == len;
        uint8_t want[8] = {(uint8_t)((toggle << 4) | ((7 - n) << 1) | (last ? 1 : 0))};
        for (uint32_t i = 0; i < n; i++) {
            want[1 + i] = byte_at(bytes, off + i);
        }
        bad += !got(s, want);
        off += n;
        toggle ^= 1;
    }
    return bad;
}

/* Block download of `len` bytes in sub-blocks of the block size the server grants. */
static uint32_t client_block_download(srv_t *s, uint16_t index, uint8_t sub, const uint8_t *bytes,
                                      uint32_t len, bool crc)
{
    uint32_t bad = 0;
    req_mux(s, crc ? 0xC6 : 0xC2, index, sub, len);
    bad += !got_mux(s, 0xA4, index, sub, 127);
    uint32_t off = 0;
    uint32_t n = 0;
    bool last = false;
    while (!last) {
        uint8_t seq = 0;
        do {
            n = len - off < 7 ? len - off : 7;
            last = off + n == len;
            seq++;
            uint8_t d[8] = {(uint8_t)((last ? 0x80 : 0) | seq)};
            for (uint32_t i = 0; i < n; i++) {
                d[1 + i] = byte_at(bytes, off + i);
            }
            req_data(s, d);
            off += n;
            if (!last && seq < 127) {
                bad += s->bus->count != 0; /* no answer inside a sub-block */
                fake_clear(s->bus);
            }
        } while (!last && seq < 127);
        uint8_t ack[8] = {0xA2, seq, 127};
        bad += !got(s, ack);
    }
    uint16_t c = crc ? crc_of(bytes, len) : 0;
    uint8_t end[8] = {(uint8_t)(0xC1 | ((7 - n) << 2)), (uint8_t)c, (uint8_t)(c >> 8)};
    req_data(s, end);
    uint8_t done[8] = {0xA1};
    bad += !got(s, done);
    return bad;
}

/* Block upload of a value of `len` bytes (size indicated), asking for `blksize`, with or
 * without CRC support (without, the end must carry CRC 0). */
static uint32_t client_block_upload(srv_t *s, uint16_t index, uint8_t sub, uint8_t blksize,
                                    bool with_crc, const uint8_t *bytes, uint32_t len)
{
    uint32_t bad = 0;
    uint8_t init[8] = {
        with_crc ? 0xA4 : 0xA0, (uint8_t)index, (uint8_t)(index >> 8), sub, blksize, 0};
    req_data(s, init);
    bad += !got_mux(s, 0xC6, index, sub, len);
    uint8_t start[8] = {0xA3};
    req_data(s, start);
    uint32_t off = 0;
    uint32_t n = 0;
    uint16_t crc = 0;
    bool last = false;
    while (!last) {
        uint32_t count = s->bus->count;
        uint32_t left = len - off;
        uint32_t want_count = left == 0 ? 1 : (left + 6) / 7;
        if (want_count > blksize) {
            want_count = blksize;
        }
        bad += count != want_count;
        for (uint32_t k = 0; k < count && k < want_count; k++) {
            n = len - off < 7 ? len - off : 7;
            last = off + n == len;
            uint8_t want[8] = {(uint8_t)((last ? 0x80 : 0) | (k + 1))};
            for (uint32_t i = 0; i < n; i++) {
                want[1 + i] = byte_at(bytes, off + i);
                crc = crc_bitwise(crc, &want[1 + i], 1);
            }
            const co_frame_t *f = &s->bus->frames[k];
            bad += f->id != 0x585 || f->len != 8 || memcmp(f->data, want, 8) != 0;
            off += n;
        }
        fake_clear(s->bus);
        if (count != want_count) {
            return bad; /* lost step: stop here */
        }
        uint8_t ack[8] = {0xA2, (uint8_t)count, blksize};
        req_data(s, ack);
    }
    if (!with_crc) {
        crc = 0;
    }
    uint8_t end[8] = {(uint8_t)(0xC1 | ((7 - n) << 2)), (uint8_t)crc, (uint8_t)(crc >> 8)};
    bad += !got(s, end);
    uint8_t fin[8] = {0xA1};
    req_data(s, fin);
    bad += s->bus->count != 0;
    fake_clear(s->bus);
    return bad;
}

/* ======================================================================== helpers */

static void test_reference_crc_check_value(void)
{
    CHECK_EQ(crc_bitwise(0, (const uint8_t *)"123456789", 9), 0x31C3);
    CHECK_EQ(crc_bitwise(0, NULL, 0), 0);
    /* continued in pieces = in one go */
    uint16_t a = crc_bitwise(0, (const uint8_t *)"1234", 4);
    CHECK_EQ(crc_bitwise(a, (const uint8_t *)"56789", 5), 0x31C3);
}

static void test_response_format_is_candump(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    req(&s, "40 00 20 00 00 00 00 00");
    CHECK_EQ(t.bus.count, 1);
    char one[40];
    CHECK_STR(frame_str(&t.bus.frames[0], one, sizeof one), "585#4300200078563412");
}

/* ======================================================================== expedited */

static void test_expedited_upload_of_1_2_4_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    t.od.outputs[0] = 0xA5;
    t.od.app_i16 = -2;
    XFER(&s, "40 00 62 01 00 00 00 00", "585#4F006201A5000000");
    XFER(&s, "40 01 20 00 00 00 00 00", "585#4B012000FEFF0000");
    XFER(&s, "40 00 20 00 00 00 00 00", "585#4300200078563412");
    XFER(&s, "40 00 10 00 00 00 00 00", "585#4300100091010000");
    XFER(&s, "40 01 10 00 00 00 00 00", "585#4F01100000000000");
}

static void test_expedited_upload_of_3_bytes(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.u24 = 0xABCDEF;
    XFER(&s, "40 01 21 00 00 00 00 00", "585#4701210061626300");
    XFER(&s, "40 02 21 00 00 00 00 00", "585#47022100EFCDAB00");
}

static void test_expedited_upload_of_strings_up_to_4_chars(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    memcpy(t.od.app_string, "abcd\0", 5);
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4302200061626364");
    memcpy(t.od.app_string, "x\0", 2);
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4F02200078000000");
}

static void test_expedited_upload_through_read_hook(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.up_len = 2;
    char want[40];
    snprintf(want, sizeof want, "585#4B042100%02X%02X0000", gen(0), gen(1));
    XFER(&s, "40 04 21 00 00 00 00 00", want);
}

static void test_expedited_download_of_1_2_3_4_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "2F 00 62 01 7E 00 00 00", "585#6000620100000000");
    CHECK_EQ(t.od.outputs[0], 0x7E);
    XFER(&s, "2B 01 20 00 9C FF 00 00", "585#6001200000000000");
    CHECK_EQ(t.od.app_i16, -100);
    XFER(&s, "23 00 20 00 EF BE AD DE", "585#6000200000000000");
    CHECK_EQ(t.od.app_u32, 0xDEADBEEF);

    rig_t r;
    s = rig_srv(&r, 0);
    XFER(&s, "27 02 21 00 56 34 12 00", "585#6002210000000000");
    CHECK_EQ(r.u24, 0x123456);
    XFER(&s, "27 01 21 00 78 79 7A 00", "585#6001210000000000");
    CHECK(memcmp(r.abc, "xyz", 3) == 0);
    XFER(&s, "40 01 21 00 00 00 00 00", "585#4701210078797A00");
}

static void test_expedited_download_without_size_takes_entry_size(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "22 00 20 00 44 33 22 11", "585#6000200000000000");
    CHECK_EQ(t.od.app_u32, 0x11223344);
    XFER(&s, "22 01 20 00 32 00 FF FF", "585#6001200000000000"); /* bytes 6..7 are no data */
    CHECK_EQ(t.od.app_i16, 50);
    XFER(&s, "22 00 62 02 09 AA AA AA", "585#6000620200000000");
    CHECK_EQ(t.od.outputs[1], 9);

    rig_t r;
    s = rig_srv(&r, 0);
    XFER(&s, "22 02 21 00 01 02 03 EE", "585#6002210000000000");
    CHECK_EQ(r.u24, 0x030201);
}

static void test_expedited_download_length_mismatch(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "2B 00 20 00 01 02 00 00", "585#8000200013000706"); /* 2 bytes to a u32 */
    XFER(&s, "2F 00 20 00 01 00 00 00", "585#8000200013000706"); /* 1 byte to a u32 */
    XFER(&s, "23 01 20 00 01 00 00 00", "585#8001200012000706"); /* 4 bytes to an i16 */
    XFER(&s, "2F 01 20 00 01 00 00 00", "585#8001200013000706"); /* 1 byte to an i16 */
    XFER(&s, "22 05 20 00 01 00 00 00", "585#8005200013000706"); /* 4 bytes to an i64 */
    XFER(&s, "2B 00 62 01 01 00 00 00", "585#8000620112000706"); /* 2 bytes to a u8 */
    CHECK_EQ(t.od.app_u32, 0x12345678);
    CHECK_EQ(t.od.app_i16, 0);
    CHECK_EQ(t.od.outputs[0], 0);
}

static void test_expedited_download_to_streaming_domain(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    uint8_t d[8] = {0x27, 0x04, 0x21, 0x00, gen(0), gen(1), gen(2), 0xEE};
    req_data(&s, d);
    EXPECT(&s, "585#6004210000000000");
    CHECK_EQ(r.taken, 3);
    CHECK_EQ(r.pieces, 1);
    CHECK_EQ(r.total, 3);
    CHECK_EQ(r.lasts, 1);
    CHECK_EQ(r.mismatches, 0);
}

/* ======================================================================== segmented upload */

static void test_segmented_upload_of_5_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0568656C6C6F0000"); /* n=2, c=1 */
    /* the transfer is over: another segment request is out of place */
    XFER(&s, "70 00 00 00 00 00 00 00", "585#8000000001000405");
}

static void test_segmented_upload_of_14_bytes_toggles(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "40 08 10 00 00 00 00 00", "585#410810000E000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0063616E6F6C6120"); /* "canola " */
    XFER(&s, "70 00 00 00 00 00 00 00", "585#116578616D706C65"); /* "example", t=1, c=1 */
}

static void test_segmented_upload_last_segment_with_0_to_6_unused_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    static const char text[] = "0123456789ABCDEF";
    /* 7 bytes: one full segment; 8..14: a second one with 6..0 unused bytes (15, 16: 3 segments) */
    memcpy(t.od.app_string, "abcdefg", 8);
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200007000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0161626364656667");
    memcpy(t.od.app_string, "abcdefgh", 9);
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200008000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0061626364656667");
    XFER(&s, "70 00 00 00 00 00 00 00", "585#1D68000000000000"); /* n=6 */
    for (uint32_t len = 8; len <= 16; len++) {
        memset(t.od.app_string, 0, sizeof t.od.app_string);
        memcpy(t.od.app_string, text, len);
        CHECK_EQ(client_segmented_upload(&s, 0x2002, 0, (const uint8_t *)text, len), 0);
    }
}

static void test_segmented_upload_of_empty_value(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    t.od.app_string[0] = '\0';
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200000000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0F00000000000000"); /* n=7, c=1 */
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8000000001000405");
}

static void test_segmented_upload_toggle_error(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "40 08 10 00 00 00 00 00", "585#410810000E000000");
    XFER(&s, "70 00 00 00 00 00 00 00", "585#8008100000000305"); /* first must be t=0 */
    XFER(&s, "40 08 10 00 00 00 00 00", "585#410810000E000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0063616E6F6C6120");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8008100000000305"); /* t=0 again */
    XFER(&s, "70 00 00 00 00 00 00 00", "585#8000000001000405"); /* and it is over */
}

static void test_upload_without_size_indicated(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    char want[40];
    /* 10 bytes of unknown size: 0x40, then a full segment and a short last one */
    r.up_len = 10;
    XFER(&s, "40 05 21 00 00 00 00 00", "585#4005210000000000");
    req(&s, "60 00 00 00 00 00 00 00");
    uint8_t seg1[8] = {0x00, gen(0), gen(1), gen(2), gen(3), gen(4), gen(5), gen(6)};
    CHECK(got(&s, seg1));
    req(&s, "70 00 00 00 00 00 00 00");
    uint8_t seg2[8] = {0x19, gen(7), gen(8), gen(9)}; /* t=1, n=4, c=1 */
    CHECK(got(&s, seg2));
    /* 14 bytes: two full segments say nothing about the end; an empty one does */
    r.up_len = 14;
    XFER(&s, "40 05 21 00 00 00 00 00", "585#4005210000000000");
    req(&s, "60 00 00 00 00 00 00 00");
    CHECK(got(&s, seg1));
    req(&s, "70 00 00 00 00 00 00 00");
    uint8_t seg2full[8] = {0x10, gen(7), gen(8), gen(9), gen(10), gen(11), gen(12), gen(13)};
    CHECK(got(&s, seg2full));
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0F00000000000000");
    /* 3 bytes of unknown size are not expedited either */
    r.up_len = 3;
    XFER(&s, "40 05 21 00 00 00 00 00", "585#4005210000000000");
    snprintf(want, sizeof want, "585#09%02X%02X%02X00000000", gen(0), gen(1), gen(2));
    XFER(&s, "60 00 00 00 00 00 00 00", want);
}

static void test_segmented_upload_streams_100k(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.up_len = 100 * KIB;
    CHECK_EQ(client_segmented_upload(&s, RIG_STREAM, 0, NULL, 100 * KIB), 0);
    CHECK(r.max_read_cap <= 7); /* read piece by piece */
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8000000001000405");
}

/* ======================================================================== segmented download */

static void test_segmented_download_of_8_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "21 05 20 00 08 00 00 00", "585#6005200000000000");
    XFER(&s, "00 08 07 06 05 04 03 02", "585#2000000000000000");
    CHECK_EQ(t.od.app_i64, 0);                                   /* stored only at the end */
    XFER(&s, "1D 01 00 00 00 00 00 00", "585#3000000000000000"); /* t=1, n=6, c=1 */
    CHECK_EQ(t.od.app_i64, 0x0102030405060708);
    XFER(&s, "00 00 00 00 00 00 00 00", "585#8000000001000405"); /* over */
}

static void test_segmented_download_last_segment_with_0_to_6_unused_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    static const char text[] = "ZYXWVUTSRQPONMLK";
    /* 7 bytes: one segment, c=1, n=0 */
    XFER(&s, "21 02 20 00 07 00 00 00", "585#6002200000000000");
    XFER(&s, "01 61 62 63 64 65 66 67", "585#2000000000000000");
    CHECK_STR(t.od.app_string, "abcdefg");
    for (uint32_t len = 8; len <= 14; len++) {
        CHECK_EQ(client_segmented_download(&s, 0x2002, 0, (const uint8_t *)text, len), 0);
        CHECK_EQ(strlen(t.od.app_string), len);
        CHECK(memcmp(t.od.app_string, text, len) == 0);
    }
    /* the full capacity, no terminator */
    CHECK_EQ(client_segmented_download(&s, 0x2002, 0, (const uint8_t *)text, 16), 0);
    CHECK(memcmp(t.od.app_string, text, 16) == 0);
}

static void test_segmented_download_of_zero_length(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "21 02 20 00 00 00 00 00", "585#6002200000000000");
    XFER(&s, "0F 00 00 00 00 00 00 00", "585#2000000000000000"); /* n=7, c=1 */
    CHECK_STR(t.od.app_string, "");
}

static void test_segmented_download_without_size_indicated(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "20 02 20 00 00 00 00 00", "585#6002200000000000");
    XFER(&s, "00 73 65 67 6D 65 6E 74", "585#2000000000000000");
    XFER(&s, "17 65 64 21 00 00 00 00", "585#3000000000000000"); /* n=3, c=1 */
    CHECK_STR(t.od.app_string, "segmented!");
    /* a fixed-size entry still checks the length it gets at the end */
    XFER(&s, "20 00 20 00 00 00 00 00", "585#6000200000000000");
    XFER(&s, "05 01 02 03 04 05 00 00", "585#8000200012000706"); /* 5 bytes, n=2 */
    CHECK_EQ(t.od.app_u32, 0x12345678);
}

static void test_segmented_download_keeps_old_value_when_aborted(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    /* client abort after one segment */
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    XFER(&s, "00 41 42 43 44 45 46 47", "585#2000000000000000");
    XFER(&s, "80 02 20 00 00 00 04 05", "");
    CHECK_STR(t.od.app_string, "hello");
    /* server abort (toggle) after one segment */
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    XFER(&s, "00 41 42 43 44 45 46 47", "585#2000000000000000");
    XFER(&s, "00 41 42 43 44 45 46 47", "585#8002200000000305");
    CHECK_STR(t.od.app_string, "hello");
    /* the upload still shows the old value */
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0568656C6C6F0000");
}

static void test_segmented_download_toggle_error(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    XFER(&s, "10 41 42 43 44 45 46 47", "585#8002200000000305"); /* first must be t=0 */
    XFER(&s, "10 41 42 43 44 45 46 47", "585#8000000001000405"); /* and it is over */
    CHECK_STR(t.od.app_string, "hello");
}

static void test_segmented_download_size_mismatch(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    /* at initiate: the indicated size against the type or the capacity */
    XFER(&s, "21 00 20 00 05 00 00 00", "585#8000200012000706");
    XFER(&s, "21 00 20 00 03 00 00 00", "585#8000200013000706");
    XFER(&s, "21 02 20 00 11 00 00 00", "585#8002200012000706");
    /* more data than indicated */
    XFER(&s, "21 02 20 00 05 00 00 00", "585#6002200000000000");
    XFER(&s, "01 41 42 43 44 45 46 47", "585#8002200012000706");
    /* less data than indicated */
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    XFER(&s, "00 41 42 43 44 45 46 47", "585#2000000000000000");
    XFER(&s, "1B 48 49 00 00 00 00 00", "585#8002200013000706"); /* 2 of 3 bytes */
    /* more than indicated in the last segment */
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    XFER(&s, "00 41 42 43 44 45 46 47", "585#2000000000000000");
    XFER(&s, "17 48 49 4A 4B 00 00 00", "585#8002200012000706"); /* 4 of 3 bytes */
    CHECK_STR(t.od.app_string, "hello");
}

/* A string in RAM larger than the channel buffer: the download is received into the
 * entry's own storage, up to its capacity (the buffer frames the transfer only). */
static void test_segmented_download_larger_than_buffer_without_write_hook(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    static uint8_t text[RIG_BIG_CAP];
    for (uint32_t i = 0; i < sizeof text; i++) {
        text[i] = (uint8_t)('a' + i % 26);
    }
    CHECK_EQ(CO_SDO_BUF_SIZE, 889);
    CHECK_EQ(client_segmented_download(&s, RIG_BIG, 0, text, CO_SDO_BUF_SIZE), 0);
    CHECK_EQ(strlen(r.big), CO_SDO_BUF_SIZE);
    CHECK(memcmp(r.big, text, CO_SDO_BUF_SIZE) == 0);
    /* 890 and 1000 bytes (the capacity) fit the entry, if not the buffer */
    CHECK_EQ(client_segmented_download(&s, RIG_BIG, 0, text, 890), 0);
    CHECK_EQ(strlen(r.big), 890);
    CHECK_EQ(client_segmented_download(&s, RIG_BIG, 0, text, RIG_BIG_CAP), 0);
    CHECK(memcmp(r.big, text, RIG_BIG_CAP) == 0);
    /* a shorter value after it ends in NUL as ever */
    CHECK_EQ(client_segmented_download(&s, RIG_BIG, 0, text + 1, 900), 0);
    CHECK_EQ(strlen(r.big), 900);
    CHECK(memcmp(r.big, text + 1, 900) == 0);
    XFER(&s, "21 03 21 00 E9 03 00 00", "585#8003210012000706"); /* 1001: too long */
    /* without size: refused when it ends longer than the entry */
    XFER(&s, "20 03 21 00 00 00 00 00", "585#6003210000000000");
    uint8_t toggle = 0;
    for (uint32_t seg = 0; seg < 142; seg++) { /* 994 bytes */
        uint8_t d[8] = {(uint8_t)(toggle << 4), 'x', 'x', 'x', 'x', 'x', 'x', 'x'};
        req_data(&s, d);
        uint8_t want[8] = {(uint8_t)(0x20 | (toggle << 4))};
        CHECK(got(&s, want));
        toggle ^= 1;
    }
    XFER(&s, "01 78 78 78 78 78 78 78", "585#8003210012000706"); /* 1001 */
}

/* Without an indicated size, a value one byte over the entry's capacity is refused as it is
 * with the size indicated, however the buffer is filled. */
static void test_segmented_download_without_size_one_byte_over_buffer(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    XFER(&s, "20 03 21 00 00 00 00 00", "585#6003210000000000");
    uint8_t toggle = 0;
    for (uint32_t seg = 0; seg < 127; seg++) {
        uint8_t d[8] = {(uint8_t)(toggle << 4), 'y', 'y', 'y', 'y', 'y', 'y', 'y'};
        req_data(&s, d);
        uint8_t want[8] = {(uint8_t)(0x20 | (toggle << 4))};
        CHECK(got(&s, want));
        toggle ^= 1;
    }
    XFER(&s, "1D 7A 00 00 00 00 00 00", "585#3000000000000000"); /* byte 890, the last */
    CHECK_EQ(strlen(r.big), 890);
    CHECK_EQ(r.big[889], 'z');
}

/* A RAM DOMAIN larger than the buffer, segmented and block: the whole value, its length,
 * its check hook asked once with all of it; a refused value keeps the old length. */
static void test_download_into_ram_domain_larger_than_buffer(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    static uint8_t bytes[RIG_BLOB_CAP];
    for (uint32_t i = 0; i < sizeof bytes; i++) {
        bytes[i] = gen(i + 7);
    }
    CHECK_EQ(client_segmented_download(&s, RIG_BLOB, 0, bytes, 1500), 0);
    CHECK_EQ(r.blob.len, 1500);
    CHECK(memcmp(r.blob_bytes, bytes, 1500) == 0);
    CHECK_EQ(r.checks, 1);
    CHECK_EQ(client_block_download(&s, RIG_BLOB, 0, bytes + 1, RIG_BLOB_CAP - 1, true), 0);
    CHECK_EQ(r.blob.len, RIG_BLOB_CAP - 1);
    CHECK(memcmp(r.blob_bytes, bytes + 1, RIG_BLOB_CAP - 1) == 0);
    CHECK_EQ(client_block_download(&s, RIG_BLOB, 0, bytes, RIG_BLOB_CAP, false), 0);
    CHECK_EQ(r.blob.len, RIG_BLOB_CAP);
    CHECK_EQ(r.checks, 3);
    XFER(&s, "C6 08 21 00 D1 07 00 00", "585#8008210012000706"); /* 2001 */
    XFER(&s, "21 08 21 00 D1 07 00 00", "585#8008210012000706");
    /* the application refuses the value: its abort code, the length stays */
    r.check_abort = CO_ABORT_VALUE;
    XFER(&s, "21 08 21 00 B0 04 00 00", "585#6008210000000000"); /* 1200 bytes */
    uint8_t toggle = 0;
    for (uint32_t seg = 0; seg < 171; seg++) {
        uint8_t d[8] = {(uint8_t)(toggle << 4), 1, 2, 3, 4, 5, 6, 7};
        req_data(&s, d);
        uint8_t want[8] = {(uint8_t)(0x20 | (toggle << 4))};
        CHECK(got(&s, want));
        toggle ^= 1;
    }
    XFER(&s, "19 01 02 03 00 00 00 00", "585#8008210030000906"); /* the last 3 bytes */
    CHECK_EQ(r.checks, 4);
    CHECK_EQ(r.blob.len, RIG_BLOB_CAP);
}

static void test_segmented_download_to_ram_domain(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    static uint8_t bytes[EXAMPLE_DOMAIN_CAP + 1];
    for (uint32_t i = 0; i < sizeof bytes; i++) {
        bytes[i] = (uint8_t)(0xF0 ^ i);
    }
    CHECK_EQ(client_segmented_download(&s, 0x2003, 0, bytes, EXAMPLE_DOMAIN_CAP), 0);
    CHECK_EQ(t.od.app_domain.len, EXAMPLE_DOMAIN_CAP);
    CHECK(memcmp(t.od.domain_buf, bytes, EXAMPLE_DOMAIN_CAP) == 0);
    CHECK_EQ(client_segmented_download(&s, 0x2003, 0, bytes, 9), 0);
    CHECK_EQ(t.od.app_domain.len, 9);
    CHECK_EQ(client_segmented_upload(&s, 0x2003, 0, bytes, 9), 0);
    XFER(&s, "21 03 20 00 41 00 00 00", "585#8003200012000706"); /* 65 bytes */
    CHECK_EQ(t.od.app_domain.len, 9);
}

static void test_segmented_download_streams_100k(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    CHECK_EQ(client_segmented_download(&s, RIG_STREAM, 0, NULL, 100 * KIB), 0);
    CHECK_EQ(r.taken, 100 * KIB);
    CHECK_EQ(r.mismatches, 0);
    CHECK_EQ(r.total, 100 * KIB);
    CHECK_EQ(r.lasts, 1);
    CHECK(r.pieces > 100);
    CHECK(r.max_piece <= CO_SDO_BUF_SIZE + 6);
}

static void test_segmented_download_streams_without_size(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    const uint32_t len = 5000;
    XFER(&s, "20 04 21 00 00 00 00 00", "585#6004210000000000");
    uint8_t toggle = 0;
    uint32_t bad = 0;
    for (uint32_t off = 0; off < len; off += 7) {
        uint32_t n = len - off < 7 ? len - off : 7;
        bool last = off + n == len;
        uint8_t d[8] = {(uint8_t)((toggle << 4) | ((7 - n) << 1) | last)};
        for (uint32_t i = 0; i < n; i++) {
            d[1 + i] = gen(off + i);
        }
        req_data(&s, d);
        uint8_t want[8] = {(uint8_t)(0x20 | (toggle << 4))};
        bad += !got(&s, want);
        toggle ^= 1;
    }
    CHECK_EQ(bad, 0);
    CHECK_EQ(r.taken, len);
    CHECK_EQ(r.mismatches, 0);
    CHECK_EQ(r.total, CO_OD_SIZE_UNKNOWN);
    CHECK_EQ(r.lasts, 1);
}

/* ======================================================================== block download */

static void test_block_download_of_4_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    uint8_t v[4] = {0x11, 0x22, 0x33, 0x44};
    uint16_t crc = crc_bitwise(0, v, 4);
    XFER(&s, "C6 00 20 00 04 00 00 00", "585#A40020007F000000");
    XFER(&s, "81 11 22 33 44 00 00 00", "585#A2017F0000000000");
    CHECK_EQ(t.od.app_u32, 0x12345678);
    uint8_t end[8] = {0xCD, (uint8_t)crc, (uint8_t)(crc >> 8)}; /* n=3 */
    req_data(&s, end);
    EXPECT(&s, "585#A100000000000000");
    CHECK_EQ(t.od.app_u32, 0x44332211);
}

static void test_block_download_last_segment_with_0_to_6_unused_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    static const char text[] = "block transfer!!";
    for (uint32_t len = 1; len <= 16; len++) {
        CHECK_EQ(client_block_download(&s, 0x2002, 0, (const uint8_t *)text, len, true), 0);
        CHECK_EQ(strlen(t.od.app_string), len);
        CHECK(memcmp(t.od.app_string, text, len) == 0);
    }
}

static void test_block_download_wrong_crc(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    uint16_t crc = crc_bitwise(0, (const uint8_t *)"world", 5);
    XFER(&s, "C6 02 20 00 05 00 00 00", "585#A40220007F000000");
    XFER(&s, "81 77 6F 72 6C 64 00 00", "585#A2017F0000000000");
    uint8_t end[8] = {0xC9, (uint8_t)(crc ^ 1), (uint8_t)(crc >> 8)};
    req_data(&s, end);
    EXPECT(&s, "585#8002200004000405");
    CHECK_STR(t.od.app_string, "hello");
    /* the right CRC passes */
    XFER(&s, "C6 02 20 00 05 00 00 00", "585#A40220007F000000");
    XFER(&s, "81 77 6F 72 6C 64 00 00", "585#A2017F0000000000");
    end[1] = (uint8_t)crc;
    req_data(&s, end);
    EXPECT(&s, "585#A100000000000000");
    CHECK_STR(t.od.app_string, "world");
}

static void test_block_download_without_crc(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "C2 02 20 00 05 00 00 00", "585#A40220007F000000"); /* cc=0 */
    XFER(&s, "81 77 6F 72 6C 64 00 00", "585#A2017F0000000000");
    XFER(&s, "C9 DE AD 00 00 00 00 00", "585#A100000000000000"); /* any CRC */
    CHECK_STR(t.od.app_string, "world");
    /* size not indicated either */
    XFER(&s, "C0 02 20 00 00 00 00 00", "585#A40220007F000000");
    XFER(&s, "81 61 62 00 00 00 00 00", "585#A2017F0000000000");
    XFER(&s, "D5 00 00 00 00 00 00 00", "585#A100000000000000"); /* n=5 */
    CHECK_STR(t.od.app_string, "ab");
}

static void test_block_download_sub_blocks_of_1_to_127_segments(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    for (uint32_t k = 1; k <= 127; k++) {
        uint32_t len = 7 * k - k % 7; /* k segments, the last with k % 7 unused bytes */
        rig_forget(&r);
        CHECK_EQ(client_block_download(&s, RIG_STREAM, 0, NULL, len, true), 0);
        CHECK_EQ(r.taken, len);
        CHECK_EQ(r.mismatches, 0);
        CHECK_EQ(r.lasts, 1);
    }
    /* a full sub-block then one segment */
    rig_forget(&r);
    CHECK_EQ(client_block_download(&s, RIG_STREAM, 0, NULL, 127 * 7 + 3, true), 0);
    CHECK_EQ(r.taken, 127 * 7 + 3);
    CHECK_EQ(r.mismatches, 0);
}

static void test_block_download_of_889_bytes_without_write_hook(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    static uint8_t text[CO_SDO_BUF_SIZE];
    for (uint32_t i = 0; i < sizeof text; i++) {
        text[i] = (uint8_t)('A' + i % 26);
    }
    CHECK_EQ(client_block_download(&s, RIG_BIG, 0, text, sizeof text, true), 0);
    CHECK_EQ(strlen(r.big), CO_SDO_BUF_SIZE);
    CHECK(memcmp(r.big, text, sizeof text) == 0);
    static uint8_t more[RIG_BIG_CAP]; /* past the buffer, up to the entry's capacity */
    for (uint32_t i = 0; i < sizeof more; i++) {
        more[i] = (uint8_t)('a' + i % 26);
    }
    CHECK_EQ(client_block_download(&s, RIG_BIG, 0, more, 890, true), 0);
    CHECK_EQ(strlen(r.big), 890);
    CHECK_EQ(client_block_download(&s, RIG_BIG, 0, more, sizeof more, true), 0);
    CHECK(memcmp(r.big, more, sizeof more) == 0);
    XFER(&s, "C6 03 21 00 E9 03 00 00", "585#8003210012000706"); /* 1001 */
}

static void test_block_download_lost_segment_is_repeated(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    const uint32_t len = 70; /* 10 segments */
    XFER(&s, "C6 04 21 00 46 00 00 00", "585#A40421007F000000");
    for (uint32_t seq = 1; seq <= 10; seq++) {
        if (seq == 3) {
            continue; /* lost on the bus */
        }
        uint8_t d[8] = {(uint8_t)((seq == 10 ? 0x80 : 0) | seq)};
        for (uint32_t i = 0; i < 7; i++) {
            d[1 + i] = gen((seq - 1) * 7 + i);
        }
        req_data(&s, d);
        if (seq < 10) {
            EXPECT(&s, "");
        }
    }
    EXPECT(&s, "585#A2027F0000000000"); /* 1 and 2 arrived in order */
    /* the client goes on with what followed segment 2, numbered from 1 */
    for (uint32_t seq = 1; seq <= 8; seq++) {
        uint8_t d[8] = {(uint8_t)((seq == 8 ? 0x80 : 0) | seq)};
        for (uint32_t i = 0; i < 7; i++) {
            d[1 + i] = gen((seq + 1) * 7 + i);
        }
        req_data(&s, d);
    }
    EXPECT(&s, "585#A2087F0000000000");
    uint16_t crc = crc_of(NULL, len);
    uint8_t end[8] = {0xC1, (uint8_t)crc, (uint8_t)(crc >> 8)};
    req_data(&s, end);
    EXPECT(&s, "585#A100000000000000");
    CHECK_EQ(r.taken, len);
    CHECK_EQ(r.mismatches, 0);
    CHECK_EQ(r.lasts, 1);
}

static void test_block_download_lost_first_segment_acks_0(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "C6 02 20 00 0A 00 00 00", "585#A40220007F000000");
    XFER(&s, "82 68 69 6A 00 00 00 00", "585#A2007F0000000000"); /* segment 1 never came */
    XFER(&s, "01 61 62 63 64 65 66 67", "");
    XFER(&s, "82 68 69 6A 00 00 00 00", "585#A2027F0000000000");
    uint16_t crc = crc_bitwise(0, (const uint8_t *)"abcdefghij", 10);
    uint8_t end[8] = {0xD1, (uint8_t)crc, (uint8_t)(crc >> 8)}; /* n=4 */
    req_data(&s, end);
    EXPECT(&s, "585#A100000000000000");
    CHECK_STR(t.od.app_string, "abcdefghij");
}

static void test_block_download_sequence_number_0(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "C6 02 20 00 0A 00 00 00", "585#A40220007F000000");
    XFER(&s, "01 61 62 63 64 65 66 67", "");
    XFER(&s, "00 68 69 6A 00 00 00 00", "585#8002200003000405");
    CHECK_STR(t.od.app_string, "hello");
    /* (a sequence number above the block size cannot be sent: the server grants 127) */
}

static void test_block_download_end_errors(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    uint16_t crc = crc_bitwise(0, (const uint8_t *)"world", 5);
    /* the end request must be 0xC1 | n << 2 */
    XFER(&s, "C6 02 20 00 05 00 00 00", "585#A40220007F000000");
    XFER(&s, "81 77 6F 72 6C 64 00 00", "585#A2017F0000000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8002200001000405");
    /* data shorter than indicated */
    XFER(&s, "C6 02 20 00 06 00 00 00", "585#A40220007F000000");
    XFER(&s, "81 77 6F 72 6C 64 00 00", "585#A2017F0000000000");
    uint8_t end[8] = {0xC9, (uint8_t)crc, (uint8_t)(crc >> 8)};
    req_data(&s, end);
    EXPECT(&s, "585#8002200013000706");
    /* data longer than indicated */
    XFER(&s, "C6 02 20 00 04 00 00 00", "585#A40220007F000000");
    XFER(&s, "81 77 6F 72 6C 64 00 00", "585#A2017F0000000000");
    req_data(&s, end);
    EXPECT(&s, "585#8002200012000706");
    CHECK_STR(t.od.app_string, "hello");
    /* size at initiate against the type */
    XFER(&s, "C6 00 20 00 05 00 00 00", "585#8000200012000706");
    XFER(&s, "C6 00 20 00 02 00 00 00", "585#8000200013000706");
}

/* An empty value: one segment carrying no data, end with n = 7 (the server itself ends an
 * empty block upload that way). */
static void test_block_download_of_empty_value(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "C6 02 20 00 00 00 00 00", "585#A40220007F000000");
    XFER(&s, "81 00 00 00 00 00 00 00", "585#A2017F0000000000");
    XFER(&s, "DD 00 00 00 00 00 00 00", "585#A100000000000000");
    CHECK_STR(t.od.app_string, "");
}

static void test_block_download_streams_1m(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    CHECK_EQ(client_block_download(&s, RIG_STREAM, 0, NULL, 1024 * KIB, true), 0);
    CHECK_EQ(r.taken, 1024 * KIB);
    CHECK_EQ(r.mismatches, 0);
    CHECK_EQ(r.total, 1024 * KIB);
    CHECK_EQ(r.lasts, 1);
    CHECK(r.max_piece <= CO_SDO_BUF_SIZE + 6);
}

static void test_block_download_streams_without_crc(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    CHECK_EQ(client_block_download(&s, RIG_STREAM, 0, NULL, 2000, false), 0);
    CHECK_EQ(r.taken, 2000);
    CHECK_EQ(r.mismatches, 0);
    CHECK_EQ(r.lasts, 1);
}

static void test_block_download_streams_with_wrong_crc(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    /* 2 sub-blocks, then an end with a CRC off by one bit */
    const uint32_t len = 2 * 127 * 7;
    req_mux(&s, 0xC6, RIG_STREAM, 0, len);
    CHECK(got_mux(&s, 0xA4, RIG_STREAM, 0, 127));
    for (uint32_t off = 0; off < len; off += 7) {
        uint32_t seq = (off / 7) % 127 + 1;
        uint8_t d[8] = {(uint8_t)((off + 7 == len ? 0x80 : 0) | seq)};
        for (uint32_t i = 0; i < 7; i++) {
            d[1 + i] = gen(off + i);
        }
        req_data(&s, d);
    }
    EXPECT(&s, "585#A27F7F0000000000 585#A27F7F0000000000");
    uint16_t crc = crc_of(NULL, len) ^ 0x0100;
    uint8_t end[8] = {0xC1, (uint8_t)crc, (uint8_t)(crc >> 8)};
    req_data(&s, end);
    EXPECT(&s, "585#8004210004000405");
    CHECK_EQ(r.lasts, 0); /* the hook never heard the end */
}

/* ======================================================================== block upload */

static void test_block_upload_of_5_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    uint16_t crc = crc_bitwise(0, (const uint8_t *)"hello", 5);
    XFER(&s, "A4 02 20 00 7F 00 00 00", "585#C602200005000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#8168656C6C6F0000");
    req(&s, "A2 01 7F 00 00 00 00 00");
    uint8_t end[8] = {0xC9, (uint8_t)crc, (uint8_t)(crc >> 8)}; /* n=2 */
    CHECK(got(&s, end));
    XFER(&s, "A1 00 00 00 00 00 00 00", "");
    XFER(&s, "A1 00 00 00 00 00 00 00", "585#8000000001000405"); /* over */
}

static void test_block_upload_last_segment_with_0_to_6_unused_bytes(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    static const char text[] = "0123456789abcdef";
    for (uint32_t len = 1; len <= 16; len++) {
        memset(t.od.app_string, 0, sizeof t.od.app_string);
        memcpy(t.od.app_string, text, len);
        CHECK_EQ(client_block_upload(&s, 0x2002, 0, 127, true, (const uint8_t *)text, len), 0);
    }
}

static void test_block_upload_sub_blocks_and_block_sizes(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    for (uint32_t k = 1; k <= 127; k++) {
        r.up_len = 7 * k - k % 7; /* one sub-block of k segments */
        CHECK_EQ(client_block_upload(&s, RIG_STREAM, 0, 127, true, NULL, r.up_len), 0);
    }
    r.up_len = 500;
    for (uint8_t blksize = 1; blksize <= 127; blksize++) {
        CHECK_EQ(client_block_upload(&s, RIG_STREAM, 0, blksize, true, NULL, r.up_len), 0);
    }
}

static void test_block_upload_block_size_changes_with_ack(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.up_len = 40; /* 6 segments */
    req(&s, "A4 04 21 00 02 00 00 00");
    CHECK(got_mux(&s, 0xC6, RIG_STREAM, 0, 40));
    req(&s, "A3 00 00 00 00 00 00 00");
    CHECK_EQ(s.bus->count, 2);
    fake_clear(s.bus);
    req(&s, "A2 02 03 00 00 00 00 00"); /* next sub-block of 3 */
    CHECK_EQ(s.bus->count, 3);
    CHECK_EQ(s.bus->frames[2].data[0], 0x03);
    fake_clear(s.bus);
    req(&s, "A2 03 05 00 00 00 00 00"); /* the rest: one segment of 5 bytes */
    uint8_t last[8] = {0x81, gen(35), gen(36), gen(37), gen(38), gen(39)};
    CHECK(got(&s, last));
    req(&s, "A2 01 05 00 00 00 00 00");
    uint16_t crc = crc_of(NULL, 40);
    uint8_t end[8] = {0xC9, (uint8_t)crc, (uint8_t)(crc >> 8)};
    CHECK(got(&s, end));
    XFER(&s, "A1 00 00 00 00 00 00 00", "");
}

static void test_block_upload_lost_segment_is_repeated(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.up_len = 40; /* 5 full segments and one of 5 bytes */
    req(&s, "A4 04 21 00 7F 00 00 00");
    CHECK(got_mux(&s, 0xC6, RIG_STREAM, 0, 40));
    req(&s, "A3 00 00 00 00 00 00 00");
    CHECK_EQ(s.bus->count, 6);
    CHECK_EQ(s.bus->frames[5].data[0], 0x86);
    fake_clear(s.bus);
    req(&s, "A2 03 7F 00 00 00 00 00"); /* segment 4 was lost */
    CHECK_EQ(s.bus->count, 3);
    uint32_t bad = 0;
    for (uint32_t k = 0; k < 3 && k < s.bus->count; k++) {
        uint8_t want[8] = {(uint8_t)((k == 2 ? 0x80 : 0) | (k + 1))};
        uint32_t n = k == 2 ? 5 : 7;
        for (uint32_t i = 0; i < n; i++) {
            want[1 + i] = gen(21 + 7 * k + i);
        }
        bad += memcmp(s.bus->frames[k].data, want, 8) != 0;
    }
    CHECK_EQ(bad, 0);
    fake_clear(s.bus);
    req(&s, "A2 00 7F 00 00 00 00 00"); /* none of them arrived */
    CHECK_EQ(s.bus->count, 3);
    CHECK_EQ(s.bus->frames[0].data[1], gen(21));
    fake_clear(s.bus);
    req(&s, "A2 03 7F 00 00 00 00 00");
    uint16_t crc = crc_of(NULL, 40);
    uint8_t end[8] = {0xC9, (uint8_t)crc, (uint8_t)(crc >> 8)};
    CHECK(got(&s, end));
    XFER(&s, "A1 00 00 00 00 00 00 00", "");
}

static void test_block_upload_lost_segment_in_early_sub_block(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.up_len = 200; /* 29 segments */
    req(&s, "A4 04 21 00 0A 00 00 00");
    CHECK(got_mux(&s, 0xC6, RIG_STREAM, 0, 200));
    req(&s, "A3 00 00 00 00 00 00 00");
    CHECK_EQ(s.bus->count, 10);
    fake_clear(s.bus);
    req(&s, "A2 04 0A 00 00 00 00 00"); /* 4 of 10: the next sub-block starts at byte 28 */
    uint32_t off = 28;
    uint32_t bad = 0;
    uint32_t rounds = 0;
    while (s.bus->count > 0 && s.bus->frames[0].data[0] < 0xC0 && rounds++ < 10) {
        uint32_t count = s.bus->count;
        for (uint32_t k = 0; k < count; k++) {
            const uint8_t *d = s.bus->frames[k].data;
            uint32_t n = 200 - off < 7 ? 200 - off : 7;
            bad += (d[0] & 0x7F) != k + 1;
            bad += ((d[0] & 0x80) != 0) != (off + n == 200);
            for (uint32_t i = 0; i < n; i++) {
                bad += d[1 + i] != gen(off + i);
            }
            off += n;
        }
        fake_clear(s.bus);
        uint8_t ack[8] = {0xA2, (uint8_t)count, 10};
        req_data(&s, ack);
    }
    CHECK_EQ(bad, 0);
    CHECK_EQ(off, 200);
    uint16_t crc = crc_of(NULL, 200);
    uint8_t end[8] = {0xCD, (uint8_t)crc, (uint8_t)(crc >> 8)}; /* 200 = 28 * 7 + 4: n=3 */
    CHECK(got(&s, end));
    XFER(&s, "A1 00 00 00 00 00 00 00", "");
}

static void test_block_upload_protocol_switch(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    /* size <= pst: a normal upload answers */
    XFER(&s, "A4 00 20 00 7F 04 00 00", "585#4300200078563412");
    XFER(&s, "A4 02 20 00 7F 05 00 00", "585#4102200005000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0568656C6C6F0000");
    XFER(&s, "A4 02 20 00 7F 10 00 00", "585#4102200005000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0568656C6C6F0000");
    /* size > pst, or pst 0: block upload */
    XFER(&s, "A4 02 20 00 7F 04 00 00", "585#C602200005000000");
    XFER(&s, "80 02 20 00 00 00 00 00", "");
    XFER(&s, "A4 00 20 00 7F 00 00 00", "585#C600200004000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#8178563412000000");
}

static void test_block_upload_invalid_block_size(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "A4 02 20 00 00 00 00 00", "585#8002200002000405");
    XFER(&s, "A4 02 20 00 80 00 00 00", "585#8002200002000405");
    XFER(&s, "A4 02 20 00 FF 00 00 00", "585#8002200002000405");
    /* and in the acknowledgement */
    t.od.device_name[0] = 'C';
    XFER(&s, "A4 08 10 00 01 00 00 00", "585#C60810000E000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#0143616E6F6C6120");
    XFER(&s, "A2 01 00 00 00 00 00 00", "585#8008100002000405");
    XFER(&s, "A4 08 10 00 01 00 00 00", "585#C60810000E000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#0143616E6F6C6120");
    XFER(&s, "A2 01 80 00 00 00 00 00", "585#8008100002000405");
}

static void test_block_upload_ackseq_beyond_sent(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "A4 08 10 00 7F 00 00 00", "585#C60810000E000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#0163616E6F6C6120 585#826578616D706C65");
    XFER(&s, "A2 03 7F 00 00 00 00 00", "585#8008100003000405");
}

static void test_block_upload_unexpected_commands(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    /* after the initiate the client must start with 0xA3 */
    XFER(&s, "A4 02 20 00 7F 00 00 00", "585#C602200005000000");
    XFER(&s, "A2 00 7F 00 00 00 00 00", "585#8002200001000405");
    /* after a sub-block the client must acknowledge */
    XFER(&s, "A4 02 20 00 7F 00 00 00", "585#C602200005000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#8168656C6C6F0000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#8002200001000405");
    /* after the end the client must answer 0xA1 */
    XFER(&s, "A4 02 20 00 7F 00 00 00", "585#C602200005000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#8168656C6C6F0000");
    req(&s, "A2 01 7F 00 00 00 00 00");
    CHECK_EQ(s.bus->count, 1);
    fake_clear(s.bus);
    XFER(&s, "A2 01 7F 00 00 00 00 00", "585#8002200001000405");
}

static void test_block_upload_of_empty_value(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    t.od.app_string[0] = '\0';
    XFER(&s, "A4 02 20 00 7F 00 00 00", "585#C602200000000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#8100000000000000");
    XFER(&s, "A2 01 7F 00 00 00 00 00", "585#DD00000000000000"); /* n=7, CRC of nothing */
    XFER(&s, "A1 00 00 00 00 00 00 00", "");
}

static void test_block_upload_without_size_indicated(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.up_len = 10;
    XFER(&s, "A4 05 21 00 7F 00 00 00", "585#C405210000000000");
    req(&s, "A3 00 00 00 00 00 00 00");
    CHECK_EQ(s.bus->count, 2);
    uint8_t seg2[8] = {0x82, gen(7), gen(8), gen(9)};
    CHECK(s.bus->count == 2 && memcmp(s.bus->frames[1].data, seg2, 8) == 0);
    fake_clear(s.bus);
    req(&s, "A2 02 7F 00 00 00 00 00");
    uint16_t crc = crc_of(NULL, 10);
    uint8_t end[8] = {0xD1, (uint8_t)crc, (uint8_t)(crc >> 8)}; /* n=4 */
    CHECK(got(&s, end));
    XFER(&s, "A1 00 00 00 00 00 00 00", "");
    /* pst cannot switch a transfer of unknown size */
    XFER(&s, "A4 05 21 00 7F 7F 00 00", "585#C405210000000000");
}

/* Without CRC support on the client (cc = 0) the end's CRC field must be 0 (CiA 301). */
static void test_block_upload_without_crc_sends_crc_0(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "A0 02 20 00 7F 00 00 00", "585#C602200005000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#8168656C6C6F0000");
    XFER(&s, "A2 01 7F 00 00 00 00 00", "585#C900000000000000");
    XFER(&s, "A1 00 00 00 00 00 00 00", "");
}

static void test_block_upload_without_crc_over_sub_blocks(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.up_len = 2000;
    CHECK_EQ(client_block_upload(&s, RIG_STREAM, 0, 127, false, NULL, r.up_len), 0);
    CHECK_EQ(client_block_upload(&s, RIG_STREAM, 0, 127, true, NULL, r.up_len), 0);
}

static void test_upload_of_value_larger_than_buffer(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    for (uint32_t i = 0; i < RIG_BIG_CAP; i++) {
        r.big[i] = (char)('a' + i % 26);
    }
    CHECK_EQ(client_segmented_upload(&s, RIG_BIG, 0, (const uint8_t *)r.big, RIG_BIG_CAP), 0);
    CHECK_EQ(client_block_upload(&s, RIG_BIG, 0, 127, true, (const uint8_t *)r.big, RIG_BIG_CAP),
             0);
}

static void test_block_upload_waits_for_busy_driver(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.up_len = 70;
    req(&s, "A4 04 21 00 7F 00 00 00");
    CHECK(got_mux(&s, 0xC6, RIG_STREAM, 0, 70));
    r.bus.busy = true;
    req(&s, "A3 00 00 00 00 00 00 00");
    CHECK_EQ(s.bus->count, 0);
    CHECK_EQ(s.node->txq_count, 1); /* one segment waits, the rest is not queued */
    s.now = 5 * MS;
    co_node_poll(s.node, s.now);
    CHECK_EQ(s.bus->count, 0);
    r.bus.busy = false;
    s.now = 6 * MS;
    co_node_poll(s.node, s.now);
    CHECK_EQ(s.bus->count, 10);
    uint32_t bad = 0;
    for (uint32_t k = 0; k < s.bus->count; k++) {
        bad += s.bus->frames[k].data[0] != (uint8_t)((k == 9 ? 0x80 : 0) | (k + 1));
        bad += s.bus->frames[k].data[1] != gen(7 * k);
    }
    CHECK_EQ(bad, 0);
    fake_clear(s.bus);
    req(&s, "A2 0A 7F 00 00 00 00 00");
    uint16_t crc = crc_of(NULL, 70);
    uint8_t end[8] = {0xC1, (uint8_t)crc, (uint8_t)(crc >> 8)};
    CHECK(got(&s, end));
}

static void test_block_upload_streams_1m(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.up_len = 1024 * KIB;
    CHECK_EQ(client_block_upload(&s, RIG_STREAM, 0, 127, true, NULL, r.up_len), 0);
    CHECK(r.max_read_cap <= CO_SDO_BUF_SIZE);
}

/* ======================================================================== abort codes */

static void test_abort_access_and_existence(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "40 04 20 00 00 00 00 00", "585#8004200001000106"); /* read write-only */
    XFER(&s, "A4 04 20 00 7F 00 00 00", "585#8004200001000106");
    XFER(&s, "23 00 10 00 01 02 03 04", "585#8000100002000106"); /* write read-only */
    XFER(&s, "21 00 10 00 04 00 00 00", "585#8000100002000106");
    XFER(&s, "C6 00 10 00 04 00 00 00", "585#8000100002000106");
    XFER(&s, "21 08 10 00 03 00 00 00", "585#8008100002000106"); /* write const */
    XFER(&s, "2F 00 62 00 03 00 00 00", "585#8000620002000106");
    XFER(&s, "40 00 30 00 00 00 00 00", "585#8000300000000206"); /* no object */
    XFER(&s, "23 00 30 00 01 02 03 04", "585#8000300000000206");
    XFER(&s, "40 00 10 01 00 00 00 00", "585#8000100111000906"); /* no sub-index */
    XFER(&s, "40 00 62 05 00 00 00 00", "585#8000620511000906");
    CHECK_EQ(t.od.device_type, 0x191);
}

static void test_abort_value_limits(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "2B 01 20 00 65 00 00 00", "585#8001200031000906"); /* 101 */
    XFER(&s, "2B 01 20 00 9B FF 00 00", "585#8001200032000906"); /* -101 */
    CHECK_EQ(t.od.app_i16, 0);
    XFER(&s, "2B 01 20 00 64 00 00 00", "585#6001200000000000"); /* 100 */
    CHECK_EQ(t.od.app_i16, 100);
    XFER(&s, "21 01 20 00 02 00 00 00", "585#6001200000000000"); /* segmented -101 */
    XFER(&s, "0B 9B FF 00 00 00 00 00", "585#8001200032000906");
    CHECK_EQ(t.od.app_i16, 100);
}

static void test_abort_invalid_boolean(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    XFER(&s, "2F 00 21 00 02 00 00 00", "585#8000210030000906");
    CHECK_EQ(r.flag, 0);
    XFER(&s, "2F 00 21 00 01 00 00 00", "585#6000210000000000");
    CHECK_EQ(r.flag, 1);
}

static void test_abort_odd_length_unicode_string(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    XFER(&s, "27 07 21 00 41 00 42 00", "585#8007210010000706"); /* 3 bytes: half a unit */
    XFER(&s, "2B 07 21 00 41 00 42 00", "585#6007210000000000");
    CHECK_EQ(r.unicode[0], 0x41);
}

static void test_abort_from_check_hook_passes_through(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.check_abort = CO_ABORT_NO_RESOURCE;
    XFER(&s, "23 06 21 00 01 00 00 00", "585#8006210023000A06");
    r.check_abort = CO_ABORT_DATA_STATE;
    XFER(&s, "21 06 21 00 04 00 00 00", "585#6006210000000000");
    XFER(&s, "07 01 00 00 00 00 00 00", "585#8006210022000008");
    CHECK_EQ(r.checked, 0);
    r.check_abort = CO_ABORT_NONE;
    XFER(&s, "23 06 21 00 01 00 00 00", "585#6006210000000000");
    CHECK_EQ(r.checked, 1);
    CHECK_EQ(r.checks, 3);
}

static void test_abort_from_read_and_write_hooks_passes_through(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    r.read_abort = CO_ABORT_NO_DATA;
    XFER(&s, "40 04 21 00 00 00 00 00", "585#8004210024000008");
    XFER(&s, "A4 04 21 00 7F 00 00 00", "585#8004210024000008");
    /* a read that fails in the middle of a segmented upload */
    r.read_abort = CO_ABORT_NONE;
    r.up_len = 20;
    XFER(&s, "40 04 21 00 00 00 00 00", "585#4104210014000000");
    r.read_abort = CO_ABORT_HARDWARE;
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8004210000000606");
    r.write_abort = CO_ABORT_DATA_STORE;
    XFER(&s, "2F 04 21 00 01 00 00 00", "585#8004210020000008");
    XFER(&s, "21 04 21 00 02 00 00 00", "585#6004210000000000");
    XFER(&s, "0B 01 02 00 00 00 00 00", "585#8004210020000008");
}

static void test_abort_unknown_command_in_idle(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "E0 00 20 00 00 00 00 00", "585#8000000001000405");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8000000001000405");
    XFER(&s, "00 00 00 00 00 00 00 00", "585#8000000001000405");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#8000000001000405");
    XFER(&s, "C1 00 00 00 00 00 00 00", "585#8000000001000405");
    /* the server is still fine */
    XFER(&s, "40 00 20 00 00 00 00 00", "585#4300200078563412");
}

static void test_abort_unexpected_command_in_transfer(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    /* an upload segment request during a download */
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8002200001000405");
    /* a download segment during an upload */
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    XFER(&s, "00 41 42 43 44 45 46 47", "585#8002200001000405");
    /* an unknown specifier during an upload */
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    XFER(&s, "E0 00 00 00 00 00 00 00", "585#8002200001000405");
    /* the transfers are over */
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8000000001000405");
    CHECK_STR(t.od.app_string, "hello");
}

/* ======================================================================== time-out */

static void test_timeout_exactly_after_last_frame(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    s.now = 10 * MS;
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    CHECK_EQ(co_node_poll(s.node, 1010 * MS - 1), 1010 * MS);
    EXPECT(&s, "");
    CHECK_EQ(co_node_poll(s.node, 1010 * MS), CO_TIME_NEVER);
    EXPECT(&s, "585#8002200000000405");
    s.now = 1020 * MS;
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8000000001000405"); /* over */
}

static void test_timeout_restarts_with_each_frame(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    s.now = 600 * MS;
    XFER(&s, "00 41 42 43 44 45 46 47", "585#2000000000000000");
    co_node_poll(s.node, 1000 * MS);
    co_node_poll(s.node, 1600 * MS - 1);
    EXPECT(&s, "");
    co_node_poll(s.node, 1600 * MS);
    EXPECT(&s, "585#8002200000000405");
    CHECK_STR(t.od.app_string, "hello");
}

/* Nothing just before `ms`, the abort `frame` at `ms`: the time-out's edge. */
static void expect_timeout_at(srv_t *s, uint32_t ms, const char *frame)
{
    co_node_poll(s->node, ms * MS - 1);
    EXPECT(s, "");
    co_node_poll(s->node, ms * MS);
    EXPECT(s, frame);
}

/* Issue 34: a segment that moves nothing (no data, more to come) is answered but does not
 * restart the time-out: a client sending only those holds the channel for one time-out,
 * then hears 0x05040000 (timed out: the transfer made no progress for the time-out). */
static void test_timeout_not_restarted_by_empty_segments(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    s.now = 300 * MS;
    XFER(&s, "00 41 42 43 44 45 46 47", "585#2000000000000000"); /* 7 bytes: progress */
    uint8_t toggle = 0x10;
    for (uint32_t ms = 400; ms < 1300; ms += 100) { /* empty segments (n = 7), answered */
        s.now = ms * MS;
        char hex[32];
        snprintf(hex, sizeof hex, "%02X 00 00 00 00 00 00 00", (unsigned)(toggle | 0x0E));
        char want[32];
        snprintf(want, sizeof want, "585#%02X00000000000000", (unsigned)(0x20 | toggle));
        XFER(&s, hex, want);
        toggle ^= 0x10;
        co_node_poll(s.node, s.now);
        EXPECT(&s, "");
    }
    /* one time-out after the last segment with data */
    expect_timeout_at(&s, 1300, "585#8002200000000405");
}

/* The same in block transfers: a segment repeated, out of order, or an acknowledgement of
 * nothing (the sub-block sent again) moves nothing. */
static void test_timeout_not_restarted_without_block_progress(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    XFER(&s, "C6 04 21 00 46 00 00 00", "585#A40421007F000000");
    s.now = 100 * MS;
    XFER(&s, "01 00 00 00 00 00 00 00", ""); /* in order: progress */
    for (uint32_t ms = 200; ms < 1100; ms += 100) {
        s.now = ms * MS;
        XFER(&s, "01 00 00 00 00 00 00 00", ""); /* the same again */
        XFER(&s, "05 00 00 00 00 00 00 00", ""); /* out of order */
    }
    expect_timeout_at(&s, 1100, "585#8004210000000405");
    /* block upload: acknowledgements of nothing resend the sub-block, without progress */
    r.up_len = 10;
    s.now = 2000 * MS;
    XFER(&s, "A4 04 21 00 7F 00 00 00", "585#C60421000A000000");
    s.now = 2100 * MS;
    req(&s, "A3 00 00 00 00 00 00 00");
    CHECK_EQ(s.bus->count, 2);
    for (uint32_t ms = 2200; ms < 3100; ms += 100) {
        fake_clear(s.bus);
        s.now = ms * MS;
        req(&s, "A2 00 7F 00 00 00 00 00");
        CHECK_EQ(s.bus->count, 2); /* sent again */
    }
    fake_clear(s.bus);
    expect_timeout_at(&s, 3100, "585#8004210000000405");
}

static void test_timeout_configured(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 250);
    r.up_len = 100;
    s.now = 1000 * MS;
    XFER(&s, "40 04 21 00 00 00 00 00", "585#4104210064000000");
    co_node_poll(s.node, 1250 * MS - 1);
    EXPECT(&s, "");
    co_node_poll(s.node, 1250 * MS);
    EXPECT(&s, "585#8004210000000405");
}

static void test_timeout_in_block_transfers(void)
{
    rig_t r;
    srv_t s = rig_srv(&r, 0);
    /* block download, inside a sub-block */
    XFER(&s, "C6 04 21 00 46 00 00 00", "585#A40421007F000000");
    s.now = 100 * MS;
    XFER(&s, "01 00 00 00 00 00 00 00", "");
    co_node_poll(s.node, 1100 * MS - 1);
    EXPECT(&s, "");
    co_node_poll(s.node, 1100 * MS);
    EXPECT(&s, "585#8004210000000405");
    /* block upload, waiting for the acknowledgement */
    r.up_len = 10;
    s.now = 2000 * MS;
    XFER(&s, "A4 04 21 00 7F 00 00 00", "585#C60421000A000000");
    s.now = 2500 * MS;
    req(&s, "A3 00 00 00 00 00 00 00");
    CHECK_EQ(s.bus->count, 2);
    fake_clear(s.bus);
    co_node_poll(s.node, 3500 * MS - 1);
    EXPECT(&s, "");
    co_node_poll(s.node, 3500 * MS);
    EXPECT(&s, "585#8004210000000405");
}

static void test_no_timeout_when_idle(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "40 00 20 00 00 00 00 00", "585#4300200078563412");
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0568656C6C6F0000");
    co_node_poll(s.node, 5000 * MS);
    EXPECT(&s, "");
}

/* ======================================================================== transfer control */

static void test_client_abort_ends_transfer_silently(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    XFER(&s, "80 02 20 00 00 00 04 05", "");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8000000001000405");
    /* in a block download sub-block too */
    XFER(&s, "C6 02 20 00 0A 00 00 00", "585#A40220007F000000");
    XFER(&s, "01 61 62 63 64 65 66 67", "");
    XFER(&s, "80 02 20 00 00 00 04 05", "");
    co_node_poll(s.node, 5000 * MS); /* no time-out follows */
    EXPECT(&s, "");
    CHECK_STR(t.od.app_string, "hello");
    /* and in idle it is ignored */
    XFER(&s, "80 00 20 00 00 00 00 08", "");
}

static void test_new_initiate_replaces_open_transfer(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    XFER(&s, "00 41 42 43 44 45 46 47", "585#2000000000000000");
    /* a new upload: served, no abort for the old download */
    XFER(&s, "40 00 20 00 00 00 00 00", "585#4300200078563412");
    XFER(&s, "10 48 49 4A 00 00 00 00", "585#8000000001000405");
    CHECK_STR(t.od.app_string, "hello");
    /* a new segmented download replaces a segmented upload */
    XFER(&s, "40 08 10 00 00 00 00 00", "585#410810000E000000");
    XFER(&s, "21 02 20 00 03 00 00 00", "585#6002200000000000");
    XFER(&s, "09 61 62 63 00 00 00 00", "585#2000000000000000");
    CHECK_STR(t.od.app_string, "abc");
    /* and a block upload waiting for its acknowledgement */
    XFER(&s, "A4 02 20 00 7F 00 00 00", "585#C602200003000000");
    XFER(&s, "A3 00 00 00 00 00 00 00", "585#8161626300000000");
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4702200061626300");
}

static void test_malformed_frames_are_ignored(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    uint32_t before = co_node_stats(s.node)->rx_malformed;
    XFER(&s, "40 00 20 00 00 00 00", "");
    XFER(&s, "40", "");
    XFER(&s, "", "");
    XFER(&s, "R8", "");
    CHECK_EQ(co_node_stats(s.node)->rx_malformed - before, 4);
    /* an open transfer goes on undisturbed */
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    XFER(&s, "60 00 00 00", "");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#0568656C6C6F0000");
    CHECK_EQ(co_node_stats(s.node)->rx_malformed - before, 5);
}

static void test_stopped_node_does_not_answer(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    nmt(&s, "02 05");
    CHECK_EQ(co_nmt_state(s.node), CO_NMT_STOPPED);
    uint32_t gated = co_node_stats(s.node)->rx_gated;
    XFER(&s, "40 00 20 00 00 00 00 00", "");
    XFER(&s, "23 00 20 00 01 00 00 00", "");
    XFER(&s, "E0 00 00 00 00 00 00 00", "");
    CHECK_EQ(co_node_stats(s.node)->rx_gated - gated, 3);
    CHECK_EQ(t.od.app_u32, 0x12345678);
    nmt(&s, "01 05");
    XFER(&s, "40 00 20 00 00 00 00 00", "585#4300200078563412");
    nmt(&s, "80 05");
    XFER(&s, "40 00 20 00 00 00 00 00", "585#4300200078563412");
}

static void test_stop_ends_open_transfer_without_abort(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    s.now = 10 * MS;
    nmt(&s, "02 05");
    co_node_poll(s.node, 1000 * MS); /* no abort may be sent in stopped */
    EXPECT(&s, "");
    s.now = 1100 * MS;
    nmt(&s, "01 05");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8000000001000405");
}

/* The same, with operational again before a poll ran: the transfer is over all the same. */
static void test_stop_ends_open_transfer_at_once(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "40 02 20 00 00 00 00 00", "585#4102200005000000");
    s.now = 10 * MS;
    nmt(&s, "02 05");
    co_node_poll(s.node, 20 * MS);
    s.now = 30 * MS;
    nmt(&s, "01 05");
    XFER(&s, "60 00 00 00 00 00 00 00", "585#8000000001000405");
}

static void test_reset_communication_ends_open_transfer(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    nmt(&s, "82 05");
    EXPECT(&s, "705#00");
    XFER(&s, "00 41 42 43 44 45 46 47", "585#8000000001000405");
    co_node_poll(s.node, 5000 * MS);
    EXPECT(&s, "");
}

static void test_operational_serves_like_pre_operational(void)
{
    test_node_t t;
    srv_t s = example_srv(&t);
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    nmt(&s, "01 05"); /* a state change that keeps SDO does not end the transfer */
    XFER(&s, "00 41 42 43 44 45 46 47", "585#2000000000000000");
    XFER(&s, "19 48 49 4A 00 00 00 00", "585#3000000000000000");
    XFER(&s, "21 02 20 00 0A 00 00 00", "585#6002200000000000");
    XFER(&s, "00 41 42 43 44 45 46 47", "585#2000000000000000");
    XFER(&s, "19 48 49 4A 00 00 00 00", "585#3000000000000000");
    CHECK_STR(t.od.app_string, "ABCDEFGHIJ");
}

/* ---- edges: the documented answers to inputs seldom seen */

static const char *last_frame(const test_node_t *t)
{
    static char buf[40];
    return t->bus.count ? frame_str(&t->bus.frames[t->bus.count - 1], buf, sizeof buf) : "";
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

/* ---- a read hook that hands out short pieces: od.h lets it copy "up to `cap` bytes" a call,
 * and sdo.h has uploads read the dictionary piece by piece, so read hooks stream too */

#define TRICKLE 0x2200 /* DOMAIN ro: byte i is 0x10 + i; the hook copies `piece` bytes a call */

typedef struct trickle {
    fake_bus_t bus;
    co_node_t node;
    co_od_entry_t entry;
    uint32_t len;
    uint32_t piece;
} trickle_t;

static co_abort_t trickle_read(void *ctx, const co_od_entry_t *entry, uint32_t offset, uint8_t *buf,
                               uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)entry;
    trickle_t *m = ctx;
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

/* Node 5 with the one entry TRICKLE, pre-operational, bus cleared. */
static void trickle_start(trickle_t *m, uint32_t len, uint32_t piece)
{
    memset(m, 0, sizeof *m);
    m->len = len;
    m->piece = piece;
    m->entry = (co_od_entry_t){.index = TRICKLE,
                               .type = CO_TYPE_DOMAIN,
                               .attr = CO_OD_RO,
                               .size = 0x10000u,
                               .hooks = &k_trickle_hooks};
    co_node_config_t cfg = {.node_id = 5, .driver = fake_driver(&m->bus)};
    cfg.od = (co_od_t){.entries = &m->entry, .count = 1, .hook_ctx = m};
    CHECK_EQ(co_node_init(&m->node, &cfg), CO_OK);
    CHECK_EQ(co_node_start(&m->node, 0), CO_OK);
    fake_clear(&m->bus);
}

static void trickle_request(trickle_t *m, uint64_t now, const char *hex)
{
    co_frame_t f = frm(0x605, hex);
    co_node_ingest(&m->node, now, &f);
    (void)co_node_poll(&m->node, now);
}

/* A 3-byte value whose hook gives one byte per call is still uploaded whole: 0x47 + 10 11 12,
 * not 10 00 00. */
static void test_expedited_upload_collects_every_piece_of_a_short_read_hook(void)
{
    trickle_t m;
    trickle_start(&m, 3, 1);
    trickle_request(&m, 0, "40 00 22 00 00 00 00 00");
    CHECK_STR(fake_dump(&m.bus, dump, sizeof dump), "585#4700220010111200");
}

/* A 20-byte value read 4 bytes per call, by block upload: after the client's start (0xA3)
 * the server sends the sub-block (CiA 301: segments 1..n, the last one flagged), and does
 * not fall silent until the transfer times out. */
static void test_block_upload_sends_segments_when_read_hook_gives_short_pieces(void)
{
    trickle_t m;
    trickle_start(&m, 20, 4);
    trickle_request(&m, 0, "A4 00 22 00 7F 00 00 00");
    CHECK_STR(fake_dump(&m.bus, dump, sizeof dump), "585#C600220014000000");
    fake_clear(&m.bus);
    trickle_request(&m, 1 * MS, "A3 00 00 00 00 00 00 00");
    CHECK_STR(fake_dump(&m.bus, dump, sizeof dump),
              "585#0110111213141516 585#021718191A1B1C1D 585#831E1F2021222300");
}

int main(void)
{
    /* helpers */
    RUN(test_reference_crc_check_value);
    RUN(test_response_format_is_candump);
    /* expedited */
    RUN(test_expedited_upload_of_1_2_4_bytes);
    RUN(test_expedited_upload_of_3_bytes);
    RUN(test_expedited_upload_of_strings_up_to_4_chars);
    RUN(test_expedited_upload_through_read_hook);
    RUN(test_expedited_download_of_1_2_3_4_bytes);
    RUN(test_expedited_download_without_size_takes_entry_size);
    RUN(test_expedited_download_length_mismatch);
    RUN(test_expedited_download_to_streaming_domain);
    /* segmented upload */
    RUN(test_segmented_upload_of_5_bytes);
    RUN(test_segmented_upload_of_14_bytes_toggles);
    RUN(test_segmented_upload_last_segment_with_0_to_6_unused_bytes);
    RUN(test_segmented_upload_of_empty_value);
    RUN(test_segmented_upload_toggle_error);
    RUN(test_upload_without_size_indicated);
    RUN(test_segmented_upload_streams_100k);
    /* segmented download */
    RUN(test_segmented_download_of_8_bytes);
    RUN(test_segmented_download_last_segment_with_0_to_6_unused_bytes);
    RUN(test_segmented_download_of_zero_length);
    RUN(test_segmented_download_without_size_indicated);
    RUN(test_segmented_download_keeps_old_value_when_aborted);
    RUN(test_segmented_download_toggle_error);
    RUN(test_segmented_download_size_mismatch);
    RUN(test_segmented_download_larger_than_buffer_without_write_hook);
    RUN(test_segmented_download_without_size_one_byte_over_buffer);
    RUN(test_segmented_download_to_ram_domain);
    RUN(test_download_into_ram_domain_larger_than_buffer);
    RUN(test_segmented_download_streams_100k);
    RUN(test_segmented_download_streams_without_size);
    /* block download */
    RUN(test_block_download_of_4_bytes);
    RUN(test_block_download_last_segment_with_0_to_6_unused_bytes);
    RUN(test_block_download_wrong_crc);
    RUN(test_block_download_without_crc);
    RUN(test_block_download_sub_blocks_of_1_to_127_segments);
    RUN(test_block_download_of_889_bytes_without_write_hook);
    RUN(test_block_download_lost_segment_is_repeated);
    RUN(test_block_download_lost_first_segment_acks_0);
    RUN(test_block_download_sequence_number_0);
    RUN(test_block_download_end_errors);
    RUN(test_block_download_of_empty_value);
    RUN(test_block_download_streams_1m);
    RUN(test_block_download_streams_without_crc);
    RUN(test_block_download_streams_with_wrong_crc);
    /* block upload */
    RUN(test_block_upload_of_5_bytes);
    RUN(test_block_upload_last_segment_with_0_to_6_unused_bytes);
    RUN(test_block_upload_sub_blocks_and_block_sizes);
    RUN(test_block_upload_block_size_changes_with_ack);
    RUN(test_block_upload_lost_segment_is_repeated);
    RUN(test_block_upload_lost_segment_in_early_sub_block);
    RUN(test_block_upload_protocol_switch);
    RUN(test_block_upload_invalid_block_size);
    RUN(test_block_upload_ackseq_beyond_sent);
    RUN(test_block_upload_unexpected_commands);
    RUN(test_block_upload_of_empty_value);
    RUN(test_block_upload_without_size_indicated);
    RUN(test_block_upload_without_crc_sends_crc_0);
    RUN(test_block_upload_without_crc_over_sub_blocks);
    RUN(test_upload_of_value_larger_than_buffer);
    RUN(test_block_upload_waits_for_busy_driver);
    RUN(test_block_upload_streams_1m);
    /* abort codes */
    RUN(test_abort_access_and_existence);
    RUN(test_abort_value_limits);
    RUN(test_abort_invalid_boolean);
    RUN(test_abort_odd_length_unicode_string);
    RUN(test_abort_from_check_hook_passes_through);
    RUN(test_abort_from_read_and_write_hooks_passes_through);
    RUN(test_abort_unknown_command_in_idle);
    RUN(test_abort_unexpected_command_in_transfer);
    /* time-out */
    RUN(test_timeout_exactly_after_last_frame);
    RUN(test_timeout_restarts_with_each_frame);
    RUN(test_timeout_not_restarted_by_empty_segments);
    RUN(test_timeout_not_restarted_without_block_progress);
    RUN(test_timeout_configured);
    RUN(test_timeout_in_block_transfers);
    RUN(test_no_timeout_when_idle);
    /* transfer control and NMT */
    RUN(test_client_abort_ends_transfer_silently);
    RUN(test_new_initiate_replaces_open_transfer);
    RUN(test_malformed_frames_are_ignored);
    RUN(test_stopped_node_does_not_answer);
    RUN(test_stop_ends_open_transfer_without_abort);
    RUN(test_stop_ends_open_transfer_at_once);
    RUN(test_reset_communication_ends_open_transfer);
    RUN(test_operational_serves_like_pre_operational);
    RUN(test_block_download_bad_sequence_number);
    RUN(test_block_download_of_an_empty_value);
    RUN(test_block_upload_bad_acknowledgements);
    RUN(test_expedited_download_without_size);
    RUN(test_unsized_download_beyond_the_buffer);
    RUN(test_unsized_block_download_beyond_the_buffer);
    RUN(test_expedited_without_size_to_wide_objects);
    /* Several server channels: CO_SDO_SERVERS_MAX is 1 in the default configuration, so
     * there is no second channel to test here. */
    RUN(test_expedited_upload_collects_every_piece_of_a_short_read_hook);
    RUN(test_block_upload_sends_segments_when_read_hook_gives_short_pieces);
    return check_summary();
}
