/* SPDX-License-Identifier: Apache-2.0 */
/* tests/cortex-m/model_fdcan.c -- see model_fdcan.h. */
#include "model_fdcan.h"

#include <stddef.h>
#include <string.h>

#define OFF(field) ((uint32_t)offsetof(co_fdcan_regs_t, field))

#define CCCR_INIT (1u << 0)
#define CCCR_CCE (1u << 1)
#define IR_RF0N (1u << 0)
#define IR_RF0F (1u << 1)
#define IR_RF0L (1u << 2)
#define IR_TC (1u << 7)
#define IR_TCF (1u << 8)
#define IR_EP (1u << 17)
#define IR_EW (1u << 18)
#define IR_BO (1u << 19)
#define IR_ALL 0x00FFFFFFu
#define TXBC_TFQM (1u << 24)
#define RXGFC_F0OM (1u << 9)
#define E_XTD (1u << 30)
#define E_RTR (1u << 29)

/* IR bits by interrupt group (ILS bit): RXFIFO0, RXFIFO1, SMSG, TFERR, MISC, BERR, PERR. */
static const uint32_t k_groups[7] = {0x7u, 0x38u, 0x1C0u, 0x1E00u, 0xE000u, 0x30000u, 0xFC0000u};

static fdcan_model_t *self(can_model_t *m) { return (fdcan_model_t *)m; }

static bool in_init(const fdcan_model_t *x) { return (x->cccr & CCCR_INIT) != 0; }
static bool configurable(const fdcan_model_t *x) { return in_init(x) && (x->cccr & CCCR_CCE); }

static uint32_t *element(fdcan_model_t *x, uint32_t area, uint32_t i)
{
    return &x->ram[area + i * CO_FDCAN_RAM_ELEMENT_WORDS];
}

/* ---- Receive: the filter list, FIFO 0. */

/* What the filters do with the frame: 1 FIFO 0, 2 FIFO 1, 0 reject. */
static uint32_t std_filter(const fdcan_model_t *x, uint32_t id)
{
    uint32_t lss = (x->rxgfc >> 16) & 0x1Fu;
    for (uint32_t i = 0; i < lss && i < CO_FDCAN_STD_FILTERS; i++) {
        uint32_t e = x->ram[CO_FDCAN_RAM_STD_FILTERS + i];
        uint32_t sft = e >> 30, sfec = (e >> 27) & 7u, id1 = (e >> 16) & 0x7FFu, id2 = e & 0x7FFu;
        bool match = sft == 0   ? (id >= id1 && id <= id2)
                     : sft == 1 ? (id == id1 || id == id2)
                     : sft == 2 ? ((id & id2) == (id1 & id2))
                                : false;
        if (match && sfec != 0) {
            return sfec == 1 ? 1u : sfec == 2 ? 2u : 0u; /* (priority storage: not modelled) */
        }
    }
    uint32_t anfs = (x->rxgfc >> 4) & 3u;
    return anfs == 0 ? 1u : anfs == 1 ? 2u : 0u;
}

static uint32_t ext_filter(const fdcan_model_t *x, uint32_t id)
{
    uint32_t lse = (x->rxgfc >> 24) & 0xFu;
    id &= x->xidam;
    for (uint32_t i = 0; i < lse && i < CO_FDCAN_EXT_FILTERS; i++) {
        uint32_t f0 = x->ram[CO_FDCAN_RAM_EXT_FILTERS + 2 * i];
        uint32_t f1 = x->ram[CO_FDCAN_RAM_EXT_FILTERS + 2 * i + 1];
        uint32_t efec = f0 >> 29, eft = f1 >> 30, id1 = f0 & 0x1FFFFFFFu, id2 = f1 & 0x1FFFFFFFu;
        bool match = eft == 0   ? (id >= id1 && id <= id2)
                     : eft == 1 ? (id == id1 || id == id2)
                     : eft == 2 ? ((id & id2) == (id1 & id2))
                                : (id >= id1 && id <= id2); /* 3: range without XIDAM */
        if (match && efec != 0) {
            return efec == 1 ? 1u : efec == 2 ? 2u : 0u;
        }
    }
    uint32_t anfe = (x->rxgfc >> 2) & 3u;
    return anfe == 0 ? 1u : anfe == 1 ? 2u : 0u;
}

