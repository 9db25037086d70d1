/* SPDX-License-Identifier: Apache-2.0 */
/* port/stm32/bxcan.c -- the STM32 bxCAN driver; see canola/stm32_bxcan.h. */
#include "canola/stm32_bxcan.h"

#include "canola/cm_bit_timing.h"
#include "canola/stm32_reg.h"

/* MCR, MSR */
#define MCR_INRQ (1u << 0)
#define MCR_TXFP (1u << 2)
#define MCR_ABOM (1u << 6)
#define MSR_INAK (1u << 0)
#define MSR_ERRI (1u << 2)
/* TSR: per mailbox n, RQCPn at 8n (written 1 it clears TXOK, ALST and TERR too); TMEn */
#define TSR_RQCP_ALL 0x00010101u
#define TSR_TME_SHIFT 26
/* RF0R */
#define RF0R_FMP 3u
#define RF0R_FULL (1u << 3)
#define RF0R_FOVR (1u << 4)
#define RF0R_RFOM (1u << 5)
/* IER */
#define IER_TMEIE (1u << 0)
#define IER_FMPIE0 (1u << 1)
#define IER_FOVIE0 (1u << 3)
#define IER_EWGIE (1u << 8)
#define IER_EPVIE (1u << 9)
#define IER_BOFIE (1u << 10)
#define IER_ERRIE (1u << 15)
/* ESR */
#define ESR_EWGF (1u << 0)
#define ESR_EPVF (1u << 1)
#define ESR_BOFF (1u << 2)
/* TIxR / RIxR */
#define IR_TXRQ (1u << 0)
#define IR_RTR (1u << 1)
#define IR_IDE (1u << 2)
#define IR_ID_MASK 0xFFFFFFFCu /* identifier and IDE: what makes two frames "the same" */
/* FMR */
#define FMR_FINIT (1u << 0)
/* A filter in 16-bit scale: STID[15:5] RTR 4 IDE 3 EXID[17:15] 2:0; the mask takes STID and
 * IDE (an 11-bit frame), not RTR (data and remote frames alike). */
#define F16_IDE (1u << 3)
#define F16_MASK (0x7FFu << 5 | F16_IDE)
#define F32_MASK (0x1FFFFFFFu << 3 | IR_IDE)

static const co_cm_bit_limits_t k_limits = {
    .brp_max = 1024, .tseg1_min = 1, .tseg1_max = 16, .tseg2_min = 1, .tseg2_max = 8, .sjw_max = 4};

static uint32_t rd(const volatile uint32_t *reg) { return co_stm32_read(reg); }
static void wr(volatile uint32_t *reg, uint32_t value) { co_stm32_write(reg, value); }

/* Wait until (MSR & INAK) is `inak`: true when it came. */
static bool wait_inak(co_bxcan_regs_t *r, bool inak)
{
    for (uint32_t n = 0; n < CO_STM32_WAIT_READS; n++) {
        if (((rd(&r->msr) & MSR_INAK) != 0) == inak) {
            return true;
        }
    }
    return false;
}

static uint32_t btr_of(const co_cm_bit_timing_t *t)
{
    return (uint32_t)(t->sjw - 1u) << 24 | (uint32_t)(t->tseg2 - 1u) << 20 |
           (uint32_t)(t->tseg1 - 1u) << 16 | (uint32_t)(t->brp - 1u);
}

static uint32_t mcr_running(const co_bxcan_t *drv)
{
    uint32_t mcr = drv->cfg.request_order ? MCR_TXFP : 0u;
#if !defined(CO_TEST_FAULT_NO_RECOVERY) /* test-only: the controller stays bus-off */
    mcr |= MCR_ABOM;
#endif
    return mcr;
}

/* ---- Transmit (the port's critical section held). */

static uint32_t ir_of(const co_frame_t *frame)
{
    uint32_t ir = (frame->flags & CO_FRAME_EXT) ? (frame->id << 3 | IR_IDE) : frame->id << 21;
    return (frame->flags & CO_FRAME_RTR) ? (ir | IR_RTR) : ir;
}

static bool bx_mailbox_put(void *hw, const co_frame_t *frame)
{
    co_bxcan_t *drv = hw;
    co_bxcan_regs_t *r = drv->cfg.regs;
    uint32_t empty = rd(&r->tsr) >> TSR_TME_SHIFT & 7u;
    if (empty == 0) {
        return false;
    }
    uint32_t ir = ir_of(frame);
    for (uint32_t i = 0; !drv->cfg.request_order && i < 3; i++) {
        if (!(empty & (1u << i)) && (rd(&r->tx[i].ir) & IR_ID_MASK) == (ir & IR_ID_MASK)) {
            return false; /* its predecessor has not left: it would go by mailbox number */
        }
    }
    co_bxcan_mailbox_t *box = &r->tx[(empty & 1u) ? 0 : (empty & 2u) ? 1 : 2];
    wr(&box->dtr, frame->len > 8 ? 8u : frame->len);
    wr(&box->dlr, co_stm32_data_word(frame, 0));
    wr(&box->dhr, co_stm32_data_word(frame, 4));
    wr(&box->ir, ir | IR_TXRQ);
    return true;
}

