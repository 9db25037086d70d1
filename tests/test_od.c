/* SPDX-License-Identifier: Apache-2.0 */
/* test_od.c -- the object dictionary (src/od.c): look-up, wire forms, checks, hooks, reset. */
#include "check.h"
#include "example_od.h"

#include "canola/od.h"

/* A core without CO_CONFIG_OD_HASH neither uses the hash nor checks it: co_od_validate's
 * answer for a table whose hash alone is bad. */
#define BAD_HASH (CO_CONFIG_OD_HASH ? CO_ERR_CONFIG : CO_OK)

/* ---- Helpers. */

#define COUNT(a) ((uint32_t)(sizeof(a) / sizeof((a)[0])))

static co_od_t make_od(const co_od_entry_t *entries, uint32_t count, void *ctx)
{
    co_od_t od = {.entries = entries, .count = count, .hook_ctx = ctx};
    return od;
}

static co_od_entry_t var(uint16_t index, uint8_t sub, uint8_t type, uint8_t attr, uint32_t size,
                         void *value)
{
    co_od_entry_t e = {
        .index = index, .sub = sub, .type = type, .attr = attr, .size = size, .value = value};
    return e;
}

/* Read the whole value in one piece; returns the byte count (or 0xFFFFFFFF on an abort). */
static uint32_t read_all(const co_od_t *od, const co_od_entry_t *e, uint8_t *buf, uint32_t cap)
{
    uint32_t n = 0, total = 0;
    co_abort_t ab = co_od_read(od, e, 0, buf, cap, &n, &total);
    if (ab != CO_ABORT_NONE) {
        return 0xFFFFFFFFu;
    }
    CHECK_EQ(n, total);
    return n;
}

/* Write `wire` to a one-entry OD of `type`, check it reads back the same bytes. */
static void round_trip(uint8_t type, void *value, const uint8_t *wire, uint32_t len)
{
    co_od_entry_t e = var(0x2000, 0, type, CO_OD_RW, len, value);
    co_od_t od = make_od(&e, 1, NULL);
    uint8_t back[16] = {0};
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    CHECK_EQ(co_od_write(&od, &e, wire, len), CO_ABORT_NONE);
    CHECK_EQ(read_all(&od, &e, back, sizeof back), len);
    CHECK(memcmp(back, wire, len) == 0);
}

/* Read a native value back out as wire bytes. */
static void check_wire(uint8_t type, void *value, const uint8_t *wire, uint32_t len)
{
    co_od_entry_t e = var(0x2000, 0, type, CO_OD_RW, len, value);
    co_od_t od = make_od(&e, 1, NULL);
    uint8_t back[16] = {0};
    CHECK_EQ(read_all(&od, &e, back, sizeof back), len);
    CHECK(memcmp(back, wire, len) == 0);
}

/* ---- Types and validation. */

static void test_type_size(void)
{
    CHECK_EQ(co_type_size(CO_TYPE_BOOLEAN), 1);
    CHECK_EQ(co_type_size(CO_TYPE_INTEGER8), 1);
    CHECK_EQ(co_type_size(CO_TYPE_UNSIGNED8), 1);
    CHECK_EQ(co_type_size(CO_TYPE_INTEGER16), 2);
    CHECK_EQ(co_type_size(CO_TYPE_UNSIGNED16), 2);
    CHECK_EQ(co_type_size(CO_TYPE_INTEGER24), 3);
    CHECK_EQ(co_type_size(CO_TYPE_UNSIGNED24), 3);
    CHECK_EQ(co_type_size(CO_TYPE_INTEGER32), 4);
    CHECK_EQ(co_type_size(CO_TYPE_UNSIGNED32), 4);
    CHECK_EQ(co_type_size(CO_TYPE_REAL32), 4);
    CHECK_EQ(co_type_size(CO_TYPE_INTEGER40), 5);
    CHECK_EQ(co_type_size(CO_TYPE_UNSIGNED40), 5);
    CHECK_EQ(co_type_size(CO_TYPE_INTEGER48), 6);
    CHECK_EQ(co_type_size(CO_TYPE_UNSIGNED48), 6);
    CHECK_EQ(co_type_size(CO_TYPE_TIME_OF_DAY), 6);
    CHECK_EQ(co_type_size(CO_TYPE_TIME_DIFFERENCE), 6);
    CHECK_EQ(co_type_size(CO_TYPE_INTEGER56), 7);
    CHECK_EQ(co_type_size(CO_TYPE_UNSIGNED56), 7);
    CHECK_EQ(co_type_size(CO_TYPE_INTEGER64), 8);
    CHECK_EQ(co_type_size(CO_TYPE_UNSIGNED64), 8);
    CHECK_EQ(co_type_size(CO_TYPE_REAL64), 8);
    CHECK_EQ(co_type_size(CO_TYPE_VISIBLE_STRING), 0);
    CHECK_EQ(co_type_size(CO_TYPE_OCTET_STRING), 0);
    CHECK_EQ(co_type_size(CO_TYPE_UNICODE_STRING), 0);
    CHECK_EQ(co_type_size(CO_TYPE_DOMAIN), 0);
    CHECK_EQ(co_type_size((co_type_t)0x00), 0);
    CHECK_EQ(co_type_size((co_type_t)0x0E), 0);
    CHECK_EQ(co_type_size((co_type_t)0x17), 0);
    CHECK_EQ(co_type_size((co_type_t)0x1C), 0);
    CHECK_EQ(co_type_size((co_type_t)0xFF), 0);
}

static void test_validate_example(void)
{
    static example_od_t x;
    co_od_t od = example_od_init(&x, 1000);
    uint32_t bad = 0xDEAD;
    CHECK_EQ(co_od_validate(&od, &bad), CO_OK);
    CHECK_EQ(bad, 0xDEAD);
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    co_od_t empty = make_od(NULL, 0, NULL);
    CHECK_EQ(co_od_validate(&empty, NULL), CO_OK);
    co_od_t broken = make_od(NULL, 3, NULL);
    CHECK_EQ(co_od_validate(&broken, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 0);
    CHECK_EQ(co_od_validate(NULL, NULL), CO_ERR_ARG);
}

static void test_validate_order(void)
{
    uint8_t v[4] = {0};
    co_od_entry_t unsorted[] = {
        var(0x1000, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[0]),
        var(0x1001, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[1]),
        var(0x1000, 5, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[2]),
    };
    co_od_t od = make_od(unsorted, COUNT(unsorted), NULL);
    uint32_t bad = 0;
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 2);

    co_od_entry_t subs[] = {
        var(0x1000, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[0]),
        var(0x1000, 2, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[1]),
        var(0x1000, 1, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[2]),
    };
    od = make_od(subs, COUNT(subs), NULL);
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 2);

    co_od_entry_t dup[] = {
        var(0x1000, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[0]),
        var(0x1000, 1, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[1]),
        var(0x1000, 1, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[2]),
        var(0x1001, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v[3]),
    };
    od = make_od(dup, COUNT(dup), NULL);
    CHECK_EQ(co_od_validate(&od, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 2);
}

/* One bad entry after a good one: validate must name position 1. */
static void expect_bad_second(co_od_entry_t e, uint32_t line)
{
    uint8_t good = 0;
    co_od_entry_t t[2] = {var(0x1000, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &good), e};
    co_od_t od = make_od(t, 2, NULL);
    uint32_t bad = 99;
    co_err_t err = co_od_validate(&od, &bad);
    if (err != CO_ERR_CONFIG || bad != 1) {
        printf("  (case at line %u)\n", (unsigned)line);
    }
    CHECK_EQ(err, CO_ERR_CONFIG);
    CHECK_EQ(bad, 1);
}

static co_abort_t hook_read_zero(void *ctx, const co_od_entry_t *e, uint32_t offset, uint8_t *buf,
                                 uint32_t cap, uint32_t *n, uint32_t *total)
{
    (void)ctx;
    (void)offset;
    uint32_t k = cap < e->size ? cap : e->size;
    memset(buf, 0, k);
    *n = k;
    *total = e->size;
    return CO_ABORT_NONE;
}

static co_abort_t hook_write_drop(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                  const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    (void)ctx, (void)e, (void)offset, (void)data, (void)n, (void)total, (void)last;
    return CO_ABORT_NONE;
}