static void fd_received(can_model_t *m, const co_frame_t *f)
{
    fdcan_model_t *x = self(m);
    if (in_init(x)) {
        return;
    }
    bool ext = (f->flags & CO_FRAME_EXT) != 0;
    bool remote_rejected = (f->flags & CO_FRAME_RTR) && ((x->rxgfc >> (ext ? 0 : 1)) & 1u);
    uint32_t to = remote_rejected ? 0u : ext ? ext_filter(x, f->id) : std_filter(x, f->id);
    if (to == 0) {
        m->rx_rejected++;
        return;
    }
    m->rx_accepted++;
    if (to == 2) {
        m->rx_lost++; /* FIFO 1: not modelled */
        return;
    }
    if (x->rx_fill == 3) {
        if (!(x->rxgfc & RXGFC_F0OM)) {
            x->ir |= IR_RF0L; /* blocking mode: the new frame is lost */
            m->rx_lost++;
            return;
        }
        x->rx_get = (x->rx_get + 1u) % 3u; /* overwrite mode: the oldest goes */
        x->rx_fill--;
        m->rx_lost++;
    }
    uint32_t *e = element(x, CO_FDCAN_RAM_RX_FIFO0, (x->rx_get + x->rx_fill) % 3u);
    e[0] = (ext ? (f->id | E_XTD) : f->id << 18) | ((f->flags & CO_FRAME_RTR) ? E_RTR : 0u);
    e[1] = (uint32_t)f->len << 16;
    for (uint32_t w = 0; w < 2; w++) {
        e[2 + w] = (uint32_t)f->data[4 * w] | (uint32_t)f->data[4 * w + 1] << 8 |
                   (uint32_t)f->data[4 * w + 2] << 16 | (uint32_t)f->data[4 * w + 3] << 24;
    }
    x->rx_fill++;
    x->ir |= IR_RF0N | (x->rx_fill == 3 ? IR_RF0F : 0u);
}

static void rx_acknowledge(fdcan_model_t *x, uint32_t index)
{
    uint32_t n = (index + 3u - x->rx_get) % 3u + 1u; /* the elements up to `index` */
    if (index > 2 || n > x->rx_fill) {
        x->base.violations++; /* an index that holds no frame */
        return;
    }
    x->rx_get = (x->rx_get + n) % 3u;
    x->rx_fill -= n;
}

/* ---- Transmit. */

static bool queue_mode(const fdcan_model_t *x) { return (x->txbc & TXBC_TFQM) != 0; }

static uint32_t pending_bits(const fdcan_model_t *x)
{
    uint32_t bits = 0;
    for (uint32_t i = 0; i < 3; i++) {
        bits |= x->base.slot_pending[i] ? 1u << i : 0u;
    }
    return bits;
}

/* The buffer the driver writes next: queue mode the lowest free, FIFO mode the next round. */
static uint32_t put_index(const fdcan_model_t *x)
{
    if (!queue_mode(x)) {
        return x->tx_put;
    }
    uint32_t pending = pending_bits(x);
    uint32_t i = 0;
    while (i < 3 && (pending & (1u << i))) {
        i++;
    }
    return i % 3u;
}

static uint32_t txfqs_read(const fdcan_model_t *x)
{
    uint32_t pending = pending_bits(x);
    uint32_t busy = (pending & 1u) + (pending >> 1 & 1u) + (pending >> 2 & 1u);
    int next = can_model_next_slot(&x->base);
    uint32_t get = queue_mode(x) || next < 0 ? 0u : (uint32_t)next;
    return (queue_mode(x) ? 0u : 3u - busy) | get << 8 | put_index(x) << 16 |
           (busy == 3 ? 1u << 21 : 0u);
}

static co_frame_t frame_in(const uint32_t *e)
{
    uint32_t dlc = (e[1] >> 16) & 0xFu;
    co_frame_t f = {.id = (e[0] & E_XTD) ? (e[0] & 0x1FFFFFFFu) : ((e[0] >> 18) & 0x7FFu),
                    .flags = (uint8_t)(((e[0] & E_XTD) ? CO_FRAME_EXT : 0u) |
                                       ((e[0] & E_RTR) ? CO_FRAME_RTR : 0u)),
                    .len = (uint8_t)(dlc > 8 ? 8 : dlc)};
    for (uint32_t i = 0; i < 8; i++) {
        f.data[i] = (uint8_t)(e[2 + i / 4] >> (8 * (i % 4)));
    }
    return f;
}