/* ---- Filters, bit rate, counters (main loop). */

static void bank_set(co_bxcan_regs_t *f, uint32_t bank, bool wide, uint32_t fr1, uint32_t fr2)
{
    uint32_t bit = 1u << bank;
    wr(&f->fs1r, wide ? (rd(&f->fs1r) | bit) : (rd(&f->fs1r) & ~bit));
    wr(&f->fm1r, rd(&f->fm1r) & ~bit);   /* mask mode */
    wr(&f->ffa1r, rd(&f->ffa1r) & ~bit); /* FIFO 0 */
    wr(&f->bank[bank].fr1, fr1);
    wr(&f->bank[bank].fr2, fr2);
}

static uint32_t f16_of(uint32_t id) { return (id & 0x7FFu) << 5 | F16_MASK << 16; }

/* Fill the banks from bank_first: the 11-bit identifiers two a bank, then the 29-bit one a
 * bank. Returns the banks used, or 0 when they need more than the range has. */
static uint32_t fill_banks(co_bxcan_t *drv, const uint32_t *ids, size_t n)
{
    size_t std = 0;
    for (size_t i = 0; i < n; i++) {
        std += !(ids[i] & 0x80000000u);
    }
    if ((std + 1u) / 2u + (n - std) > drv->cfg.bank_count) {
        return 0;
    }
    co_bxcan_regs_t *f = drv->cfg.filters;
    uint32_t bank = drv->cfg.bank_first;
    uint32_t pending = 0; /* an 11-bit identifier waiting for its bank's second filter */
    bool half = false;
    for (size_t i = 0; i < n; i++) {
        uint32_t id = ids[i] & 0x1FFFFFFFu;
        if (ids[i] & 0x80000000u) {
            bank_set(f, bank++, true, id << 3 | IR_IDE, F32_MASK);
        } else if (half) {
            bank_set(f, bank++, false, f16_of(pending), f16_of(id));
            half = false;
        } else {
            pending = id;
            half = true;
        }
    }
    if (half) { /* an odd one: its bank's second filter repeats it */
        bank_set(f, bank++, false, f16_of(pending), f16_of(pending));
    }
    return bank - drv->cfg.bank_first;
}

static bool bx_set_filters(void *hw, const uint32_t *ids, size_t n)
{
    co_bxcan_t *drv = hw;
    co_bxcan_regs_t *f = drv->cfg.filters;
    uint32_t range = ((1u << drv->cfg.bank_count) - 1u) << drv->cfg.bank_first;
    wr(&f->fmr, rd(&f->fmr) | FMR_FINIT);
    wr(&f->fa1r, rd(&f->fa1r) & ~range);
    uint32_t used = ids ? fill_banks(drv, ids, n) : 0u;
    bool fits = ids != NULL && (used > 0 || n == 0);
    if (!fits) { /* accept-all: one bank, 32-bit mask 0 */
        bank_set(f, drv->cfg.bank_first, true, 0, 0);
        used = 1;
    }
    wr(&f->fa1r, rd(&f->fa1r) | (((1u << used) - 1u) << drv->cfg.bank_first));
    wr(&f->fmr, rd(&f->fmr) & ~FMR_FINIT);
    return fits || ids == NULL;
}

static co_err_t set_timing(co_bxcan_t *drv, uint32_t bit_rate)
{
    co_cm_bit_timing_t t;
    if (co_cm_bit_timing(drv->cfg.clock_hz, bit_rate, &k_limits, &t) != CO_OK) {
        return CO_ERR_ARG;
    }
    co_bxcan_regs_t *r = drv->cfg.regs;
    wr(&r->mcr, mcr_running(drv) | MCR_INRQ);
    if (!wait_inak(r, true)) {
        return CO_ERR_STATE;
    }
    wr(&r->btr, btr_of(&t));
    drv->cfg.bit_rate = bit_rate;
    wr(&r->mcr, mcr_running(drv));
    return wait_inak(r, false) ? CO_OK : CO_ERR_STATE;
}

static co_err_t bx_set_bit_rate(void *hw, uint32_t bit_rate) { return set_timing(hw, bit_rate); }

static void bx_error_counters(void *hw, uint8_t *tec, uint8_t *rec)
{
    uint32_t esr = rd(&((co_bxcan_t *)hw)->cfg.regs->esr);
    *tec = (uint8_t)(esr >> 16);
    *rec = (uint8_t)(esr >> 24);
}

