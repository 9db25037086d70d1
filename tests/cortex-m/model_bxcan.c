/* SPDX-License-Identifier: Apache-2.0 */
/* tests/cortex-m/model_bxcan.c -- see model_bxcan.h. */
#include "model_bxcan.h"

#include <stddef.h>
#include <string.h>

#define OFF(field) ((uint32_t)offsetof(co_bxcan_regs_t, field))
#define MAILBOX_OFF OFF(tx)
#define FIFO_OFF OFF(rx)
#define BANK_OFF OFF(bank)

#define MCR_INRQ (1u << 0)
#define MCR_SLEEP (1u << 1)
#define MCR_RFLM (1u << 3)
#define MCR_TXFP (1u << 2)
#define MCR_ABOM (1u << 6)
#define MSR_INAK (1u << 0)
#define MSR_SLAK (1u << 1)
#define MSR_ERRI (1u << 2)
#define MSR_RC_W1 (7u << 2) /* ERRI, WKUI, SLAKI */
#define IER_TMEIE (1u << 0)
#define IER_FMPIE0 (1u << 1)
#define IER_FFIE0 (1u << 2)
#define IER_FOVIE0 (1u << 3)
#define IER_EWGIE (1u << 8)
#define IER_EPVIE (1u << 9)
#define IER_BOFIE (1u << 10)
#define IER_ERRIE (1u << 15)
#define TSR_FLAGS 0x8Fu /* per mailbox: RQCP, TXOK, ALST, TERR, ABRQ */
#define TSR_RQCP 1u
#define TSR_TXOK 2u
#define TSR_ABRQ 0x80u
#define IR_TXRQ 1u
#define IR_RTR 2u
#define IR_IDE 4u
#define RF0R_FULL (1u << 3)
#define RF0R_FOVR (1u << 4)
#define RF0R_RFOM (1u << 5)
#define FMR_FINIT 1u

static bxcan_model_t *self(can_model_t *m) { return (bxcan_model_t *)m; }

static bool in_init(const bxcan_model_t *x) { return (x->msr & MSR_INAK) != 0; }

/* Initialisation or sleep: no frame in or out. */
static bool stopped(const bxcan_model_t *x) { return (x->msr & (MSR_INAK | MSR_SLAK)) != 0; }

/* ---- Frames and their register forms. */

static co_frame_t frame_of(uint32_t ir, uint32_t dtr, uint32_t dlr, uint32_t dhr)
{
    uint32_t dlc = dtr & 0xFu;
    co_frame_t f = {.id = (ir & IR_IDE) ? ir >> 3 : ir >> 21,
                    .flags = (uint8_t)(((ir & IR_IDE) ? CO_FRAME_EXT : 0u) |
                                       ((ir & IR_RTR) ? CO_FRAME_RTR : 0u)),
                    .len = (uint8_t)(dlc > 8 ? 8 : dlc)};
    for (uint32_t i = 0; i < 4; i++) {
        f.data[i] = (uint8_t)(dlr >> (8 * i));
        f.data[4 + i] = (uint8_t)(dhr >> (8 * i));
    }
    return f;
}

static uint32_t ir_of(const co_frame_t *f)
{
    uint32_t rtr = (f->flags & CO_FRAME_RTR) ? IR_RTR : 0u;
    return (f->flags & CO_FRAME_EXT) ? (f->id << 3 | IR_IDE | rtr) : (f->id << 21 | rtr);
}

static uint32_t data_word(const co_frame_t *f, uint32_t first)
{
    return (uint32_t)f->data[first] | (uint32_t)f->data[first + 1] << 8 |
           (uint32_t)f->data[first + 2] << 16 | (uint32_t)f->data[first + 3] << 24;
}

/* A frame in a 16-bit filter's layout: STID[15:5] RTR 4 IDE 3 EXID[17:15]. */
static uint32_t f16_of(const co_frame_t *f)
{
    uint32_t rtr = (f->flags & CO_FRAME_RTR) ? 1u << 4 : 0u;
    if (f->flags & CO_FRAME_EXT) {
        return ((f->id >> 18) & 0x7FFu) << 5 | rtr | 1u << 3 | ((f->id >> 15) & 7u);
    }
    return (f->id & 0x7FFu) << 5 | rtr;
}

/* ---- Receive: the filter banks, FIFO 0. */