static void test_validate_entries(void)
{
    static const co_od_hooks_t rd = {.read = hook_read_zero};
    static const co_od_hooks_t wr = {.write = hook_write_drop};
    static const co_od_hooks_t both = {.read = hook_read_zero, .write = hook_write_drop};
    uint32_t u32 = 0;
    char s[8] = "";
    co_od_domain_t no_buf = {.data = NULL, .len = 0};
    co_od_entry_t e;

    /* wrong sizes for fixed types, zero capacity for variable ones, unknown types */
    expect_bad_second(var(0x1001, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 2, &u32), __LINE__);
    expect_bad_second(var(0x1001, 0, CO_TYPE_UNSIGNED16, CO_OD_RW, 4, &u32), __LINE__);
    expect_bad_second(var(0x1001, 0, CO_TYPE_INTEGER24, CO_OD_RW, 4, &u32), __LINE__);
    expect_bad_second(var(0x1001, 0, CO_TYPE_BOOLEAN, CO_OD_RW, 0, &u32), __LINE__);
    expect_bad_second(var(0x1001, 0, CO_TYPE_VISIBLE_STRING, CO_OD_RW, 0, s), __LINE__);
    expect_bad_second(var(0x1001, 0, CO_TYPE_OCTET_STRING, CO_OD_RW, 0, s), __LINE__);
    expect_bad_second(var(0x1001, 0, CO_TYPE_UNICODE_STRING, CO_OD_RW, 7, s), __LINE__);
    expect_bad_second(var(0x1001, 0, 0x0E, CO_OD_RW, 1, &u32), __LINE__);
    expect_bad_second(var(0x1001, 0, 0x00, CO_OD_RW, 1, &u32), __LINE__);
    expect_bad_second(var(0x1001, 0, 0x40, CO_OD_RW, 1, &u32), __LINE__);
    /* storage missing where no hook replaces it */
    expect_bad_second(var(0x1001, 0, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, NULL), __LINE__);
    expect_bad_second(var(0x1001, 0, CO_TYPE_UNSIGNED32, CO_OD_WO, 4, NULL), __LINE__);
    expect_bad_second(var(0x1001, 0, CO_TYPE_UNSIGNED32, 0, 4, NULL), __LINE__);
    expect_bad_second(var(0x1001, 0, CO_TYPE_DOMAIN, CO_OD_RW, 8, &no_buf), __LINE__);
    e = var(0x1001, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, NULL);
    e.hooks = &rd;
    expect_bad_second(e, __LINE__);
    e.hooks = &wr;
    expect_bad_second(e, __LINE__);

    /* and the matching good ones */
    co_od_entry_t ok[] = {
        var(0x1000, 0, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, NULL),
        var(0x1001, 0, CO_TYPE_UNSIGNED32, CO_OD_WO, 4, NULL),
        var(0x1002, 0, CO_TYPE_DOMAIN, CO_OD_RW, 0xFFFFFFFFu, NULL),
        var(0x1003, 0, CO_TYPE_UNICODE_STRING, CO_OD_RW, 8, s),
        var(0x1004, 0, CO_TYPE_INTEGER24, CO_OD_RW, 3, &u32),
    };
    ok[0].hooks = &rd;
    ok[1].hooks = &wr;
    ok[2].hooks = &both;
    co_od_t od = make_od(ok, COUNT(ok), NULL);
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
}

/* ---- Look-up. */

static void test_find_example(void)
{
    static example_od_t x;
    co_od_t od = example_od_init(&x, 500);
    co_abort_t ab = 0;
    const co_od_entry_t *e = co_od_find(&od, 0x1000, 0, &ab);
    CHECK(e == &od.entries[0]);
    e = co_od_find(&od, 0x6200, 4, &ab);
    CHECK(e == &od.entries[od.count - 1]);
    e = co_od_find(&od, 0x1016, 2, &ab);
    CHECK(e != NULL && e->index == 0x1016 && e->sub == 2 && e->value == &x.hb_consumer[1]);

    CHECK(co_od_find(&od, 0x1016, 5, &ab) == NULL);
    CHECK_EQ(ab, CO_ABORT_NO_SUB);
    CHECK(co_od_find(&od, 0x1017, 1, &ab) == NULL);
    CHECK_EQ(ab, CO_ABORT_NO_SUB);
    CHECK(co_od_find(&od, 0x6200, 0xFF, &ab) == NULL);
    CHECK_EQ(ab, CO_ABORT_NO_SUB);
    CHECK(co_od_find(&od, 0x1002, 0, &ab) == NULL);
    CHECK_EQ(ab, CO_ABORT_NO_OBJECT);
    CHECK(co_od_find(&od, 0x0FFF, 0xFF, &ab) == NULL);
    CHECK_EQ(ab, CO_ABORT_NO_OBJECT);
    CHECK(co_od_find(&od, 0xFFFF, 0, &ab) == NULL);
    CHECK_EQ(ab, CO_ABORT_NO_OBJECT);
    CHECK(co_od_find(&od, 0x0000, 0, NULL) == NULL);

    co_od_t empty = make_od(NULL, 0, NULL);
    CHECK(co_od_find(&empty, 0x1000, 0, &ab) == NULL);
    CHECK_EQ(ab, CO_ABORT_NO_OBJECT);
}

#define BIG_OBJECTS 2000
#define BIG_SUBS 3

/* Objects at even indexes 0x2000, 0x2002, ... with subs 0, 2, 4. */
static void test_find_large(void)
{
    static co_od_entry_t t[BIG_OBJECTS * BIG_SUBS];
    static uint8_t vals[BIG_OBJECTS * BIG_SUBS];
    uint32_t n = 0;
    for (uint32_t i = 0; i < BIG_OBJECTS; i++) {
        for (uint32_t s = 0; s < BIG_SUBS; s++) {
            t[n] = var((uint16_t)(0x2000 + 2 * i), (uint8_t)(2 * s), CO_TYPE_UNSIGNED8, CO_OD_RW, 1,
                       &vals[n]);
            n++;
        }
    }
    co_od_t od = make_od(t, n, NULL);
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    uint32_t found = 0, wrong = 0;
    for (uint32_t i = 0; i < BIG_OBJECTS; i++) {
        uint16_t index = (uint16_t)(0x2000 + 2 * i);
        for (uint32_t s = 0; s < 2 * BIG_SUBS + 1; s++) {
            co_abort_t ab = 0;
            const co_od_entry_t *e = co_od_find(&od, index, (uint8_t)s, &ab);
            if (s % 2 == 0 && s < 2 * BIG_SUBS) {
                found += e == &t[i * BIG_SUBS + s / 2];
            } else {
                wrong += e != NULL || ab != CO_ABORT_NO_SUB;
            }
            e = co_od_find(&od, (uint16_t)(index + 1), (uint8_t)s, &ab);
            wrong += e != NULL || ab != CO_ABORT_NO_OBJECT;
        }
    }
    CHECK_EQ(found, n);
    CHECK_EQ(wrong, 0);
    co_abort_t ab = 0;
    CHECK(co_od_find(&od, 0x1FFF, 0, &ab) == NULL);
    CHECK_EQ(ab, CO_ABORT_NO_OBJECT);
}

/* ---- Wire forms of every type. */

static void test_round_trip_small_ints(void)
{
    uint8_t b = 0;
    int8_t i8 = 0;
    uint8_t u8 = 0;
    int16_t i16 = 0;
    uint16_t u16 = 0;
    round_trip(CO_TYPE_BOOLEAN, &b, (const uint8_t[]){0x01}, 1);
    CHECK_EQ(b, 1);
    round_trip(CO_TYPE_BOOLEAN, &b, (const uint8_t[]){0x00}, 1);
    CHECK_EQ(b, 0);
    round_trip(CO_TYPE_INTEGER8, &i8, (const uint8_t[]){0x80}, 1);
    CHECK_EQ(i8, -128);
    round_trip(CO_TYPE_UNSIGNED8, &u8, (const uint8_t[]){0xFE}, 1);
    CHECK_EQ(u8, 0xFE);
    round_trip(CO_TYPE_INTEGER16, &i16, (const uint8_t[]){0xFE, 0xFF}, 2);
    CHECK_EQ(i16, -2);
    round_trip(CO_TYPE_UNSIGNED16, &u16, (const uint8_t[]){0x34, 0x12}, 2);
    CHECK_EQ(u16, 0x1234);
}

static void test_round_trip_32(void)
{
    int32_t i32 = 0;
    uint32_t u32 = 0;
    round_trip(CO_TYPE_INTEGER24, &i32, (const uint8_t[]){0xFF, 0xFF, 0xFF}, 3);
    CHECK_EQ(i32, -1);
    round_trip(CO_TYPE_INTEGER24, &i32, (const uint8_t[]){0x00, 0x00, 0x80}, 3);
    CHECK_EQ(i32, -8388608);
    round_trip(CO_TYPE_INTEGER24, &i32, (const uint8_t[]){0xFF, 0xFF, 0x7F}, 3);
    CHECK_EQ(i32, 8388607);
    round_trip(CO_TYPE_UNSIGNED24, &u32, (const uint8_t[]){0xFF, 0xFF, 0xFF}, 3);
    CHECK_EQ(u32, 0xFFFFFF);
    round_trip(CO_TYPE_INTEGER32, &i32, (const uint8_t[]){0x78, 0x56, 0x34, 0x12}, 4);
    CHECK_EQ(i32, 0x12345678);
    round_trip(CO_TYPE_INTEGER32, &i32, (const uint8_t[]){0x00, 0x00, 0x00, 0x80}, 4);
    CHECK(i32 == INT32_MIN);
    round_trip(CO_TYPE_UNSIGNED32, &u32, (const uint8_t[]){0xEF, 0xBE, 0xAD, 0xDE}, 4);
    CHECK_EQ(u32, 0xDEADBEEF);

    /* native -> wire takes the low three bytes */
    i32 = -2;
    check_wire(CO_TYPE_INTEGER24, &i32, (const uint8_t[]){0xFE, 0xFF, 0xFF}, 3);
    u32 = 0x00ABCDEF;
    check_wire(CO_TYPE_UNSIGNED24, &u32, (const uint8_t[]){0xEF, 0xCD, 0xAB}, 3);
}