static void add_requests(fdcan_model_t *x, uint32_t bits)
{
    for (uint32_t i = 0; i < 3; i++) {
        if (!(bits & (1u << i)) || x->base.slot_pending[i]) {
            continue; /* a pending buffer's add request is ignored */
        }
        if (!queue_mode(x)) {
            if (i != x->tx_put) {
                x->base.violations++; /* FIFO mode: only the put index */
                continue;
            }
            x->tx_put = (x->tx_put + 1u) % 3u;
        }
        x->txbto &= ~(1u << i);
        co_frame_t f = frame_in(element(x, CO_FDCAN_RAM_TX_BUFFERS, i));
        can_model_request(&x->base, i, &f);
    }
}

static void cancel_requests(fdcan_model_t *x, uint32_t bits)
{
    for (uint32_t i = 0; i < 3; i++) {
        if ((bits & (1u << i)) && can_model_abort(&x->base, i)) {
            x->txbcf |= 1u << i;
            x->ir |= IR_TCF;
        }
    }
}

static void fd_sent(can_model_t *m, uint32_t slot)
{
    fdcan_model_t *x = self(m);
    x->txbto |= 1u << slot;
    if (x->txbtie & (1u << slot)) {
        x->ir |= IR_TC;
    }
}

/* ---- Modes, errors. */

static void set_held(fdcan_model_t *x)
{
    x->base.transmit_held = in_init(x);
    x->base.request_order = !queue_mode(x);
    can_model_offer(&x->base);
}

/* INIT written freely; CCE only while INIT was set, and cleared with it; the other bits only
 * while both were set. */
static void cccr_write(fdcan_model_t *x, uint32_t value)
{
    if (x->stuck_in_init) {
        return;
    }
    const uint32_t protected_bits = 0xF3FCu;
    bool was_init = in_init(x);
    uint32_t next =
        configurable(x) ? (x->cccr & ~protected_bits) | (value & protected_bits) : x->cccr;
    if (value & CCCR_INIT) {
        next |= CCCR_INIT;
        next = (was_init && (value & CCCR_CCE)) ? (next | CCCR_CCE) : (next & ~CCCR_CCE);
    } else {
        next &= ~(CCCR_INIT | CCCR_CCE);
        if (was_init && x->base.bus_off) {
            can_model_start_recovery(&x->base); /* the software's word after bus-off */
        }
    }
    x->cccr = next;
    set_held(x);
}

static uint32_t psr_read(const fdcan_model_t *x)
{
    co_cm_can_state_t s = can_model_state(&x->base);
    return 7u | (s >= CO_CM_CAN_ERROR_PASSIVE ? 1u << 5 : 0u) |
           (s >= CO_CM_CAN_ERROR_WARNING ? 1u << 6 : 0u) | (s == CO_CM_CAN_BUS_OFF ? 1u << 7 : 0u);
}

static void fd_state_changed(can_model_t *m, co_cm_can_state_t was)
{
    fdcan_model_t *x = self(m);
    co_cm_can_state_t now = can_model_state(m);
    if ((now >= CO_CM_CAN_ERROR_WARNING) != (was >= CO_CM_CAN_ERROR_WARNING)) {
        x->ir |= IR_EW;
    }
    if ((now >= CO_CM_CAN_ERROR_PASSIVE) != (was >= CO_CM_CAN_ERROR_PASSIVE)) {
        x->ir |= IR_EP;
    }
    if ((now == CO_CM_CAN_BUS_OFF) != (was == CO_CM_CAN_BUS_OFF)) {
        x->ir |= IR_BO;
    }
    if (now == CO_CM_CAN_BUS_OFF) {
        x->cccr |= CCCR_INIT; /* the controller stops itself */
        set_held(x);
    }
}

static void update_bit_rate(fdcan_model_t *x)
{
    uint32_t brp = ((x->nbtp >> 16) & 0x1FFu) + 1u;
    uint32_t quanta = 1u + ((x->nbtp >> 8) & 0xFFu) + 1u + (x->nbtp & 0x7Fu) + 1u;
    x->base.bit_rate = x->clock_hz / (brp * quanta);
}

/* ---- Register accesses. */