static bool pair16(uint32_t frame16, uint32_t reg, bool list)
{
    uint32_t lo = reg & 0xFFFFu;
    uint32_t hi = reg >> 16;
    return list ? (frame16 == lo || frame16 == hi) : ((frame16 & hi) == (lo & hi));
}

static bool bank_takes(const bxcan_model_t *x, uint32_t b, const co_frame_t *f)
{
    bool list = (x->fm1r >> b) & 1u;
    if ((x->fs1r >> b) & 1u) {
        uint32_t w = ir_of(f);
        return list ? (w == x->fr1[b] || w == x->fr2[b])
                    : ((w & x->fr2[b]) == (x->fr1[b] & x->fr2[b]));
    }
    uint32_t w16 = f16_of(f);
    return pair16(w16, x->fr1[b], list) || pair16(w16, x->fr2[b], list);
}

static void bx_received(can_model_t *m, const co_frame_t *f)
{
    bxcan_model_t *x = self(m);
    if (stopped(x) || (x->fmr & FMR_FINIT)) {
        return; /* reception stopped */
    }
    uint32_t b = 0;
    while (b < 28 && !(((x->fa1r >> b) & 1u) && bank_takes(x, b, f))) {
        b++;
    }
    if (b == 28) {
        m->rx_rejected++;
        return;
    }
    m->rx_accepted++;
    if ((x->ffa1r >> b) & 1u) {
        m->rx_lost++; /* FIFO 1: not modelled */
        return;
    }
    if (x->fifo_count < 3) {
        x->fifo[x->fifo_count++] = *f;
        x->full = x->fifo_count == 3;
        return;
    }
    x->overrun = true;
    m->rx_lost++;
    if (!(x->mcr & MCR_RFLM)) {
        x->fifo[2] = *f; /* FIFO not locked: the newest frame replaces the last stored */
    }
}

/* ---- Transmit. */

static uint32_t tsr_read(const bxcan_model_t *x)
{
    uint32_t tsr = x->tsr;
    int code = -1;
    for (uint32_t i = 0; i < 3; i++) {
        if (!x->base.slot_pending[i]) {
            tsr |= 1u << (26 + i);
            code = code < 0 ? (int)i : code;
        }
    }
    if (code < 0) { /* all pending: the one that would go last */
        code = 0;
        for (uint32_t i = 1; i < 3; i++) {
            if (can_model_key(&x->base.slot_frame[i]) >=
                can_model_key(&x->base.slot_frame[(uint32_t)code])) {
                code = (int)i;
            }
        }
    }
    return tsr | (uint32_t)code << 24;
}

static void tsr_write(bxcan_model_t *x, uint32_t value)
{
    for (uint32_t i = 0; i < 3; i++) {
        uint32_t bits = value >> (8 * i);
        if (bits & TSR_RQCP) {
            x->tsr &= ~(TSR_FLAGS << (8 * i)); /* RQCP clears TXOK, ALST, TERR with it */
        }
        if ((bits & TSR_ABRQ) && can_model_abort(&x->base, i)) {
            x->tsr |= TSR_RQCP << (8 * i); /* aborted: done, not sent */
        }
    }
}

static void mailbox_write(bxcan_model_t *x, uint32_t box, uint32_t reg, uint32_t value)
{
    if (x->base.slot_pending[box]) {
        x->base.violations++; /* a pending mailbox is write protected */
        return;
    }
    co_bxcan_mailbox_t *mb = &x->tx[box];
    volatile uint32_t *word[4] = {&mb->ir, &mb->dtr, &mb->dlr, &mb->dhr};
    *word[reg] = value;
    if (reg == 0 && (value & IR_TXRQ)) {
        co_frame_t f = frame_of(mb->ir, mb->dtr, mb->dlr, mb->dhr);
        can_model_request(&x->base, box, &f);
    }
}

static void bx_sent(can_model_t *m, uint32_t slot)
{
    self(m)->tsr |= (TSR_RQCP | TSR_TXOK) << (8 * slot);
}

/* ---- Modes, errors. */

