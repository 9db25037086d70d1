/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_cm_bit_timing.c -- bit timing from a clock and a CiA 301 rate (cm_bit_timing.c), on
 * the clocks STM32 CAN controllers run at, with the bxCAN's and the FDCAN's limits: exact
 * rates only, the sample point CiA 102 asks (87.5 %, 80 % at 800 k, 75 % at 1 M) within
 * one quantum, every field within its register's range.
 */
#include "canola/cm_bit_timing.h"
#include "check.h"

static const co_cm_bit_limits_t k_bxcan = {1024, 1, 16, 1, 8, 4};
static const co_cm_bit_limits_t k_fdcan = {512, 2, 256, 1, 128, 128};
static const uint32_t k_rates[] = {10000, 20000, 50000, 125000, 250000, 500000, 800000, 1000000};

static void check_timing(uint32_t clock, uint32_t rate, const co_cm_bit_limits_t *lim,
                         const co_cm_bit_timing_t *t)
{
    uint32_t quanta = 1u + t->tseg1 + t->tseg2;
    CHECK_EQ((uint64_t)t->brp * quanta * rate, clock); /* exact */
    CHECK(t->brp >= 1 && t->brp <= lim->brp_max);
    CHECK(t->tseg1 >= lim->tseg1_min && t->tseg1 <= lim->tseg1_max);
    CHECK(t->tseg2 >= lim->tseg2_min && t->tseg2 <= lim->tseg2_max);
    CHECK(t->sjw >= 1 && t->sjw <= t->tseg2 && t->sjw <= lim->sjw_max);
    /* the sample point within one quantum (and 2.5 %) of CiA 102's */
    uint32_t sp = (1u + t->tseg1) * 1000u / quanta;
    uint32_t want = co_cm_sample_point_permille(rate);
    uint32_t off = sp > want ? sp - want : want - sp;
    CHECK(off * quanta <= 1000u);
    CHECK(off <= 25u);
}

static void test_sample_points(void)
{
    CHECK_EQ(co_cm_sample_point_permille(1000000), 750);
    CHECK_EQ(co_cm_sample_point_permille(800000), 800);
    CHECK_EQ(co_cm_sample_point_permille(500000), 875);
    CHECK_EQ(co_cm_sample_point_permille(10000), 875);
}

/* bxCAN: F0 48 MHz, F1 36 MHz, F3 36 MHz, F4 42 and 45 MHz, L4 80 MHz, a 16 MHz part. */
static void test_bxcan_clocks(void)
{
    const uint32_t clocks[] = {16000000, 36000000, 42000000, 45000000, 48000000, 80000000};
    uint32_t refused = 0;
    for (uint32_t c = 0; c < 6; c++) {
        for (uint32_t r = 0; r < 8; r++) {
            co_cm_bit_timing_t t = {0};
            co_err_t err = co_cm_bit_timing(clocks[c], k_rates[r], &k_bxcan, &t);
            if (err == CO_OK) {
                check_timing(clocks[c], k_rates[r], &k_bxcan, &t);
            } else {
                CHECK_EQ(err, CO_ERR_ARG);
                CHECK_EQ(t.brp, 0); /* untouched */
                refused++;
                CHECK_EQ(k_rates[r], 800000); /* 42 and 45 MHz: 52.5 and 56.25 clocks a bit */
            }
        }
    }
    CHECK_EQ(refused, 2);
}

/* FDCAN: G4 at 80, 160 and 170 MHz, G0 at 64 MHz, H7-class 40 MHz, a 24 MHz crystal. */
static void test_fdcan_clocks(void)
{
    const uint32_t clocks[] = {24000000, 40000000, 64000000, 80000000, 160000000, 170000000};
    for (uint32_t c = 0; c < 6; c++) {
        for (uint32_t r = 0; r < 8; r++) {
            co_cm_bit_timing_t t = {0};
            co_err_t err = co_cm_bit_timing(clocks[c], k_rates[r], &k_fdcan, &t);
            if (clocks[c] == 170000000 && k_rates[r] == 800000) {
                CHECK_EQ(err, CO_ERR_ARG); /* 212.5 clocks a bit */
            } else if (err == CO_OK) {
                check_timing(clocks[c], k_rates[r], &k_fdcan, &t);
            } else {
                CHECK_EQ(err, CO_OK);
            }
        }
    }
}

static void test_nonsense_is_refused(void)
{
    co_cm_bit_timing_t t = {0};
    CHECK_EQ(co_cm_bit_timing(0, 500000, &k_bxcan, &t), CO_ERR_ARG);
    CHECK_EQ(co_cm_bit_timing(48000000, 0, &k_bxcan, &t), CO_ERR_ARG);
    CHECK_EQ(co_cm_bit_timing(48000000, 48000001, &k_bxcan, &t), CO_ERR_ARG);
    CHECK_EQ(co_cm_bit_timing(1000000, 1000000, &k_bxcan, &t), CO_ERR_ARG); /* 1 quantum */
    CHECK_EQ(t.brp, 0);
}

/* A known answer: 48 MHz, 500 kbit/s on bxCAN: 96 clocks a bit; 24 quanta would need a time
 * segment 1 of 20 (bxCAN: at most 16), so 16 quanta of 6: 1 + 13 + 2, 87.5 % exactly. */
static void test_known_answer(void)
{
    co_cm_bit_timing_t t = {0};
    CHECK_EQ(co_cm_bit_timing(48000000, 500000, &k_bxcan, &t), CO_OK);
    CHECK_EQ(t.brp, 6);
    CHECK_EQ(t.tseg1, 13);
    CHECK_EQ(t.tseg2, 2);
    CHECK_EQ(t.sjw, 2);
}

int main(void)
{
    RUN(test_sample_points);
    RUN(test_bxcan_clocks);
    RUN(test_fdcan_clocks);
    RUN(test_nonsense_is_refused);
    RUN(test_known_answer);
    return check_summary();
}