static uint32_t fd_read(can_model_t *m, uint32_t off)
{
    fdcan_model_t *x = self(m);
    uint32_t tec = m->tec > 255 ? 255u : m->tec;
    switch (off) {
    case OFF(crel):
        return 0x32141218u;
    case OFF(endn):
        return 0x87654321u;
    case OFF(cccr):
        return x->cccr;
    case OFF(nbtp):
        return x->nbtp;
    case OFF(ecr):
        return tec | (m->rec & 0x7Fu) << 8 | (m->rec >= 128 ? 1u << 15 : 0u);
    case OFF(psr):
        return psr_read(x);
    case OFF(ir):
        return x->ir;
    case OFF(ie):
        return x->ie;
    case OFF(ils):
        return x->ils;
    case OFF(ile):
        return x->ile;
    case OFF(rxgfc):
        return x->rxgfc;
    case OFF(xidam):
        return x->xidam;
    case OFF(rxf0s):
        return x->rx_fill | x->rx_get << 8 | ((x->rx_get + x->rx_fill) % 3u) << 16 |
               (x->rx_fill == 3 ? 1u << 24 : 0u) | ((x->ir & IR_RF0L) ? 1u << 25 : 0u);
    case OFF(txbc):
        return x->txbc;
    case OFF(txfqs):
        return txfqs_read(x);
    case OFF(txbrp):
        return pending_bits(x);
    case OFF(txbto):
        return x->txbto;
    case OFF(txbcf):
        return x->txbcf;
    case OFF(txbtie):
        return x->txbtie;
    default:
        return 0;
    }
}

/* A register written only with INIT and CCE set. */
static void protected_write(fdcan_model_t *x, uint32_t *reg, uint32_t value, uint32_t mask)
{
    if (configurable(x)) {
        *reg = value & mask;
    } else {
        x->base.violations++;
    }
}

static void fd_write(can_model_t *m, uint32_t off, uint32_t value)
{
    fdcan_model_t *x = self(m);
    switch (off) {
    case OFF(cccr):
        cccr_write(x, value);
        break;
    case OFF(nbtp):
        protected_write(x, &x->nbtp, value, 0xFFFFFF7Fu);
        update_bit_rate(x);
        break;
    case OFF(ir):
        x->ir &= ~(value & IR_ALL);
        break;
    case OFF(ie):
        x->ie = value & IR_ALL;
        break;
    case OFF(ils):
        x->ils = value & 0x7Fu;
        break;
    case OFF(ile):
        x->ile = value & 3u;
        break;
    case OFF(rxgfc):
        protected_write(x, &x->rxgfc, value, 0x0F1F033Fu);
        break;
    case OFF(xidam):
        protected_write(x, &x->xidam, value, 0x1FFFFFFFu);
        break;
    case OFF(rxf0a):
        rx_acknowledge(x, value & 7u);
        break;
    case OFF(txbc):
        protected_write(x, &x->txbc, value, TXBC_TFQM);
        set_held(x);
        break;
    case OFF(txbar):
        add_requests(x, value & 7u);
        break;
    case OFF(txbcr):
        cancel_requests(x, value & 7u);
        break;
    case OFF(txbtie):
        x->txbtie = value & 7u;
        break;
    case OFF(txbcie):
        break;
    default:
        m->violations++;
        break;
    }
}

static bool fd_pending(can_model_t *m, uint32_t v)
{
    fdcan_model_t *x = self(m);
    uint32_t line1 = 0;
    for (uint32_t g = 0; g < 7; g++) {
        line1 |= ((x->ils >> g) & 1u) ? k_groups[g] : 0u;
    }
    uint32_t active = x->ir & x->ie;
    if (v == FDCAN_VEC_IT0) {
        return (x->ile & 1u) && (active & ~line1);
    }
    return v == FDCAN_VEC_IT1 && (x->ile & 2u) && (active & line1);
}

static const can_model_class_t k_fdcan = {fd_read, fd_write,         fd_received,
                                          fd_sent, fd_state_changed, fd_pending};

void fdcan_model_init(fdcan_model_t *x)
{
    memset(x, 0, sizeof *x);
    can_model_init(&x->base, &k_fdcan, &x->regs, sizeof x->regs, x->ram, CO_FDCAN_RAM_WORDS,
                   129u * 11u);
    for (uint32_t i = 0; i < CO_FDCAN_RAM_WORDS; i++) {
        x->ram[i] = 0xA5A5A5A5u ^ i; /* undefined after power-up */
    }
    x->cccr = CCCR_INIT;
    x->nbtp = 0x06000A03u;
    x->xidam = 0x1FFFFFFFu;
    x->clock_hz = 80000000u;
    update_bit_rate(x);
    set_held(x);
}
