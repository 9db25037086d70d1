/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/cm_bit_timing.h -- CAN bit timing from the controller's clock and a bit rate, for
 * any controller whose bit is a prescaler times a number of time quanta: sync segment (1),
 * time segment 1 (propagation + phase 1), time segment 2 (phase 2).
 *
 * The sample point follows CiA 102 (what CiA 301's bit rates assume): 87.5 % up to
 * 500 kbit/s, 80 % at 800 kbit/s, 75 % at 1 Mbit/s. Only exact bit rates are taken (clock
 * = rate x prescaler x quanta): a clock the rate does not divide is refused, not
 * approximated. Of the exact timings the one whose sample point is nearest the target
 * wins, then the one with more quanta (a finer sample point, a wider resynchronisation).
 * The resynchronisation jump width is time segment 2, at most the controller's maximum.
 *
 * Threading: none. Memory: none. Cost: O(quanta range) divisions, at start-up and at a bit
 * rate switch (LSS).
 */
#ifndef CANOLA_CM_BIT_TIMING_H
#define CANOLA_CM_BIT_TIMING_H

#include <stdint.h>

#include "canola/types.h"

/** What a controller's bit timing register can hold (all in time quanta but brp). */
typedef struct co_cm_bit_limits {
    uint16_t brp_max;   /**< prescaler 1..brp_max */
    uint16_t tseg1_min; /**< time segment 1 */
    uint16_t tseg1_max;
    uint8_t tseg2_min; /**< time segment 2 */
    uint8_t tseg2_max;
    uint8_t sjw_max; /**< resynchronisation jump width 1..sjw_max */
} co_cm_bit_limits_t;

/** One bit timing. bit rate = clock / (brp * (1 + tseg1 + tseg2)). */
typedef struct co_cm_bit_timing {
    uint16_t brp;
    uint16_t tseg1;
    uint8_t tseg2;
    uint8_t sjw;
} co_cm_bit_timing_t;

/** The sample point CiA 102 asks of `bit_rate`, in tenths of a percent (875, 800, 750). */
uint16_t co_cm_sample_point_permille(uint32_t bit_rate);

/** The bit timing of `bit_rate` from `clock_hz` within `limits` into `out`. Returns CO_OK,
 *  or CO_ERR_ARG when no exact timing fits (a zero rate or clock, a rate the clock does not
 *  divide within the limits); `out` is then unchanged. */
co_err_t co_cm_bit_timing(uint32_t clock_hz, uint32_t bit_rate, const co_cm_bit_limits_t *limits,
                          co_cm_bit_timing_t *out);

#endif /* CANOLA_CM_BIT_TIMING_H */
