/* SPDX-License-Identifier: Apache-2.0 */
/* flash_model.c -- STM32-like internal flash with power cuts; see flash_model.h. */
#include "flash_model.h"

#include <string.h>

/* Begin an operation: false when it must not change anything (no power, a failure). On
 * the cut, the caller does its partial part, then the power is gone. */
static bool op_begins(flash_model_t *m, bool *cut_now)
{
    uint32_t op = m->ops++;
    *cut_now = false;
    if (m->off || op == m->fail_at) {
        return false;
    }
    if (op == m->cut_at) {
        *cut_now = true;
        m->off = true;
    }
    return true;
}

static co_err_t erase_page(void *hw, uintptr_t addr)
{
    flash_model_t *m = hw;
    bool cut_now;
    uint32_t page = m->api.page_size;
    uint8_t *p = (uint8_t *)addr;
    if (p < m->mem || p + page > m->mem + m->size || (uint32_t)(p - m->mem) % page != 0) {
        m->misuse++;
        return CO_ERR_ARG;
    }
    if (!op_begins(m, &cut_now)) {
        return CO_ERR_STATE;
    }
    if (!cut_now) {
        memset(p, 0xFF, page);
        return CO_OK;
    }
    for (uint32_t i = 0; i < page; i++) {
        bool done = m->cut == FLASH_CUT_HALF ? i < page / 2 : m->cut == FLASH_CUT_SCATTER && i % 2;
        if (done) {
            p[i] = 0xFF;
        }
    }
    return CO_ERR_STATE;
}

static co_err_t program(void *hw, uintptr_t addr, const uint8_t *data)
{
    flash_model_t *m = hw;
    bool cut_now;
    uint8_t unit = m->api.unit;
    uint8_t *p = (uint8_t *)addr;
    if (p < m->mem || p + unit > m->mem + m->size || (uint32_t)(p - m->mem) % unit != 0) {
        m->misuse++;
        return CO_ERR_ARG;
    }
    for (uint8_t i = 0; i < unit; i++) {
        if (p[i] != 0xFF) {
            m->misuse++; /* programmed twice since the erase */
            return CO_ERR_STATE;
        }
    }
    for (unsigned s = 0; s < 2; s++) {
        if (m->slots[s] != 0 && addr == m->slots[s] + 32u && m->commits < 16) {
            m->commit_ops[m->commits++] = m->ops;
        }
    }
    if (!op_begins(m, &cut_now)) {
        return CO_ERR_STATE;
    }
    unsigned skip = 0; /* FLASH_CUT_SCATTER: every other bit to clear, the first one not */
    for (uint8_t i = 0; i < unit; i++) {
        if (!cut_now) {
            p[i] &= data[i];
        } else if (m->cut == FLASH_CUT_HALF && i < unit / 2) {
            p[i] &= data[i];
        } else if (m->cut == FLASH_CUT_SCATTER) {
            for (unsigned bit = 0; bit < 8; bit++) {
                uint8_t mask = (uint8_t)(1u << bit);
                if ((data[i] & mask) == 0 && (skip ^= 1u) == 0) {
                    p[i] &= (uint8_t)~mask;
                }
            }
        }
    }
    return cut_now ? CO_ERR_STATE : CO_OK;
}

void flash_model_init(flash_model_t *m, uint8_t *mem, uint32_t size, uint32_t page_size,
                      uint8_t unit)
{
    memset(m, 0, sizeof *m);
    memset(mem, 0xFF, size);
    m->mem = mem;
    m->size = size;
    m->api = (co_cm_flash_t){.erase_page = erase_page,
                             .program = program,
                             .hw = m,
                             .page_size = page_size,
                             .unit = unit};
    flash_power_on(m);
}

void flash_power_on(flash_model_t *m)
{
    m->off = false;
    m->cut_at = FLASH_NEVER;
    m->fail_at = FLASH_NEVER;
}
