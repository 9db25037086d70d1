/* SPDX-License-Identifier: Apache-2.0 */
/* port/stm32/fdcan.c -- the STM32 FDCAN driver (classic CAN); see canola/stm32_fdcan.h. */
#include "canola/stm32_fdcan.h"

#include "canola/cm_bit_timing.h"
#include "canola/stm32_reg.h"

/* CCCR */
#define CCCR_INIT (1u << 0)
#define CCCR_CCE (1u << 1)
/* IR / IE (G4 positions) */
#define IR_RF0N (1u << 0)
#define IR_RF0F (1u << 1)
#define IR_RF0L (1u << 2)
#define IR_TC (1u << 7)
#define IR_EP (1u << 17)
#define IR_EW (1u << 18)
#define IR_BO (1u << 19)
#define ILE_EINT0 (1u << 0)
/* PSR */
#define PSR_EP (1u << 5)
#define PSR_EW (1u << 6)
#define PSR_BO (1u << 7)
/* RXGFC: list sizes, what frames no element takes do (2: reject) */
#define RXGFC_ANFE_REJECT (2u << 2)
#define RXGFC_ANFS_REJECT (2u << 4)
#define RXGFC_LSS_SHIFT 16
#define RXGFC_LSE_SHIFT 24
/* RXF0S, TXFQS, TXBC */
#define RXF0S_FILL 0xFu
#define RXF0S_GET_SHIFT 8
#define TXFQS_FULL (1u << 21)
#define TXFQS_PUT_SHIFT 16
#define TXBC_TFQM (1u << 24)
/* Message RAM elements: word 0 of a frame element; filter elements */
#define E_XTD (1u << 30)
#define E_RTR (1u << 29)
#define E_ID_MASK (E_XTD | 0x1FFFFFFFu) /* identifier and XTD: what makes two frames "the same" */
#define SF_DUAL_FIFO0 (1u << 30 | 1u << 27) /* SFT 01 (dual ID), SFEC 001 (store in FIFO 0) */
#define EF0_FIFO0 (1u << 29)                /* EFEC 001 */
#define EF1_DUAL (1u << 30)                 /* EFT 01 */

static const co_cm_bit_limits_t k_limits = {.brp_max = 512,
                                            .tseg1_min = 2,
                                            .tseg1_max = 256,
                                            .tseg2_min = 1,
                                            .tseg2_max = 128,
                                            .sjw_max = 128};

static uint32_t rd(const volatile uint32_t *reg) { return co_stm32_read(reg); }
static void wr(volatile uint32_t *reg, uint32_t value) { co_stm32_write(reg, value); }

static volatile uint32_t *element(const co_fdcan_t *drv, uint32_t area, uint32_t i)
{
    return &drv->cfg.ram[area + i * CO_FDCAN_RAM_ELEMENT_WORDS];
}

/* Into initialisation with the configuration registers writable (CCE), or out of it. */
static bool set_init(co_fdcan_regs_t *r, bool init)
{
    wr(&r->cccr, init ? (rd(&r->cccr) | CCCR_INIT) : 0u); /* leaving clears CCE too */
    for (uint32_t n = 0; n < CO_STM32_WAIT_READS; n++) {
        if (((rd(&r->cccr) & CCCR_INIT) != 0) == init) {
            if (init) {
                wr(&r->cccr, CCCR_INIT | CCCR_CCE);
            }
            return true;
        }
    }
    return false;
}

static uint32_t nbtp_of(const co_cm_bit_timing_t *t)
{
    return (uint32_t)(t->sjw - 1u) << 25 | (uint32_t)(t->brp - 1u) << 16 |
           (uint32_t)(t->tseg1 - 1u) << 8 | (uint32_t)(t->tseg2 - 1u);
}

/* ---- Transmit (the port's critical section held). */