static void test_round_trip_64(void)
{
    int64_t i64 = 0;
    uint64_t u64 = 0;
    round_trip(CO_TYPE_UNSIGNED40, &u64, (const uint8_t[]){1, 2, 3, 4, 5}, 5);
    CHECK_EQ(u64, 0x0504030201ull);
    round_trip(CO_TYPE_INTEGER40, &i64, (const uint8_t[]){0, 0, 0, 0, 0x80}, 5);
    CHECK(i64 == -((int64_t)1 << 39));
    round_trip(CO_TYPE_INTEGER40, &i64, (const uint8_t[]){0xFF, 0xFF, 0xFF, 0xFF, 0x7F}, 5);
    CHECK(i64 == 0x7FFFFFFFFFll);
    round_trip(CO_TYPE_INTEGER48, &i64, (const uint8_t[]){0xFE, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}, 6);
    CHECK(i64 == -2);
    round_trip(CO_TYPE_UNSIGNED48, &u64, (const uint8_t[]){1, 2, 3, 4, 5, 0xF6}, 6);
    CHECK_EQ(u64, 0xF60504030201ull);
    round_trip(CO_TYPE_INTEGER56, &i64, (const uint8_t[]){0, 0, 0, 0, 0, 0, 0x80}, 7);
    CHECK(i64 == -((int64_t)1 << 55));
    round_trip(CO_TYPE_UNSIGNED56, &u64, (const uint8_t[]){1, 2, 3, 4, 5, 6, 0xF7}, 7);
    CHECK_EQ(u64, 0xF7060504030201ull);
    round_trip(CO_TYPE_INTEGER64, &i64, (const uint8_t[]){0, 0, 0, 0, 0, 0, 0, 0x80}, 8);
    CHECK(i64 == INT64_MIN);
    round_trip(CO_TYPE_UNSIGNED64, &u64, (const uint8_t[]){1, 2, 3, 4, 5, 6, 7, 0xF8}, 8);
    CHECK_EQ(u64, 0xF807060504030201ull);

    i64 = -3;
    check_wire(CO_TYPE_INTEGER40, &i64, (const uint8_t[]){0xFD, 0xFF, 0xFF, 0xFF, 0xFF}, 5);
    u64 = 0x1122334455667788ull; /* the high byte does not fit UNSIGNED56 */
    check_wire(CO_TYPE_UNSIGNED56, &u64,
               (const uint8_t[]){0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22}, 7);
}

static void test_round_trip_real(void)
{
    float f = 0.0f;
    double d = 0.0;
    round_trip(CO_TYPE_REAL32, &f, (const uint8_t[]){0x00, 0x00, 0xC0, 0x3F}, 4);
    CHECK(f == 1.5f);
    round_trip(CO_TYPE_REAL32, &f, (const uint8_t[]){0x00, 0x00, 0x00, 0xC0}, 4);
    CHECK(f == -2.0f);
    round_trip(CO_TYPE_REAL64, &d, (const uint8_t[]){0, 0, 0, 0, 0, 0, 0xF8, 0x3F}, 8);
    CHECK(d == 1.5);
    round_trip(CO_TYPE_REAL64, &d, (const uint8_t[]){0, 0, 0, 0, 0, 0, 0x59, 0xC0}, 8);
    CHECK(d == -100.0);

    f = 1.5f;
    check_wire(CO_TYPE_REAL32, &f, (const uint8_t[]){0x00, 0x00, 0xC0, 0x3F}, 4);
    d = 0.1;
    check_wire(CO_TYPE_REAL64, &d,
               (const uint8_t[]){0x9A, 0x99, 0x99, 0x99, 0x99, 0x99, 0xB9, 0x3F}, 8);
}

static void test_round_trip_time(void)
{
    uint8_t tod[6] = {0};
    uint8_t diff[6] = {0};
    const uint8_t wire[6] = {0x10, 0x32, 0x54, 0x06, 0x2A, 0x3B}; /* ms, then days since 1984 */
    round_trip(CO_TYPE_TIME_OF_DAY, tod, wire, 6);
    CHECK(memcmp(tod, wire, 6) == 0);
    round_trip(CO_TYPE_TIME_DIFFERENCE, diff, wire, 6);
    CHECK(memcmp(diff, wire, 6) == 0);
}

/* Piecewise reads of a number, offsets at and past the end. */
static void test_read_pieces(void)
{
    uint32_t u32 = 0xA1B2C3D4u;
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, &u32);
    co_od_t od = make_od(&e, 1, NULL);
    uint8_t buf[4] = {0};
    uint32_t n = 9, total = 9;
    CHECK_EQ(co_od_read(&od, &e, 0, buf, 3, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(n, 3);
    CHECK_EQ(total, 4);
    CHECK_EQ(buf[0], 0xD4);
    CHECK_EQ(buf[2], 0xB2);
    CHECK_EQ(co_od_read(&od, &e, 3, buf, 3, &n, NULL), CO_ABORT_NONE);
    CHECK_EQ(n, 1);
    CHECK_EQ(buf[0], 0xA1);
    CHECK_EQ(co_od_read(&od, &e, 4, buf, 3, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(n, 0);
    CHECK_EQ(co_od_read(&od, &e, 5, buf, 3, &n, &total), CO_ABORT_GENERAL);
    CHECK_EQ(n, 0);
    CHECK_EQ(co_od_read(&od, &e, 0, NULL, 0, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(n, 0);
    CHECK_EQ(total, 4);
}

/* ---- Lengths. */

static void test_length_fixed(void)
{
    static const struct {
        uint8_t type;
        uint32_t size;
    } types[] = {
        {CO_TYPE_BOOLEAN, 1},         {CO_TYPE_INTEGER8, 1},   {CO_TYPE_UNSIGNED8, 1},
        {CO_TYPE_INTEGER16, 2},       {CO_TYPE_UNSIGNED16, 2}, {CO_TYPE_INTEGER24, 3},
        {CO_TYPE_UNSIGNED24, 3},      {CO_TYPE_INTEGER32, 4},  {CO_TYPE_UNSIGNED32, 4},
        {CO_TYPE_REAL32, 4},          {CO_TYPE_INTEGER40, 5},  {CO_TYPE_UNSIGNED40, 5},
        {CO_TYPE_INTEGER48, 6},       {CO_TYPE_UNSIGNED48, 6}, {CO_TYPE_TIME_OF_DAY, 6},
        {CO_TYPE_TIME_DIFFERENCE, 6}, {CO_TYPE_INTEGER56, 7},  {CO_TYPE_UNSIGNED56, 7},
        {CO_TYPE_INTEGER64, 8},       {CO_TYPE_UNSIGNED64, 8}, {CO_TYPE_REAL64, 8},
    };
    const uint8_t zeros[9] = {0};
    for (uint32_t i = 0; i < COUNT(types); i++) {
        uint64_t storage = 0x5A5A5A5A5A5A5A5Aull; /* wide and aligned enough for every type */
        uint64_t before = storage;
        co_od_entry_t e = var(0x2000, 0, types[i].type, CO_OD_RW, types[i].size, &storage);
        co_od_t od = make_od(&e, 1, NULL);
        CHECK_EQ(co_od_write(&od, &e, zeros, types[i].size + 1), CO_ABORT_LEN_HIGH);
        CHECK_EQ(co_od_write(&od, &e, zeros, types[i].size - 1), CO_ABORT_LEN_LOW);
        CHECK_EQ(co_od_check(&od, &e, zeros, 0), CO_ABORT_LEN_LOW);
        CHECK_EQ(co_od_store(&od, &e, zeros, types[i].size + 1), CO_ABORT_LEN_HIGH);
        CHECK_EQ(storage, before);
        CHECK_EQ(co_od_check(&od, &e, zeros, types[i].size), CO_ABORT_NONE);
    }
}

static void test_length_variable(void)
{
    char vs[4] = "abc";
    uint8_t os[4] = {1, 2, 3, 4};
    uint8_t us[4] = {'a', 0, 'b', 0};
    uint8_t buf[4] = {0};
    co_od_domain_t dom = {.data = buf, .len = 0};
    co_od_entry_t t[] = {
        var(0x2000, 0, CO_TYPE_VISIBLE_STRING, CO_OD_RW, 4, vs),
        var(0x2001, 0, CO_TYPE_OCTET_STRING, CO_OD_RW, 4, os),
        var(0x2002, 0, CO_TYPE_UNICODE_STRING, CO_OD_RW, 4, us),
        var(0x2003, 0, CO_TYPE_DOMAIN, CO_OD_RW, 4, &dom),
    };
    co_od_t od = make_od(t, COUNT(t), NULL);
    const uint8_t data[5] = {'v', 'w', 'x', 'y', 'z'};
    for (uint32_t i = 0; i < COUNT(t); i++) {
        CHECK_EQ(co_od_write(&od, &t[i], data, 5), CO_ABORT_LEN_HIGH);
        CHECK_EQ(co_od_check(&od, &t[i], data, 4), CO_ABORT_NONE);
        CHECK_EQ(co_od_check(&od, &t[i], data, 2), CO_ABORT_NONE);
        CHECK_EQ(co_od_check(&od, &t[i], NULL, 0), CO_ABORT_NONE);
    }
    CHECK_EQ(co_od_write(&od, &t[2], data, 3), CO_ABORT_TYPE_MISMATCH);
    CHECK_EQ(co_od_write(&od, &t[2], data, 1), CO_ABORT_TYPE_MISMATCH);
    CHECK_STR(vs, "abc");
    CHECK_EQ(os[3], 4);
    CHECK_EQ(us[2], 'b');
    CHECK_EQ(dom.len, 0);
}

/* ---- Strings and domains. */

static void test_visible_string(void)
{
    char s[8] = {'a', 'b', 'c', 'd', 'e', 'f', 'g', 'h'}; /* full: no terminator */
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_VISIBLE_STRING, CO_OD_RW, 8, s);
    co_od_t od = make_od(&e, 1, NULL);
    uint8_t buf[16];
    CHECK_EQ(co_od_value_len(&od, &e), 8);
    CHECK_EQ(read_all(&od, &e, buf, sizeof buf), 8);
    CHECK(memcmp(buf, "abcdefgh", 8) == 0);

    CHECK_EQ(co_od_write(&od, &e, (const uint8_t *)"xy", 2), CO_ABORT_NONE);
    CHECK(memcmp(s, "xy\0\0\0\0\0\0", 8) == 0);
    CHECK_EQ(co_od_value_len(&od, &e), 2);
    CHECK_EQ(read_all(&od, &e, buf, sizeof buf), 2);
    CHECK(memcmp(buf, "xy", 2) == 0);

    CHECK_EQ(co_od_write(&od, &e, NULL, 0), CO_ABORT_NONE);
    CHECK_EQ(co_od_value_len(&od, &e), 0);
    CHECK_EQ(s[0], 0);

    /* an embedded NUL ends the string */
    CHECK_EQ(co_od_write(&od, &e, (const uint8_t *)"ab\0cd", 5), CO_ABORT_NONE);
    CHECK_EQ(co_od_value_len(&od, &e), 2);
}

static void test_octet_string(void)
{
    uint8_t os[6] = {9, 9, 9, 9, 9, 9};
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_OCTET_STRING, CO_OD_RW, 6, os);
    co_od_t od = make_od(&e, 1, NULL);
    uint8_t buf[8];
    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){0, 1, 2}, 3), CO_ABORT_NONE);
    CHECK(memcmp(os, "\0\1\2\0\0\0", 6) == 0);
    CHECK_EQ(co_od_value_len(&od, &e), 6);
    CHECK_EQ(read_all(&od, &e, buf, sizeof buf), 6);
    CHECK(memcmp(buf, os, 6) == 0);
}