const co_cm_can_ops_t co_bxcan_ops = {bx_mailbox_put, bx_set_filters, bx_set_bit_rate,
                                      bx_error_counters};

co_err_t co_bxcan_init(co_bxcan_t *drv, const co_bxcan_config_t *cfg)
{
    co_cm_bit_timing_t t;
    if (!drv || !cfg || !cfg->regs || cfg->bank_count == 0 ||
        cfg->bank_first + cfg->bank_count > 28u ||
        co_cm_bit_timing(cfg->clock_hz, cfg->bit_rate, &k_limits, &t) != CO_OK) {
        return CO_ERR_ARG;
    }
    drv->cfg = *cfg;
    drv->cfg.filters = cfg->filters ? cfg->filters : cfg->regs;
    drv->state = CO_CM_CAN_ERROR_ACTIVE;
    co_bxcan_regs_t *r = drv->cfg.regs;
    wr(&r->mcr, MCR_INRQ); /* out of sleep, into initialisation */
    if (!wait_inak(r, true)) {
        return CO_ERR_STATE;
    }
    wr(&r->mcr, mcr_running(drv) | MCR_INRQ);
    wr(&r->btr, btr_of(&t));
    (void)bx_set_filters(drv, NULL, 0);
    wr(&r->ier,
       IER_TMEIE | IER_FMPIE0 | IER_FOVIE0 | IER_EWGIE | IER_EPVIE | IER_BOFIE | IER_ERRIE);
    wr(&r->mcr, mcr_running(drv));
    return wait_inak(r, false) ? CO_OK : CO_ERR_STATE;
}

/* ---- Interrupts. */

/* Tell the port the error state when it changed since the last time. */
static void report_state(co_bxcan_t *drv)
{
    uint32_t esr = rd(&drv->cfg.regs->esr);
    co_cm_can_state_t state = (esr & ESR_BOFF)   ? CO_CM_CAN_BUS_OFF
                              : (esr & ESR_EPVF) ? CO_CM_CAN_ERROR_PASSIVE
                              : (esr & ESR_EWGF) ? CO_CM_CAN_ERROR_WARNING
                                                 : CO_CM_CAN_ERROR_ACTIVE;
    if (state != drv->state) {
        drv->state = state;
        co_cm_isr_bus_state(drv->cfg.port, state);
    }
}

void co_bxcan_isr_tx(co_bxcan_t *drv)
{
    co_bxcan_regs_t *r = drv->cfg.regs;
    uint32_t done = rd(&r->tsr) & TSR_RQCP_ALL;
    if (done) {
        wr(&r->tsr, done);
    }
    report_state(drv); /* back from bus-off or passive: the first frame out says so */
    if (done) {
        co_cm_isr_tx_done(drv->cfg.port);
    }
}

static co_frame_t read_fifo0(co_bxcan_regs_t *r)
{
    uint32_t ir = rd(&r->rx[0].ir);
    uint32_t dlc = rd(&r->rx[0].dtr) & 0xFu;
    uint32_t lo = rd(&r->rx[0].dlr);
    uint32_t hi = rd(&r->rx[0].dhr);
    co_frame_t frame = {.id = (ir & IR_IDE) ? ir >> 3 : ir >> 21,
                        .flags = (uint8_t)(((ir & IR_IDE) ? CO_FRAME_EXT : 0u) |
                                           ((ir & IR_RTR) ? CO_FRAME_RTR : 0u)),
                        .len = (uint8_t)(dlc > 8 ? 8 : dlc)};
    co_stm32_data_set(&frame, lo, hi);
    wr(&r->rf0r, RF0R_RFOM); /* release the output: the next frame moves up */
    return frame;
}

void co_bxcan_isr_rx0(co_bxcan_t *drv)
{
    co_bxcan_regs_t *r = drv->cfg.regs;
    for (uint32_t n = 0; n < 3 && (rd(&r->rf0r) & RF0R_FMP); n++) {
        co_frame_t frame = read_fifo0(r);
        co_cm_isr_rx(drv->cfg.port, &frame);
    }
#if !defined(CO_TEST_FAULT_NO_OVERRUN) /* test-only: the overrun flag left set, unreported */
    uint32_t flags = rd(&r->rf0r) & (RF0R_FULL | RF0R_FOVR);
    if (flags) {
        wr(&r->rf0r, flags);
    }
    if (flags & RF0R_FOVR) {
        co_cm_isr_rx_overrun(drv->cfg.port);
    }
#endif
    report_state(drv);
}

void co_bxcan_isr_sce(co_bxcan_t *drv)
{
    wr(&drv->cfg.regs->msr, MSR_ERRI);
    report_state(drv);
}

void co_bxcan_isr(co_bxcan_t *drv)
{
    co_bxcan_isr_rx0(drv);
    co_bxcan_isr_tx(drv);
    co_bxcan_isr_sce(drv);
}
