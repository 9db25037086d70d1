/* SPDX-License-Identifier: Apache-2.0 */
/* port/cortex-m/cm_bit_timing.c -- see canola/cm_bit_timing.h. */
#include "canola/cm_bit_timing.h"

uint16_t co_cm_sample_point_permille(uint32_t bit_rate)
{
    return bit_rate > 800000u ? 750u : bit_rate > 500000u ? 800u : 875u;
}

static uint32_t distance(uint32_t a, uint32_t b) { return a > b ? a - b : b - a; }

co_err_t co_cm_bit_timing(uint32_t clock_hz, uint32_t bit_rate, const co_cm_bit_limits_t *limits,
                          co_cm_bit_timing_t *out)
{
    if (clock_hz == 0 || bit_rate == 0 || clock_hz % bit_rate != 0) {
        return CO_ERR_ARG;
    }
    uint32_t per_bit = clock_hz / bit_rate; /* clock cycles in a bit: brp x quanta */
    uint32_t target = co_cm_sample_point_permille(bit_rate);
    uint32_t q_min = 1u + limits->tseg1_min + limits->tseg2_min;
    uint32_t q_max = 1u + limits->tseg1_max + limits->tseg2_max;
    uint32_t best_error = UINT32_MAX;
    for (uint32_t q = q_max; q >= q_min; q--) { /* more quanta first: they win ties */
        if (per_bit % q != 0 || per_bit / q > limits->brp_max) {
            continue;
        }
        /* The sample point is at the end of time segment 1: (1 + tseg1) / q, rounded. */
        uint32_t tseg1 = (q * target + 500u) / 1000u - 1u;
        uint32_t tseg2 = q - 1u - tseg1;
        if (tseg2 < limits->tseg2_min) {
            tseg2 = limits->tseg2_min;
        } else if (tseg2 > limits->tseg2_max) {
            tseg2 = limits->tseg2_max;
        }
        tseg1 = q - 1u - tseg2;
        if (tseg1 < limits->tseg1_min || tseg1 > limits->tseg1_max) {
            continue;
        }
        uint32_t error = distance((1u + tseg1) * 1000u, target * q) / q;
        if (error < best_error) {
            best_error = error;
            out->brp = (uint16_t)(per_bit / q);
            out->tseg1 = (uint16_t)tseg1;
            out->tseg2 = (uint8_t)tseg2;
            out->sjw = (uint8_t)(tseg2 < limits->sjw_max ? tseg2 : limits->sjw_max);
        }
    }
    return best_error == UINT32_MAX ? CO_ERR_ARG : CO_OK;
}