static void test_unicode_string(void)
{
    uint8_t us[8];
    memset(us, 0x55, sizeof us);
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_UNICODE_STRING, CO_OD_RW, 8, us);
    co_od_t od = make_od(&e, 1, NULL);
    uint8_t buf[8];
    CHECK_EQ(co_od_value_len(&od, &e), 8);
    /* "A" then U+0100 (bytes 00 01: a zero byte, not a zero code unit) */
    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){'A', 0, 0x00, 0x01}, 4), CO_ABORT_NONE);
    CHECK_EQ(co_od_value_len(&od, &e), 4);
    CHECK_EQ(read_all(&od, &e, buf, sizeof buf), 4);
    CHECK(memcmp(buf, "A\0\0\1", 4) == 0);
    CHECK_EQ(us[4], 0);
    CHECK_EQ(us[7], 0);
    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){1, 0, 2, 0, 3, 0, 4, 0}, 8), CO_ABORT_NONE);
    CHECK_EQ(co_od_value_len(&od, &e), 8);
}

static void test_domain_storage(void)
{
    uint8_t data[16] = {0};
    co_od_domain_t dom = {.data = data, .len = 0};
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_DOMAIN, CO_OD_RW, sizeof data, &dom);
    co_od_t od = make_od(&e, 1, NULL);
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    CHECK_EQ(co_od_value_len(&od, &e), 0);
    const uint8_t in[10] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
    CHECK_EQ(co_od_write(&od, &e, in, 10), CO_ABORT_NONE);
    CHECK_EQ(dom.len, 10);
    CHECK_EQ(co_od_value_len(&od, &e), 10);

    uint8_t out[10] = {0};
    uint32_t off = 0, n = 0, total = 0, pieces = 0;
    do {
        CHECK_EQ(co_od_read(&od, &e, off, out + off, 3, &n, &total), CO_ABORT_NONE);
        off += n;
        pieces++;
    } while (n > 0 && pieces < 10);
    CHECK_EQ(off, 10);
    CHECK_EQ(total, 10);
    CHECK_EQ(pieces, 5); /* 3 + 3 + 3 + 1, then 0 */
    CHECK(memcmp(out, in, 10) == 0);
    CHECK_EQ(co_od_read(&od, &e, 11, out, 3, &n, &total), CO_ABORT_GENERAL);

    CHECK_EQ(co_od_write(&od, &e, in, 17), CO_ABORT_LEN_HIGH);
    CHECK_EQ(dom.len, 10);
    CHECK_EQ(co_od_write(&od, &e, NULL, 0), CO_ABORT_NONE);
    CHECK_EQ(dom.len, 0);

    dom.len = 100; /* application mistake: never read past the capacity */
    CHECK_EQ(co_od_value_len(&od, &e), 16);
}

/* ---- Values and limits. */

static void test_boolean_value(void)
{
    uint8_t b = 1;
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_BOOLEAN, CO_OD_RW, 1, &b);
    co_od_t od = make_od(&e, 1, NULL);
    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){2}, 1), 0x06090030u);
    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){0xFF}, 1), CO_ABORT_VALUE);
    CHECK_EQ(b, 1);
    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){0}, 1), CO_ABORT_NONE);
    CHECK_EQ(b, 0);
}

static void test_limits_signed(void)
{
    static const co_od_limits_t lim16 = {.low = {.i = -100}, .high = {.i = 100}};
    static const co_od_limits_t lim24 = {.low = {.i = -5}, .high = {.i = 5}};
    int16_t i16 = 7;
    int32_t i24 = 1;
    co_od_entry_t t[] = {
        var(0x2000, 0, CO_TYPE_INTEGER16, CO_OD_RW, 2, &i16),
        var(0x2001, 0, CO_TYPE_INTEGER24, CO_OD_RW, 3, &i24),
    };
    t[0].limits = &lim16;
    t[1].limits = &lim24;
    co_od_t od = make_od(t, COUNT(t), NULL);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){101, 0}, 2), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0x9B, 0xFF}, 2), CO_ABORT_VALUE_LOW);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0x00, 0x80}, 2), CO_ABORT_VALUE_LOW);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0xFF, 0x7F}, 2), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(i16, 7);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){100, 0}, 2), CO_ABORT_NONE);
    CHECK_EQ(i16, 100);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0x9C, 0xFF}, 2), CO_ABORT_NONE);
    CHECK_EQ(i16, -100);
    /* INTEGER24 is sign-extended from 24 bits before the comparison */
    CHECK_EQ(co_od_write(&od, &t[1], (const uint8_t[]){0xFF, 0xFF, 0xFF}, 3), CO_ABORT_NONE);
    CHECK_EQ(i24, -1);
    CHECK_EQ(co_od_write(&od, &t[1], (const uint8_t[]){0xFA, 0xFF, 0xFF}, 3), CO_ABORT_VALUE_LOW);
    CHECK_EQ(co_od_write(&od, &t[1], (const uint8_t[]){0x06, 0x00, 0x00}, 3), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(i24, -1);
}

static void test_limits_unsigned(void)
{
    static const co_od_limits_t lim32 = {.low = {.u = 10}, .high = {.u = 1000}};
    static const co_od_limits_t lim64 = {.low = {.u = 0}, .high = {.u = 0xFFFFFFFFFFFFFFFEull}};
    uint32_t u32 = 500;
    uint64_t u64 = 1;
    co_od_entry_t t[] = {
        var(0x2000, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &u32),
        var(0x2001, 0, CO_TYPE_UNSIGNED64, CO_OD_RW, 8, &u64),
    };
    t[0].limits = &lim32;
    t[1].limits = &lim64;
    co_od_t od = make_od(t, COUNT(t), NULL);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){9, 0, 0, 0}, 4), CO_ABORT_VALUE_LOW);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0xE9, 0x03, 0, 0}, 4), CO_ABORT_VALUE_HIGH);
    /* 0xFFFFFFFF must not be taken for -1 */
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0xFF, 0xFF, 0xFF, 0xFF}, 4),
             CO_ABORT_VALUE_HIGH);
    CHECK_EQ(u32, 500);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){10, 0, 0, 0}, 4), CO_ABORT_NONE);
    CHECK_EQ(u32, 10);
    CHECK_EQ(co_od_write(&od, &t[1],
                         (const uint8_t[]){0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}, 8),
             CO_ABORT_VALUE_HIGH);
    CHECK_EQ(co_od_write(&od, &t[1],
                         (const uint8_t[]){0xFE, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}, 8),
             CO_ABORT_NONE);
    CHECK_EQ(u64, 0xFFFFFFFFFFFFFFFEull);
}