static bool fd_mailbox_put(void *hw, const co_frame_t *frame)
{
    co_fdcan_t *drv = hw;
    co_fdcan_regs_t *r = drv->cfg.regs;
    uint32_t txfqs = rd(&r->txfqs);
    if (txfqs & TXFQS_FULL) {
        return false;
    }
    uint32_t t0 = (frame->flags & CO_FRAME_EXT) ? (frame->id | E_XTD) : frame->id << 18;
    t0 |= (frame->flags & CO_FRAME_RTR) ? E_RTR : 0u;
    uint32_t pending = drv->cfg.request_order ? 0u : rd(&r->txbrp) & 7u;
    for (uint32_t i = 0; i < 3; i++) {
        if ((pending & (1u << i)) &&
            (rd(element(drv, CO_FDCAN_RAM_TX_BUFFERS, i)) & E_ID_MASK) == (t0 & E_ID_MASK)) {
            return false; /* its predecessor has not left: it would go by buffer number */
        }
    }
    uint32_t put = txfqs >> TXFQS_PUT_SHIFT & 3u;
    volatile uint32_t *e = element(drv, CO_FDCAN_RAM_TX_BUFFERS, put);
    wr(&e[0], t0);
    wr(&e[1], (uint32_t)(frame->len > 8 ? 8u : frame->len) << 16); /* classic, no event */
    wr(&e[2], co_stm32_data_word(frame, 0));
    wr(&e[3], co_stm32_data_word(frame, 4));
    wr(&r->txbar, 1u << put);
    return true;
}

/* ---- Filters, bit rate, counters (main loop). */

/* The filter elements of `ids`: the RXGFC that lists them, or 0 when they do not fit. */
static uint32_t fill_elements(co_fdcan_t *drv, const uint32_t *ids, size_t n)
{
    uint32_t std = 0, ext = 0;
    uint32_t std_first = 0, ext_first = 0;
    bool std_half = false, ext_half = false;
    for (size_t i = 0; i < n; i++) {
        uint32_t id = ids[i] & 0x1FFFFFFFu;
        if (!(ids[i] & 0x80000000u)) {
            if (std_half) { /* the element's second identifier */
                wr(&drv->cfg.ram[CO_FDCAN_RAM_STD_FILTERS + std - 1u],
                   SF_DUAL_FIFO0 | std_first << 16 | (id & 0x7FFu));
            } else if (std == CO_FDCAN_STD_FILTERS) {
                return 0;
            } else { /* a new element, both identifiers this one until a second comes */
                std_first = id & 0x7FFu;
                wr(&drv->cfg.ram[CO_FDCAN_RAM_STD_FILTERS + std++],
                   SF_DUAL_FIFO0 | std_first << 16 | std_first);
            }
            std_half = !std_half;
        } else {
            volatile uint32_t *e = &drv->cfg.ram[CO_FDCAN_RAM_EXT_FILTERS + 2u * ext];
            if (ext_half) {
                wr(&e[-1], EF1_DUAL | id);
            } else if (ext == CO_FDCAN_EXT_FILTERS) {
                return 0;
            } else {
                ext_first = id;
                wr(&e[0], EF0_FIFO0 | ext_first);
                wr(&e[1], EF1_DUAL | ext_first);
                ext++;
            }
            ext_half = !ext_half;
        }
    }
    return std << RXGFC_LSS_SHIFT | ext << RXGFC_LSE_SHIFT | RXGFC_ANFS_REJECT | RXGFC_ANFE_REJECT;
}

static bool fd_set_filters(void *hw, const uint32_t *ids, size_t n)
{
    co_fdcan_t *drv = hw;
    co_fdcan_regs_t *r = drv->cfg.regs;
    if (!set_init(r, true)) {
        return false;
    }
    uint32_t rxgfc = ids ? fill_elements(drv, ids, n) : 0u;
    wr(&r->rxgfc, rxgfc); /* 0: no elements, every frame into FIFO 0 */
    (void)set_init(r, false);
    return rxgfc != 0 || ids == NULL;
}

static co_err_t fd_set_bit_rate(void *hw, uint32_t bit_rate)
{
    co_fdcan_t *drv = hw;
    co_cm_bit_timing_t t;
    if (co_cm_bit_timing(drv->cfg.clock_hz, bit_rate, &k_limits, &t) != CO_OK) {
        return CO_ERR_ARG;
    }
    if (!set_init(drv->cfg.regs, true)) {
        return CO_ERR_STATE;
    }
    wr(&drv->cfg.regs->nbtp, nbtp_of(&t));
    drv->cfg.bit_rate = bit_rate;
    return set_init(drv->cfg.regs, false) ? CO_OK : CO_ERR_STATE;
}

static void fd_error_counters(void *hw, uint8_t *tec, uint8_t *rec)
{
    uint32_t ecr = rd(&((co_fdcan_t *)hw)->cfg.regs->ecr);
    *tec = (uint8_t)ecr;
    *rec = (uint8_t)(ecr >> 8 & 0x7Fu);
}