static void mcr_write(bxcan_model_t *x, uint32_t value)
{
    bool was_init = in_init(x);
    x->mcr = value & 0x000180FFu;
    if (value & MCR_INRQ) {
        if (!x->stuck_in_init) {
            x->msr |= MSR_INAK;
        }
    } else if (was_init && !x->stuck_in_init) {
        x->msr &= ~MSR_INAK;
        if (x->base.bus_off && !(value & MCR_ABOM)) {
            can_model_start_recovery(&x->base); /* the software's recovery sequence */
        }
    }
    if (!(value & MCR_SLEEP)) {
        x->msr &= ~MSR_SLAK;
    }
    x->base.request_order = (value & MCR_TXFP) != 0;
    x->base.transmit_held = stopped(x);
    can_model_offer(&x->base);
}

static uint32_t esr_read(const bxcan_model_t *x)
{
    co_cm_can_state_t s = can_model_state(&x->base);
    uint32_t tec = x->base.tec > 255 ? 255u : x->base.tec;
    return (s >= CO_CM_CAN_ERROR_WARNING ? 1u : 0u) | (s >= CO_CM_CAN_ERROR_PASSIVE ? 2u : 0u) |
           (s == CO_CM_CAN_BUS_OFF ? 4u : 0u) | x->esr_lec | tec << 16 | x->base.rec << 24;
}

static void bx_state_changed(can_model_t *m, co_cm_can_state_t was)
{
    bxcan_model_t *x = self(m);
    co_cm_can_state_t now = can_model_state(m);
    bool rose =
        (now >= CO_CM_CAN_ERROR_WARNING && was < CO_CM_CAN_ERROR_WARNING && (x->ier & IER_EWGIE)) ||
        (now >= CO_CM_CAN_ERROR_PASSIVE && was < CO_CM_CAN_ERROR_PASSIVE && (x->ier & IER_EPVIE)) ||
        (now == CO_CM_CAN_BUS_OFF && was != CO_CM_CAN_BUS_OFF && (x->ier & IER_BOFIE));
    if (rose) {
        x->msr |= MSR_ERRI; /* the way back raises nothing */
    }
    if (now == CO_CM_CAN_BUS_OFF && (x->mcr & MCR_ABOM)) {
        can_model_start_recovery(m);
    }
}

/* The bit rate BTR gives at the model's clock (the recovery lasts bits). */
static void update_bit_rate(bxcan_model_t *x)
{
    uint32_t brp = (x->btr & 0x3FFu) + 1u;
    uint32_t quanta = 1u + ((x->btr >> 16) & 0xFu) + 1u + ((x->btr >> 20) & 7u) + 1u;
    x->base.bit_rate = x->clock_hz / (brp * quanta);
}

/* ---- Register accesses. */

static uint32_t bx_read(can_model_t *m, uint32_t off)
{
    bxcan_model_t *x = self(m);
    if (off >= MAILBOX_OFF && off < FIFO_OFF) {
        uint32_t box = (off - MAILBOX_OFF) / 16u;
        const co_bxcan_mailbox_t *mb = &x->tx[box];
        uint32_t word[4] = {(mb->ir & ~IR_TXRQ) | (m->slot_pending[box] ? IR_TXRQ : 0u), mb->dtr,
                            mb->dlr, mb->dhr};
        return word[(off % 16u) / 4u];
    }
    if (off >= FIFO_OFF && off < FIFO_OFF + 16u) {
        if (x->fifo_count == 0) {
            return 0;
        }
        const co_frame_t *f = &x->fifo[0];
        uint32_t word[4] = {ir_of(f), f->len, data_word(f, 0), data_word(f, 4)};
        return word[(off - FIFO_OFF) / 4u];
    }
    if (off >= BANK_OFF) {
        uint32_t b = (off - BANK_OFF) / 8u;
        return (off % 8u) ? x->fr2[b] : x->fr1[b];
    }
    switch (off) {
    case OFF(mcr):
        return x->mcr;
    case OFF(msr):
        return x->msr;
    case OFF(tsr):
        return tsr_read(x);
    case OFF(rf0r):
        return x->fifo_count | (x->full ? RF0R_FULL : 0u) | (x->overrun ? RF0R_FOVR : 0u);
    case OFF(ier):
        return x->ier;
    case OFF(esr):
        return esr_read(x);
    case OFF(btr):
        return x->btr;
    case OFF(fmr):
        return x->fmr;
    case OFF(fm1r):
        return x->fm1r;
    case OFF(fs1r):
        return x->fs1r;
    case OFF(ffa1r):
        return x->ffa1r;
    case OFF(fa1r):
        return x->fa1r;
    default:
        return 0;
    }
}