static void test_limits_real(void)
{
    static const co_od_limits_t lim = {.low = {.f = -1.0}, .high = {.f = 1.0}};
    float f = 0.25f;
    double d = 0.25;
    co_od_entry_t t[] = {
        var(0x2000, 0, CO_TYPE_REAL32, CO_OD_RW, 4, &f),
        var(0x2001, 0, CO_TYPE_REAL64, CO_OD_RW, 8, &d),
    };
    t[0].limits = &lim;
    t[1].limits = &lim;
    co_od_t od = make_od(t, COUNT(t), NULL);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0, 0, 0xC0, 0x3F}, 4), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0, 0, 0xC0, 0xBF}, 4), CO_ABORT_VALUE_LOW);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0, 0, 0xC0, 0x7F}, 4), CO_ABORT_VALUE);
    CHECK(f == 0.25f);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){0, 0, 0x80, 0x3F}, 4), CO_ABORT_NONE);
    CHECK(f == 1.0f);
    CHECK_EQ(co_od_write(&od, &t[1], (const uint8_t[]){0, 0, 0, 0, 0, 0, 0xF8, 0x3F}, 8),
             CO_ABORT_VALUE_HIGH);
    CHECK_EQ(co_od_write(&od, &t[1], (const uint8_t[]){0, 0, 0, 0, 0, 0, 0xF8, 0xBF}, 8),
             CO_ABORT_VALUE_LOW);
    CHECK(d == 0.25);
    CHECK_EQ(co_od_write(&od, &t[1], (const uint8_t[]){0, 0, 0, 0, 0, 0, 0xE0, 0xBF}, 8),
             CO_ABORT_NONE);
    CHECK(d == -0.5);
}

static void test_example_limits(void)
{
    static example_od_t x;
    co_od_t od = example_od_init(&x, 0);
    const co_od_entry_t *e = co_od_find(&od, 0x2001, 0, NULL);
    CHECK(e != NULL);
    CHECK_EQ(co_od_write(&od, e, (const uint8_t[]){101, 0}, 2), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(co_od_write(&od, e, (const uint8_t[]){0xF6, 0xFF}, 2), CO_ABORT_NONE);
    CHECK_EQ(x.app_i16, -10);
}

/* ---- Access rules. */

static void test_access(void)
{
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_UNSIGNED8, CO_OD_RO, 1, NULL);
    const co_od_t od = {.entries = &e, .count = 1};
    CHECK_EQ(co_od_access(&od, &e, false), CO_ABORT_NONE);
    CHECK_EQ(co_od_access(&od, &e, true), CO_ABORT_READ_ONLY);
    e.attr = CO_OD_WO;
    CHECK_EQ(co_od_access(&od, &e, false), CO_ABORT_WRITE_ONLY);
    CHECK_EQ(co_od_access(&od, &e, true), CO_ABORT_NONE);
    e.attr = CO_OD_RW | CO_OD_TPDO | CO_OD_RPDO;
    CHECK_EQ(co_od_access(&od, &e, false), CO_ABORT_NONE);
    CHECK_EQ(co_od_access(&od, &e, true), CO_ABORT_NONE);
    e.attr = CO_OD_CO;
    CHECK_EQ(co_od_access(&od, &e, false), CO_ABORT_NONE);
    CHECK_EQ(co_od_access(&od, &e, true), CO_ABORT_READ_ONLY);
    e.attr = CO_OD_RW | CO_OD_CONST;
    CHECK_EQ(co_od_access(&od, &e, true), CO_ABORT_READ_ONLY);
    e.attr = 0;
    CHECK_EQ(co_od_access(&od, &e, false), CO_ABORT_WRITE_ONLY);
    CHECK_EQ(co_od_access(&od, &e, true), CO_ABORT_READ_ONLY);
}

/* Local access ignores the rules: a write-only entry still has storage to read. */
static void test_access_not_checked_locally(void)
{
    static example_od_t x;
    co_od_t od = example_od_init(&x, 0);
    const co_od_entry_t *wo = co_od_find(&od, 0x2004, 0, NULL);
    const co_od_entry_t *ro = co_od_find(&od, 0x1000, 0, NULL);
    uint8_t buf[4];
    CHECK_EQ(co_od_write(&od, wo, (const uint8_t[]){0x42}, 1), CO_ABORT_NONE);
    CHECK_EQ(read_all(&od, wo, buf, sizeof buf), 1);
    CHECK_EQ(buf[0], 0x42);
    CHECK_EQ(co_od_write(&od, ro, (const uint8_t[]){1, 2, 3, 4}, 4), CO_ABORT_NONE);
    CHECK_EQ(x.device_type, 0x04030201u);
}

/* ---- Hooks. */

typedef struct hook_log {
    uint32_t reads;
    uint32_t checks;
    uint32_t writes;
    uint32_t written;
    uint32_t counter;        /* what the read hook reports */
    uint64_t bytes;          /* streamed byte count */
    uint32_t sum_a, sum_b;   /* Fletcher-style checksum of the streamed bytes */
    uint32_t lasts;          /* pieces flagged last */
    uint32_t last_total;     /* `total` of the last piece */
    uint32_t bad_offsets;    /* pieces not continuing where the previous ended */
    co_abort_t write_result; /* what the write hook answers */
    const co_od_entry_t *seen;
} hook_log_t;

static co_abort_t hook_read_counter(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                    uint8_t *buf, uint32_t cap, uint32_t *n, uint32_t *total)
{
    hook_log_t *log = ctx;
    log->reads++;
    log->seen = e;
    uint8_t wire[4];
    co_put_u32(wire, ++log->counter);
    if (offset > 4) {
        return CO_ABORT_GENERAL;
    }
    uint32_t k = 4 - offset < cap ? 4 - offset : cap;
    memcpy(buf, wire + offset, k);
    *n = k;
    *total = 4;
    return CO_ABORT_NONE;
}

/* Vetoes 0x42 with "device state", accepts anything else. */
static co_abort_t hook_check_veto(void *ctx, const co_od_entry_t *e, const uint8_t *data,
                                  uint32_t len)
{
    hook_log_t *log = ctx;
    (void)e;
    log->checks++;
    return (len == 1 && data[0] == 0x42) ? CO_ABORT_DATA_STATE : CO_ABORT_NONE;
}

static void hook_written(void *ctx, const co_od_entry_t *e)
{
    hook_log_t *log = ctx;
    log->written++;
    log->seen = e;
}

/* Keeps only a byte count and a checksum: no buffer for the value. */
static co_abort_t hook_write_sum(void *ctx, const co_od_entry_t *e, uint32_t offset,
                                 const uint8_t *data, uint32_t n, uint32_t total, bool last)
{
    hook_log_t *log = ctx;
    (void)e;
    log->writes++;
    log->bad_offsets += offset != (uint32_t)log->bytes;
    for (uint32_t i = 0; i < n; i++) {
        log->sum_a = (log->sum_a + data[i]) % 65521u;
        log->sum_b = (log->sum_b + log->sum_a) % 65521u;
    }
    log->bytes += n;
    log->lasts += last;
    log->last_total = total;
    return log->write_result;
}

static void test_hook_read(void)
{
    static const co_od_hooks_t hooks = {.read = hook_read_counter};
    hook_log_t log = {0};
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, NULL);
    e.hooks = &hooks;
    co_od_t od = make_od(&e, 1, &log);
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    uint8_t buf[4];
    uint32_t n = 0, total = 0;
    CHECK_EQ(co_od_read(&od, &e, 0, buf, 4, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(n, 4);
    CHECK_EQ(total, 4);
    CHECK_EQ(co_get_u32(buf), 1);
    CHECK_EQ(co_od_read(&od, &e, 0, buf, 4, &n, NULL), CO_ABORT_NONE); /* no total wanted */
    CHECK_EQ(co_get_u32(buf), 2);
    CHECK_EQ(log.reads, 2);
    CHECK(log.seen == &e);
    CHECK_EQ(co_od_value_len(&od, &e), 4);
    CHECK_EQ(co_od_read(&od, &e, 9, buf, 4, &n, &total), CO_ABORT_GENERAL);

    /* the read hook wins over storage */
    uint32_t stored = 0x11111111u;
    e.value = &stored;
    CHECK_EQ(co_od_read(&od, &e, 0, buf, 4, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(co_get_u32(buf), 4);

    /* no storage and no read hook */
    co_od_entry_t w = var(0x2001, 0, CO_TYPE_UNSIGNED32, CO_OD_WO, 4, NULL);
    CHECK_EQ(co_od_read(&od, &w, 0, buf, 4, &n, &total), CO_ABORT_WRITE_ONLY);
    CHECK_EQ(n, 0);
}

static void test_hook_check_and_written(void)
{
    static const co_od_hooks_t hooks = {.check = hook_check_veto, .written = hook_written};
    static const co_od_limits_t lim = {.low = {.u = 0}, .high = {.u = 0x80}};
    hook_log_t log = {0};
    uint8_t v = 7;
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &v);
    e.hooks = &hooks;
    e.limits = &lim;
    co_od_t od = make_od(&e, 1, &log);

    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){0x42}, 1), CO_ABORT_DATA_STATE);
    CHECK_EQ(v, 7);
    CHECK_EQ(log.checks, 1);
    CHECK_EQ(log.written, 0);
    CHECK_EQ(co_od_check(&od, &e, (const uint8_t[]){0x42}, 1), CO_ABORT_DATA_STATE);
    CHECK_EQ(log.checks, 2);

    /* failing length or limits stops before the check hook */
    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){1, 2}, 2), CO_ABORT_LEN_HIGH);
    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){0x81}, 1), CO_ABORT_VALUE_HIGH);
    CHECK_EQ(log.checks, 2);
    CHECK_EQ(log.written, 0);

    CHECK_EQ(co_od_write(&od, &e, (const uint8_t[]){0x43}, 1), CO_ABORT_NONE);
    CHECK_EQ(v, 0x43);
    CHECK_EQ(log.checks, 3);
    CHECK_EQ(log.written, 1);
    CHECK(log.seen == &e);

    /* store alone never calls written */
    CHECK_EQ(co_od_store(&od, &e, (const uint8_t[]){0x44}, 1), CO_ABORT_NONE);
    CHECK_EQ(v, 0x44);
    CHECK_EQ(log.written, 1);
    CHECK_EQ(log.checks, 3);
}