const co_cm_can_ops_t co_fdcan_ops = {fd_mailbox_put, fd_set_filters, fd_set_bit_rate,
                                      fd_error_counters};

co_err_t co_fdcan_init(co_fdcan_t *drv, const co_fdcan_config_t *cfg)
{
    co_cm_bit_timing_t t;
    if (!drv || !cfg || !cfg->regs || !cfg->ram ||
        co_cm_bit_timing(cfg->clock_hz, cfg->bit_rate, &k_limits, &t) != CO_OK) {
        return CO_ERR_ARG;
    }
    drv->cfg = *cfg;
    drv->state = CO_CM_CAN_ERROR_ACTIVE;
    co_fdcan_regs_t *r = cfg->regs;
    if (!set_init(r, true)) {
        return CO_ERR_STATE;
    }
    for (uint32_t i = 0; i < CO_FDCAN_RAM_WORDS; i++) { /* undefined after power-up */
        wr(&cfg->ram[i], 0);
    }
    wr(&r->nbtp, nbtp_of(&t));
    wr(&r->rxgfc, 0); /* accept-all until the node's routes come */
    wr(&r->txbc, cfg->request_order ? 0u : TXBC_TFQM);
    wr(&r->ie, IR_RF0N | IR_RF0L | IR_TC | IR_EP | IR_EW | IR_BO);
    wr(&r->ils, 0);
    wr(&r->ile, ILE_EINT0);
    wr(&r->txbtie, 7u);
    return set_init(r, false) ? CO_OK : CO_ERR_STATE;
}

/* ---- The interrupt. */

static void report_state(co_fdcan_t *drv)
{
    co_fdcan_regs_t *r = drv->cfg.regs;
    uint32_t psr = rd(&r->psr);
    co_cm_can_state_t state = (psr & PSR_BO)   ? CO_CM_CAN_BUS_OFF
                              : (psr & PSR_EP) ? CO_CM_CAN_ERROR_PASSIVE
                              : (psr & PSR_EW) ? CO_CM_CAN_ERROR_WARNING
                                               : CO_CM_CAN_ERROR_ACTIVE;
#if !defined(CO_TEST_FAULT_NO_RECOVERY) /* test-only: the controller stays bus-off */
    if ((psr & PSR_BO) && (rd(&r->cccr) & CCCR_INIT)) {
        wr(&r->cccr, 0); /* bus-off set INIT: clearing it starts the recovery */
    }
#endif
    if (state != drv->state) {
        drv->state = state;
        co_cm_isr_bus_state(drv->cfg.port, state);
    }
}

static co_frame_t read_element(const volatile uint32_t *e)
{
    uint32_t r0 = rd(&e[0]);
    uint32_t dlc = rd(&e[1]) >> 16 & 0xFu;
    uint32_t lo = rd(&e[2]);
    uint32_t hi = rd(&e[3]);
    co_frame_t frame = {
        .id = (r0 & E_XTD) ? (r0 & 0x1FFFFFFFu) : (r0 >> 18 & 0x7FFu),
        .flags = (uint8_t)(((r0 & E_XTD) ? CO_FRAME_EXT : 0u) | ((r0 & E_RTR) ? CO_FRAME_RTR : 0u)),
        .len = (uint8_t)(dlc > 8 ? 8 : dlc)};
    co_stm32_data_set(&frame, lo, hi);
    return frame;
}

void co_fdcan_isr(co_fdcan_t *drv)
{
    co_fdcan_regs_t *r = drv->cfg.regs;
    uint32_t ir = rd(&r->ir) & rd(&r->ie);
    wr(&r->ir, ir); /* cleared first: what comes while this runs raises the line again */
    uint32_t status;
    for (uint32_t n = 0; n < 3 && ((status = rd(&r->rxf0s)) & RXF0S_FILL); n++) {
        uint32_t get = status >> RXF0S_GET_SHIFT & 3u;
        co_frame_t frame = read_element(element(drv, CO_FDCAN_RAM_RX_FIFO0, get));
        wr(&r->rxf0a, get);
        co_cm_isr_rx(drv->cfg.port, &frame);
    }
#if !defined(CO_TEST_FAULT_NO_OVERRUN) /* test-only: a lost frame goes unreported */
    if (ir & IR_RF0L) {
        co_cm_isr_rx_overrun(drv->cfg.port);
    }
#endif
    report_state(drv);
    if (ir & IR_TC) {
        co_cm_isr_tx_done(drv->cfg.port);
    }
}