/* FM1R, FS1R, FFA1R: only in filter initialisation. */
static void filter_config_write(bxcan_model_t *x, uint32_t *reg, uint32_t value)
{
    if (x->fmr & FMR_FINIT) {
        *reg = value & 0x0FFFFFFFu;
    } else {
        x->base.violations++;
    }
}

static void bx_write(can_model_t *m, uint32_t off, uint32_t value)
{
    bxcan_model_t *x = self(m);
    if (off >= MAILBOX_OFF && off < FIFO_OFF) {
        mailbox_write(x, (off - MAILBOX_OFF) / 16u, (off % 16u) / 4u, value);
        return;
    }
    if (off >= BANK_OFF) {
        uint32_t b = (off - BANK_OFF) / 8u;
        if (!(x->fmr & FMR_FINIT) && ((x->fa1r >> b) & 1u)) {
            m->violations++; /* an active bank outside filter initialisation */
        } else if (off % 8u) {
            x->fr2[b] = value;
        } else {
            x->fr1[b] = value;
        }
        return;
    }
    switch (off) {
    case OFF(mcr):
        mcr_write(x, value);
        break;
    case OFF(msr):
        x->msr &= ~(value & MSR_RC_W1);
        break;
    case OFF(tsr):
        tsr_write(x, value);
        break;
    case OFF(rf0r):
        if (value & RF0R_FULL) {
            x->full = false;
        }
        if (value & RF0R_FOVR) {
            x->overrun = false;
        }
        if ((value & RF0R_RFOM) && x->fifo_count > 0) {
            memmove(&x->fifo[0], &x->fifo[1], (x->fifo_count - 1u) * sizeof x->fifo[0]);
            x->fifo_count--;
        }
        break;
    case OFF(ier):
        x->ier = value & 0x0003CF7Fu;
        break;
    case OFF(esr):
        x->esr_lec = value & 0x70u;
        break;
    case OFF(btr):
        if (in_init(x)) {
            x->btr = value & 0xC37F03FFu;
            update_bit_rate(x);
        } else {
            m->violations++; /* bit timing outside initialisation */
        }
        break;
    case OFF(fmr):
        x->fmr = (x->fmr & ~FMR_FINIT) | (value & FMR_FINIT);
        break;
    case OFF(fm1r):
        filter_config_write(x, &x->fm1r, value);
        break;
    case OFF(fs1r):
        filter_config_write(x, &x->fs1r, value);
        break;
    case OFF(ffa1r):
        filter_config_write(x, &x->ffa1r, value);
        break;
    case OFF(fa1r):
        x->fa1r = value & 0x0FFFFFFFu;
        break;
    default:
        m->violations++;
        break;
    }
}

static bool bx_pending(can_model_t *m, uint32_t v)
{
    bxcan_model_t *x = self(m);
    switch (v) {
    case BXCAN_VEC_TX:
        return (x->ier & IER_TMEIE) && (x->tsr & 0x00010101u);
    case BXCAN_VEC_RX0:
        return ((x->ier & IER_FMPIE0) && x->fifo_count > 0) || ((x->ier & IER_FFIE0) && x->full) ||
               ((x->ier & IER_FOVIE0) && x->overrun);
    case BXCAN_VEC_SCE:
        return (x->ier & IER_ERRIE) && (x->msr & MSR_ERRI);
    default:
        return false;
    }
}

static const can_model_class_t k_bxcan = {bx_read, bx_write,         bx_received,
                                          bx_sent, bx_state_changed, bx_pending};

void bxcan_model_init(bxcan_model_t *x)
{
    memset(x, 0, sizeof *x);
    can_model_init(&x->base, &k_bxcan, &x->regs, sizeof x->regs, NULL, 0, 128u * 11u);
    x->mcr = 0x00010002u; /* DBF, SLEEP */
    x->msr = 0x00000C02u; /* SLAK, RX, SAMP */
    x->btr = 0x01230000u;
    x->fmr = 0x2A1C0E01u; /* FINIT, CAN2SB 14 */
    x->clock_hz = 42000000u;
    x->base.transmit_held = true; /* asleep */
    update_bit_rate(x);
}