static void test_hook_store_without_storage(void)
{
    static const co_od_hooks_t hooks = {.write = hook_write_sum, .written = hook_written};
    hook_log_t log = {0};
    co_od_entry_t t[] = {
        var(0x2000, 0, CO_TYPE_UNSIGNED16, CO_OD_WO, 2, NULL),
        var(0x2001, 0, CO_TYPE_UNSIGNED16, CO_OD_WO, 2, NULL),
    };
    t[0].hooks = &hooks;
    co_od_t od = make_od(t, COUNT(t), &log);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){1, 2}, 2), CO_ABORT_NONE);
    CHECK_EQ(log.writes, 1);
    CHECK_EQ(log.bytes, 2);
    CHECK_EQ(log.lasts, 1);
    CHECK_EQ(log.last_total, 2);
    CHECK_EQ(log.written, 1);
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){1}, 1), CO_ABORT_LEN_LOW);
    CHECK_EQ(log.writes, 1);

    log.write_result = CO_ABORT_HARDWARE;
    CHECK_EQ(co_od_write(&od, &t[0], (const uint8_t[]){1, 2}, 2), CO_ABORT_HARDWARE);
    CHECK_EQ(log.written, 1);

    CHECK_EQ(co_od_store(&od, &t[1], (const uint8_t[]){1, 2}, 2), CO_ABORT_UNSUPPORTED);
    CHECK_EQ(co_od_write(&od, &t[1], (const uint8_t[]){1, 2}, 2), CO_ABORT_UNSUPPORTED);
    CHECK_EQ(co_od_write_piece(&od, &t[1], 0, (const uint8_t[]){1}, 1, 1, true),
             CO_ABORT_UNSUPPORTED);
}

#define STREAM_BYTES (100u * 1024u * 1024u)
#define STREAM_PIECE 256u

static uint8_t stream_byte(uint32_t pos) { return (uint8_t)((pos * 2654435761u) >> 24); }

/* 100 MiB through a DOMAIN that has no storage: only the hook's sum and count grow. */
static void test_stream_domain(void)
{
    static const co_od_hooks_t hooks = {.write = hook_write_sum, .written = hook_written};
    hook_log_t log = {0};
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_DOMAIN, CO_OD_WO, 0xFFFFFFFFu, NULL);
    e.hooks = &hooks;
    co_od_t od = make_od(&e, 1, &log);
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);

    uint8_t piece[STREAM_PIECE];
    uint32_t a = 0, b = 0, written_early = 0;
    for (uint32_t off = 0; off < STREAM_BYTES; off += STREAM_PIECE) {
        for (uint32_t i = 0; i < STREAM_PIECE; i++) {
            piece[i] = stream_byte(off + i);
            a = (a + piece[i]) % 65521u;
            b = (b + a) % 65521u;
        }
        bool last = off + STREAM_PIECE >= STREAM_BYTES;
        co_abort_t ab = co_od_write_piece(&od, &e, off, piece, STREAM_PIECE, STREAM_BYTES, last);
        if (ab != CO_ABORT_NONE) {
            CHECK_EQ(ab, CO_ABORT_NONE);
            break;
        }
        written_early += !last && log.written != 0;
    }
    CHECK_EQ(log.bytes, STREAM_BYTES);
    CHECK_EQ(log.writes, STREAM_BYTES / STREAM_PIECE);
    CHECK_EQ(log.sum_a, a);
    CHECK_EQ(log.sum_b, b);
    CHECK_EQ(log.bad_offsets, 0);
    CHECK_EQ(log.lasts, 1);
    CHECK_EQ(log.last_total, STREAM_BYTES);
    CHECK_EQ(log.written, 1);
    CHECK_EQ(written_early, 0);

    /* a hook refusing the last piece: no written */
    hook_log_t log2 = {0};
    od.hook_ctx = &log2;
    log2.write_result = CO_ABORT_CRC;
    CHECK_EQ(co_od_write_piece(&od, &e, 0, piece, 4, CO_OD_SIZE_UNKNOWN, true), CO_ABORT_CRC);
    CHECK_EQ(log2.written, 0);
    CHECK_EQ(log2.last_total, CO_OD_SIZE_UNKNOWN);
}

/* A long VISIBLE_STRING produced piece by piece: letters cycling a..z. */
#define LONG_LEN 5000u

static co_abort_t hook_read_long(void *ctx, const co_od_entry_t *e, uint32_t offset, uint8_t *buf,
                                 uint32_t cap, uint32_t *n, uint32_t *total)
{
    hook_log_t *log = ctx;
    (void)e;
    log->reads++;
    if (offset > LONG_LEN) {
        return CO_ABORT_GENERAL;
    }
    uint32_t k = LONG_LEN - offset < cap ? LONG_LEN - offset : cap;
    for (uint32_t i = 0; i < k; i++) {
        buf[i] = (uint8_t)('a' + (offset + i) % 26u);
    }
    *n = k;
    *total = log->counter ? CO_OD_SIZE_UNKNOWN : LONG_LEN;
    return CO_ABORT_NONE;
}

static void test_read_long_in_pieces(void)
{
    static const co_od_hooks_t hooks = {.read = hook_read_long};
    hook_log_t log = {0};
    co_od_entry_t e = var(0x2000, 0, CO_TYPE_VISIBLE_STRING, CO_OD_RO, LONG_LEN, NULL);
    e.hooks = &hooks;
    co_od_t od = make_od(&e, 1, &log);
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);

    static uint8_t out[LONG_LEN + 7];
    uint32_t off = 0, n = 0, total = 0, mismatches = 0;
    do {
        CHECK_EQ(co_od_read(&od, &e, off, out + off, 7, &n, &total), CO_ABORT_NONE);
        off += n;
    } while (n == 7);
    CHECK_EQ(off, LONG_LEN);
    CHECK_EQ(total, LONG_LEN);
    CHECK_EQ(log.reads, LONG_LEN / 7 + 1);
    for (uint32_t i = 0; i < LONG_LEN; i++) {
        mismatches += out[i] != 'a' + i % 26u;
    }
    CHECK_EQ(mismatches, 0);

    log.counter = 1; /* the hook now does not know the size */
    CHECK_EQ(co_od_read(&od, &e, 0, out, 7, &n, &total), CO_ABORT_NONE);
    CHECK_EQ(total, CO_OD_SIZE_UNKNOWN);
}

/* ---- Reset. */

static const uint32_t k_dev_type = 0x00020192u;
static const uint32_t k_cob_tpdo1 = 0x180u;
static const int8_t k_i8_base = -10;
static const float k_real = 2.5f;
static const uint8_t k_bool = 1;
static const char k_name[8] = "canola";
static const uint8_t k_domain_bytes[3] = {0xD0, 0xD1, 0xD2};
static const co_od_domain_t k_domain = {.data = (uint8_t *)k_domain_bytes, .len = 3};
static const int64_t k_i40 = -1;

typedef struct reset_vals {
    uint32_t dev_type;   /* 0x1000 */
    uint16_t no_default; /* 0x1017, no default */
    uint32_t cob;        /* 0x1800 sub1, NODEID */
    int8_t i8;           /* 0x2000, NODEID */
    float real;          /* 0x2001, NODEID ignored: not an integer */
    char name[8];        /* 0x2002 */
    uint8_t dom_buf[8];
    co_od_domain_t dom; /* 0x2003 */
    uint8_t flag;       /* 0x2004 BOOLEAN */
    int64_t i40;        /* 0x2005 INTEGER40, NODEID */
    uint32_t outside;   /* 0xA000 */
} reset_vals_t;

static uint32_t reset_table(reset_vals_t *v, co_od_entry_t *t)
{
    uint32_t n = 0;
    t[n] = var(0x1000, 0, CO_TYPE_UNSIGNED32, CO_OD_RO, 4, &v->dev_type);
    t[n++].dflt = &k_dev_type;
    t[n++] = var(0x1017, 0, CO_TYPE_UNSIGNED16, CO_OD_RW, 2, &v->no_default);
    t[n] = var(0x1800, 1, CO_TYPE_UNSIGNED32, CO_OD_RW | CO_OD_NODEID, 4, &v->cob);
    t[n++].dflt = &k_cob_tpdo1;
    t[n] = var(0x2000, 0, CO_TYPE_INTEGER8, CO_OD_RW | CO_OD_NODEID, 1, &v->i8);
    t[n++].dflt = &k_i8_base;
    t[n] = var(0x2001, 0, CO_TYPE_REAL32, CO_OD_RW | CO_OD_NODEID, 4, &v->real);
    t[n++].dflt = &k_real;
    t[n] = var(0x2002, 0, CO_TYPE_VISIBLE_STRING, CO_OD_RW, 8, v->name);
    t[n++].dflt = k_name;
    t[n] = var(0x2003, 0, CO_TYPE_DOMAIN, CO_OD_RW, 8, &v->dom);
    t[n++].dflt = &k_domain;
    t[n] = var(0x2004, 0, CO_TYPE_BOOLEAN, CO_OD_RW, 1, &v->flag);
    t[n++].dflt = &k_bool;
    t[n] = var(0x2005, 0, CO_TYPE_INTEGER40, CO_OD_RW | CO_OD_NODEID, 5, &v->i40);
    t[n++].dflt = &k_i40;
    t[n] = var(0xA000, 0, CO_TYPE_UNSIGNED32, CO_OD_RW, 4, &v->outside);
    t[n++].dflt = &k_dev_type;
    return n;
}

static void scramble(reset_vals_t *v)
{
    v->dev_type = 1;
    v->no_default = 2;
    v->cob = 3;
    v->i8 = 4;
    v->real = 5.0f;
    memcpy(v->name, "zzzzzzzz", 8);
    memset(v->dom_buf, 0xEE, sizeof v->dom_buf);
    v->dom.data = v->dom_buf;
    v->dom.len = 8;
    v->flag = 0;
    v->i40 = 6;
    v->outside = 7;
}

static void test_reset_ranges(void)
{
    reset_vals_t v;
    co_od_entry_t t[12];
    uint32_t n = reset_table(&v, t);
    co_od_t od = make_od(t, n, NULL);
    scramble(&v);
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);

    /* communication area only */
    co_od_reset(&od, 0x1000, 0x1FFF, 5);
    CHECK_EQ(v.dev_type, 0x00020192u);
    CHECK_EQ(v.no_default, 2);
    CHECK_EQ(v.cob, 0x185);
    CHECK_EQ(v.i8, 4);
    CHECK(v.real == 5.0f);
    CHECK_EQ(v.outside, 7);

    /* application area */
    co_od_reset(&od, 0x2000, 0x9FFF, 5);
    CHECK_EQ(v.i8, -5);
    CHECK(v.real == 2.5f);
    CHECK(memcmp(v.name, "canola\0\0", 8) == 0);
    CHECK_EQ(v.dom.len, 3);
    CHECK(memcmp(v.dom_buf, "\xD0\xD1\xD2", 3) == 0);
    CHECK_EQ(v.flag, 1);
    CHECK_EQ(v.i40, 4);
    CHECK_EQ(v.outside, 7);
    CHECK_EQ(v.no_default, 2);

    /* node-ID 0 leaves the default as it is; range with no entries; empty range */
    scramble(&v);
    co_od_reset(&od, 0x1801, 0x1FFF, 9);
    CHECK_EQ(v.cob, 3);
    co_od_reset(&od, 0x2000, 0x1FFF, 9);
    CHECK_EQ(v.i8, 4);
    CHECK_EQ(v.cob, 3);
    co_od_reset(&od, 0x17FF, 0x1800, 0);
    CHECK_EQ(v.cob, 0x180);
    CHECK_EQ(v.dev_type, 1);
    co_od_reset(&od, 0x0000, 0xFFFF, 127);
    CHECK_EQ(v.dev_type, 0x00020192u);
    CHECK_EQ(v.cob, 0x1FF);
    CHECK_EQ(v.outside, 0x00020192u);
    CHECK_EQ(v.no_default, 2);
}

static void test_reset_example(void)
{
    static example_od_t x;
    co_od_t od = example_od_init(&x, 1500);
    CHECK_EQ(x.device_type, 0x191);
    CHECK_EQ(x.app_u32, 0x12345678u);
    CHECK_STR(x.app_string, "hello");
    CHECK_STR(x.device_name, "canola example");
    CHECK_EQ(x.hb_period_ms, 1500);
    CHECK_EQ(x.hb_consumer_count, EXAMPLE_HB_CONSUMERS);
    CHECK_EQ(x.identity[0], 0xCA0);

    x.app_u32 = 1;
    x.hb_period_ms = 200;
    x.guard_time_ms = 99;
    co_od_reset(&od, 0x2000, 0x9FFF, 3);
    CHECK_EQ(x.app_u32, 0x12345678u);
    CHECK_EQ(x.guard_time_ms, 99);
    co_od_reset(&od, 0x1000, 0x1FFF, 3);
    CHECK_EQ(x.guard_time_ms, 0);
    /* 0x1017: back to its default if it has one, kept otherwise */
    const co_od_entry_t *hb = co_od_find(&od, 0x1017, 0, NULL);
    CHECK(hb != NULL);
    uint16_t expect = (hb && hb->dflt) ? *(const uint16_t *)hb->dflt : 200;
    CHECK_EQ(x.hb_period_ms, expect);
}

/* ---- Native integer access. */

static void test_get_set_uint(void)
{
    uint16_t u16 = 0x1234;
    int8_t i8 = -1;
    int32_t i24 = 0;
    uint8_t u8 = 0;
    uint8_t flag = 0;
    float f = 1.0f;
    char s[4] = "abc";
    int64_t i40 = 0;
    co_od_entry_t t[] = {
        var(0x2000, 0, CO_TYPE_UNSIGNED16, CO_OD_RW, 2, &u16),
        var(0x2001, 0, CO_TYPE_INTEGER8, CO_OD_RW, 1, &i8),
        var(0x2002, 0, CO_TYPE_INTEGER24, CO_OD_RW, 3, &i24),
        var(0x2003, 0, CO_TYPE_UNSIGNED8, CO_OD_RW, 1, &u8),
        var(0x2004, 0, CO_TYPE_BOOLEAN, CO_OD_RW, 1, &flag),
        var(0x2005, 0, CO_TYPE_REAL32, CO_OD_RW, 4, &f),
        var(0x2006, 0, CO_TYPE_VISIBLE_STRING, CO_OD_RW, 4, s),
        var(0x2007, 0, CO_TYPE_INTEGER40, CO_OD_RW, 5, &i40),
    };
    co_od_t od = make_od(t, COUNT(t), NULL);
    uint64_t v = 0;
    CHECK_EQ(co_od_get_uint(&od, 0x2000, 0, &v), CO_OK);
    CHECK_EQ(v, 0x1234);
    CHECK_EQ(co_od_set_uint(&od, 0x2000, 0, 0xABCDEF), CO_OK);
    CHECK_EQ(u16, 0xCDEF);
    CHECK_EQ(co_od_get_uint(&od, 0x2001, 0, &v), CO_OK);
    CHECK_EQ(v, UINT64_MAX);
    CHECK_EQ(co_od_set_uint(&od, 0x2001, 0, (uint64_t)-100), CO_OK);
    CHECK_EQ(i8, -100);
    CHECK_EQ(co_od_set_uint(&od, 0x2002, 0, (uint64_t)-7), CO_OK);
    CHECK_EQ(i24, -7);
    CHECK_EQ(co_od_entry_uint(&od, &t[2]), (uint64_t)-7);
    CHECK_EQ(co_od_set_uint(&od, 0x2003, 0, 0x1FF), CO_OK);
    CHECK_EQ(u8, 0xFF);
    CHECK_EQ(co_od_set_uint(&od, 0x2004, 0, 1), CO_OK);
    CHECK_EQ(flag, 1);
    CHECK_EQ(co_od_get_uint(&od, 0x2004, 0, &v), CO_OK);
    CHECK_EQ(v, 1);
    i40 = -((int64_t)1 << 39);
    CHECK_EQ(co_od_entry_uint(&od, &t[7]), (uint64_t)i40);

    v = 77;
    CHECK_EQ(co_od_get_uint(&od, 0x2005, 0, &v), CO_ERR_ARG);
    CHECK_EQ(co_od_set_uint(&od, 0x2005, 0, 1), CO_ERR_ARG);
    CHECK(f == 1.0f);
    CHECK_EQ(co_od_get_uint(&od, 0x2006, 0, &v), CO_ERR_ARG);
    CHECK_EQ(v, 77);
    CHECK_EQ(co_od_get_uint(&od, 0x2008, 0, &v), CO_ERR_NOT_FOUND);
    CHECK_EQ(co_od_set_uint(&od, 0x2000, 1, 0), CO_ERR_NOT_FOUND);
    CHECK_EQ(co_od_entry_uint(&od, &t[5]), 0);
    CHECK_EQ(co_od_entry_uint(&od, &t[6]), 0);

    static example_od_t x;
    co_od_t ex = example_od_init(&x, 250);
    CHECK_EQ(co_od_get_uint(&ex, 0x1017, 0, &v), CO_OK);
    CHECK_EQ(v, 250);
    CHECK_EQ(co_od_set_uint(&ex, 0x1016, 2, 0x00050064), CO_OK);
    CHECK_EQ(x.hb_consumer[1], 0x00050064u);
}

/* ---- the dense key array (co_od_t.keys): the same look-ups, and validated */

static void test_key_array_lookups(void)
{
    static example_od_t x;
    co_od_t plain = example_od_init(&x, 0);
    static uint32_t keys[512];
    CHECK(plain.count <= 512);
    for (uint32_t i = 0; i < plain.count; i++) {
        keys[i] = CO_OD_KEY(plain.entries[i].index, plain.entries[i].sub);
    }
    co_od_t keyed = plain;
    keyed.keys = keys;
    uint32_t bad = 0xFFFF;
    CHECK_EQ(co_od_validate(&keyed, &bad), CO_OK);
    CHECK_EQ(bad, 0xFFFF);
    /* Every entry is found, and it is the same entry either way. */
    for (uint32_t i = 0; i < plain.count; i++) {
        const co_od_entry_t *e = &plain.entries[i];
        co_abort_t abort = 1;
        CHECK(co_od_find(&keyed, e->index, e->sub, &abort) == e);
        CHECK(co_od_find(&plain, e->index, e->sub, NULL) == e);
    }
    /* What is not there: before the first, an unknown sub-index, between, after the last. */
    co_abort_t abort = 0;
    CHECK(co_od_find(&keyed, 0x0001, 0, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_OBJECT);
    CHECK(co_od_find(&keyed, 0x1000, 1, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_SUB);
    CHECK(co_od_find(&keyed, 0x1002, 0, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_OBJECT);
    CHECK(co_od_find(&keyed, 0xFFFF, 0xFF, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_OBJECT);
    /* One entry, and none. */
    co_od_t one = keyed;
    one.count = 1;
    CHECK(co_od_find(&one, plain.entries[0].index, plain.entries[0].sub, NULL) ==
          &plain.entries[0]);
    CHECK(co_od_find(&one, 0xFFFF, 0, &abort) == NULL);
    one.count = 0;
    CHECK(co_od_find(&one, plain.entries[0].index, plain.entries[0].sub, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_OBJECT);
    /* A key that is not its entry's: the table is refused, at that entry. */
    keys[5] ^= 1u;
    bad = 5;
    CHECK_EQ(co_od_validate(&keyed, &bad), CO_ERR_CONFIG);
    CHECK_EQ(bad, 5);
    keys[5] ^= 1u;
    CHECK_EQ(co_od_validate(&keyed, NULL), CO_OK);
}

/* ---- the hash (co_od_t.hash): every key found, misses told apart, bad tables refused */

/* Misses through the hash give the binary search's abort codes. */
static void check_misses(const co_od_t *od)
{
    co_abort_t abort = 0;
    CHECK(co_od_find(od, 0x0001, 0, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_OBJECT);
    CHECK(co_od_find(od, 0x1000, 1, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_SUB);
    CHECK(co_od_find(od, 0x1002, 0, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_OBJECT);
    CHECK(co_od_find(od, 0xFFFF, 0xFF, &abort) == NULL);
    CHECK_EQ(abort, CO_ABORT_NO_OBJECT);
    CHECK(co_od_find(od, 0x1018, 0x7F, NULL) == NULL);
}

static void check_all_found(const co_od_t *od, const co_od_entry_t *entries)
{
    for (uint32_t i = 0; i < od->count; i++) {
        CHECK(co_od_find(od, entries[i].index, entries[i].sub, NULL) == &entries[i]);
    }
}

static void test_hash_lookups(void)
{
    static example_od_t x;
    co_od_t od = example_od_keyed(&x, example_od_init(&x, 0));
    CHECK(od.hash == x.hash);
    CHECK_EQ(od.hash_mask, 511); /* 172 entries: 512 slots */
    CHECK_EQ(co_od_validate(&od, NULL), CO_OK);
    check_all_found(&od, od.entries);
    check_misses(&od);
    /* Fuller (172 entries in 256 slots): longer probe runs, still exact. */
    static uint16_t slots[256];
    co_od_t full = od;
    CHECK_EQ(co_od_hash_build(&full, slots, 8), CO_OK);
    CHECK(full.hash == slots);
    CHECK_EQ(full.hash_mask, 255);
    CHECK_EQ(co_od_validate(&full, NULL), CO_OK);
    check_all_found(&full, od.entries);
    check_misses(&full);
    /* As full as a hash may be: 7 entries in 8 slots, probes wrapping around the end. */
    static uint16_t eight[8];
    co_od_t seven = od;
    seven.count = 7;
    CHECK_EQ(co_od_hash_build(&seven, eight, 3), CO_OK);
    CHECK_EQ(co_od_validate(&seven, NULL), CO_OK);
    check_all_found(&seven, od.entries);
    check_misses(&seven);
    co_od_t before = seven;
    CHECK_EQ(co_od_hash_build(&seven, slots, 2), CO_ERR_ARG); /* 4 slots for 7 */
    CHECK(seven.hash == before.hash && seven.hash_mask == before.hash_mask);
}

static void test_hash_refused(void)
{
    static example_od_t x;
    co_od_t od = example_od_keyed(&x, example_od_init(&x, 0));
    uint32_t bad = 0;
    /* The builder: no keys, too few slots, bits out of range. */
    static uint16_t slots[512];
    static example_od_t y; /* example_od_init clears x's keys and hash too */
    co_od_t unkeyed = example_od_init(&y, 0);
    CHECK(unkeyed.keys == NULL && unkeyed.hash == NULL);
    CHECK_EQ(co_od_hash_build(&unkeyed, slots, 9), CO_ERR_ARG);
    co_od_t copy = od;
    CHECK_EQ(co_od_hash_build(&copy, slots, 7), CO_ERR_ARG); /* 128 slots, 172 entries */
    CHECK_EQ(co_od_hash_build(&copy, slots, 0), CO_ERR_ARG);
    CHECK_EQ(co_od_hash_build(&copy, slots, 17), CO_ERR_ARG);
    CHECK_EQ(co_od_hash_build(NULL, slots, 9), CO_ERR_ARG);
    CHECK_EQ(co_od_hash_build(&copy, NULL, 9), CO_ERR_ARG);
    CHECK_EQ(co_od_hash_bits(0), 1);
    CHECK_EQ(co_od_hash_bits(1), 1);
    CHECK_EQ(co_od_hash_bits(2), 2);
    CHECK_EQ(co_od_hash_bits(190), 9);
    CHECK_EQ(co_od_hash_bits(256), 9);
    CHECK_EQ(co_od_hash_bits(257), 10);
    CHECK_EQ(co_od_hash_bits(32767), 16);
    CHECK_EQ(co_od_hash_bits(32768), 0);
    /* Validation: a hash without keys, a mask that is not 2^bits - 1, a slot past the
     * entries, no empty slot, an entry its probe does not reach. `bad` names count: the
     * entries are fine. */
    co_od_t h = unkeyed;
    h.hash = od.hash;
    h.hash_mask = od.hash_mask;
    bad = od.count;
    CHECK_EQ(co_od_validate(&h, &bad), BAD_HASH);
    CHECK_EQ(bad, od.count);
    h = od;
    h.hash_mask = 0; /* one slot */
    CHECK_EQ(co_od_validate(&h, NULL), BAD_HASH);
    h.hash_mask = 500;
    CHECK_EQ(co_od_validate(&h, NULL), BAD_HASH);
    h = od;
    CHECK_EQ(co_od_hash_build(&h, slots, 9), CO_OK);
    uint32_t empty = 0;
    while (slots[empty] != 0) {
        empty++;
    }
    slots[empty] = (uint16_t)(od.count + 1u); /* past the last entry */
    CHECK_EQ(co_od_validate(&h, NULL), BAD_HASH);
    for (uint32_t i = 0; i < 512; i++) {
        slots[i] = slots[i] ? slots[i] : 1; /* every slot taken */
    }
    CHECK_EQ(co_od_validate(&h, NULL), BAD_HASH);
    CHECK_EQ(co_od_hash_build(&h, slots, 9), CO_OK);
    uint32_t at = CO_OD_HASH_HOME(od.keys[0], 511u);
    while (slots[at] != 1) {
        at = (at + 1u) & 511u;
    }
    slots[at] = 0; /* entry 0 lost: found by nothing */
    CHECK_EQ(co_od_validate(&h, NULL), BAD_HASH);
    /* A look-up through the (refused) hash misses it; a core without CO_CONFIG_OD_HASH
     * searches the entries, and finds it. */
    const co_od_entry_t *lost = co_od_find(&h, od.entries[0].index, od.entries[0].sub, NULL);
    CHECK(lost == (CO_CONFIG_OD_HASH ? NULL : &od.entries[0]));
    CHECK_EQ(co_od_hash_build(&h, slots, 9), CO_OK);
    CHECK_EQ(co_od_validate(&h, NULL), CO_OK);
}

int main(void)
{
    RUN(test_type_size);
    RUN(test_validate_example);
    RUN(test_validate_order);
    RUN(test_validate_entries);
    RUN(test_find_example);
    RUN(test_find_large);
    RUN(test_round_trip_small_ints);
    RUN(test_round_trip_32);
    RUN(test_round_trip_64);
    RUN(test_round_trip_real);
    RUN(test_round_trip_time);
    RUN(test_read_pieces);
    RUN(test_length_fixed);
    RUN(test_length_variable);
    RUN(test_visible_string);
    RUN(test_octet_string);
    RUN(test_unicode_string);
    RUN(test_domain_storage);
    RUN(test_boolean_value);
    RUN(test_limits_signed);
    RUN(test_limits_unsigned);
    RUN(test_limits_real);
    RUN(test_example_limits);
    RUN(test_access);
    RUN(test_access_not_checked_locally);
    RUN(test_hook_read);
    RUN(test_hook_check_and_written);
    RUN(test_hook_store_without_storage);
    RUN(test_stream_domain);
    RUN(test_read_long_in_pieces);
    RUN(test_reset_ranges);
    RUN(test_reset_example);
    RUN(test_get_set_uint);
    RUN(test_key_array_lookups);
    RUN(test_hash_lookups);
    RUN(test_hash_refused);
    return check_summary();
}
