/* SPDX-License-Identifier: Apache-2.0 */
/*
 * port/cortex-m/cm_can.c -- the port's CAN side (canola/cm_can.h): the receive ring between
 * the CAN interrupt and the main loop, the transmit queue behind the controller's
 * mailboxes, bus states, and the acceptance filters from the node's routes.
 *
 * Transmit: a frame goes into a free mailbox when nothing waits before it; else into the
 * queue in arbitration order; else the node keeps it (CO_ERR_BUSY). Frames leave the queue
 * only from its head, into a mailbox, in the critical section, from the main loop's send
 * and from the transmit-complete interrupt alike: after either returns, a mailbox the
 * driver would take a frame in is never free while the queue holds one.
 */
#include "canola/cm_can.h"

#include "canola/cm_critical.h"
#include "canola/cm_port.h"

/* Bus events the interrupt leaves for the main loop (co_cm_can_t.events). */
#define EV_OFF 1u
#define EV_RECOVERED 2u
#define EV_PASSIVE 4u
#define EV_ACTIVE 8u

/* The frame's arbitration field as a number: the lower wins the bus. An 11-bit frame beats
 * the 29-bit ones of its base identifier (their SRR and IDE bits are recessive), a data
 * frame the remote frame of its identifier. */
static uint32_t arbitration_key(const co_frame_t *frame)
{
    uint32_t rtr = (frame->flags & CO_FRAME_RTR) ? 1u : 0u;
    if (frame->flags & CO_FRAME_EXT) {
        return ((frame->id >> 18) & 0x7FFu) << 21 | 3u << 19 | (frame->id & 0x3FFFFu) << 1 | rtr;
    }
    return (frame->id & 0x7FFu) << 21 | rtr << 20;
}

/* ---- Transmit (the critical section held). */

/* After the frames of its priority and before the lower ones: first in, first out among
 * equals. The caller checked that there is room. Returns the frame's place (0: the head). */
static uint8_t queue_insert(co_cm_can_t *can, const co_frame_t *frame)
{
    uint32_t key = arbitration_key(frame);
    uint8_t at = can->tx_count;
    while (at > 0 && arbitration_key(&can->tx_queue[at - 1]) > key) {
        can->tx_queue[at] = can->tx_queue[at - 1];
        at--;
    }
    can->tx_queue[at] = *frame;
    can->tx_count++;
    return at;
}

/* Move frames from the head of the queue into mailboxes while the driver takes them. */
static void queue_pump(co_cm_can_t *can)
{
    uint8_t taken = 0;
    while (taken < can->tx_count && can->ops->mailbox_put(can->hw, &can->tx_queue[taken])) {
        taken++;
    }
    if (taken > 0) {
        for (uint8_t i = taken; i < can->tx_count; i++) {
            can->tx_queue[i - taken] = can->tx_queue[i];
        }
        can->tx_count = (uint8_t)(can->tx_count - taken);
#if !defined(CO_TEST_FAULT_NO_TX_WAKE) /* test-only: the node never hears of the room */
        if (can->tx_refused) {         /* the node holds frames: room for them now */
            can->tx_refused = false;
            can->tx_room = true;
        }
#endif
    }
}

/* Test-only faults (tests/cortex-m builds each, to show that its test catches it): the
 * transmit path of other stacks' ports. CO_TEST_FAULT_TX_WAIT: the send waits for a free
 * mailbox (the examples' busy loop; here it gives up after a while, where a real one waits
 * for the bus). CO_TEST_FAULT_TX_DROP: a full mailbox set loses the frame.
 * CO_TEST_FAULT_TX_SPLIT: the mailboxes and the queue in two critical sections (the
 * transmit-complete interrupt can come between). */
#if defined(CO_TEST_FAULT_TX_WAIT)
static bool wait_for_mailbox(co_cm_can_t *can, const co_frame_t *frame)
{
    for (uint32_t spin = 0; spin < 100000u; spin++) {
        co_cm_irq_t irq = co_cm_critical_enter();
        bool put = can->tx_count == 0 && can->ops->mailbox_put(can->hw, frame);
        bool queued = can->tx_count != 0;
        co_cm_critical_leave(irq);
        if (put || queued) {
            return put;
        }
    }
    return false;
}
#endif

static co_err_t cm_tx(void *ctx, const co_frame_t *frame)
{
    co_cm_can_t *can = ctx;
    co_err_t err = CO_OK;
#if defined(CO_TEST_FAULT_TX_WAIT)
    if (wait_for_mailbox(can, frame)) {
        return CO_OK;
    }
#endif
    co_cm_irq_t irq = co_cm_critical_enter();
    if (can->tx_count == 0) {
        if (!can->ops->mailbox_put(can->hw, frame)) {
#if defined(CO_TEST_FAULT_TX_DROP)
            co_cm_critical_leave(irq);
            return CO_OK;
#elif defined(CO_TEST_FAULT_TX_SPLIT)
            co_cm_critical_leave(irq);
            irq = co_cm_critical_enter();
#endif
            (void)queue_insert(can, frame);
        }
    } else if (can->tx_count < CO_CM_TX_QUEUE_LEN) {
        /* The head waits for a mailbox: so does the new frame, unless it is the new head
         * (a mailbox that refused the old head for its identifier may take it). */
        if (queue_insert(can, frame) == 0) {
            queue_pump(can);
        }
    } else {
        can->tx_refused = true;
        err = CO_ERR_BUSY;
    }
    co_cm_critical_leave(irq);
    return err;
}

void co_cm_isr_tx_done(co_cm_port_t *port)
{
    co_cm_can_t *can = &port->can;
    co_cm_irq_t irq = co_cm_critical_enter();
    queue_pump(can);
    co_cm_critical_leave(irq);
}

/* ---- Receive. */

void co_cm_isr_rx(co_cm_port_t *port, const co_frame_t *frame)
{
    co_cm_can_t *can = &port->can;
    uint16_t head = can->rx_head;
    if ((uint16_t)(head - can->rx_tail) >= CO_CM_RX_RING_LEN) {
        can->rx_lost++; /* the ring is full: the newest frame is lost */
        return;
    }
    can->rx_ring[head % CO_CM_RX_RING_LEN] = *frame;
    co_cm_barrier(); /* the slot, then the index that hands it over */
    can->rx_head = (uint16_t)(head + 1u);
}

void co_cm_isr_rx_overrun(co_cm_port_t *port) { port->can.rx_lost++; }

/* ---- Bus states. */

void co_cm_isr_bus_state(co_cm_port_t *port, co_cm_can_state_t state)
{
    co_cm_can_t *can = &port->can;
    co_cm_irq_t irq = co_cm_critical_enter();
    co_cm_can_state_t was = (co_cm_can_state_t)can->state;
    uint8_t events = 0;
    if (state == CO_CM_CAN_BUS_OFF) {
        events = was != CO_CM_CAN_BUS_OFF ? EV_OFF : 0u;
    } else if (was == CO_CM_CAN_BUS_OFF) {
        events = state == CO_CM_CAN_ERROR_PASSIVE ? (EV_RECOVERED | EV_PASSIVE) : EV_RECOVERED;
    } else if (state == CO_CM_CAN_ERROR_PASSIVE) {
        events = was != CO_CM_CAN_ERROR_PASSIVE ? EV_PASSIVE : 0u;
    } else if (was == CO_CM_CAN_ERROR_PASSIVE) {
        events = EV_ACTIVE; /* error active or warning: below 128 again */
    }
    can->state = (uint8_t)state;
    can->events = (uint8_t)(can->events | events);
    co_cm_critical_leave(irq);
}

/* Tell the node what the interrupt saw since the last time, in the order it can happen:
 * bus-off before its recovery; of error passive and back, the latest last. */
static bool report_bus_events(co_cm_can_t *can)
{
    co_cm_irq_t irq = co_cm_critical_enter();
    uint8_t events = can->events;
    co_cm_can_state_t state = (co_cm_can_state_t)can->state;
    can->events = 0;
    co_cm_critical_leave(irq);
    if (events & EV_OFF) {
        co_node_bus_event(can->node, CO_BUS_OFF);
    }
    if (events & EV_RECOVERED) {
        co_node_bus_event(can->node, CO_BUS_OFF_RECOVERED);
    }
    bool passive_now = state == CO_CM_CAN_ERROR_PASSIVE;
    if ((events & EV_PASSIVE) && !passive_now) {
        co_node_bus_event(can->node, CO_BUS_ERROR_PASSIVE);
    }
    if (events & EV_ACTIVE) {
        co_node_bus_event(can->node, CO_BUS_ERROR_ACTIVE);
    }
    if ((events & EV_PASSIVE) && passive_now) {
        co_node_bus_event(can->node, CO_BUS_ERROR_PASSIVE);
    }
    return events != 0;
}

/* ---- Filters. */

static void cm_routes_changed(void *ctx) { ((co_cm_can_t *)ctx)->filters_stale = true; }

/* The node's routes, each identifier once (they come sorted), to the driver; accept-all
 * when there are more than the list holds. */
static void program_filters(co_cm_can_t *can)
{
    uint32_t ids[CO_CM_FILTER_IDS_MAX];
    uint32_t count = co_node_route_count(can->node);
    size_t n = 0;
    bool fits = true;
    for (uint32_t i = 0; i < count; i++) {
        uint32_t id = co_node_route_id(can->node, i);
        if (n > 0 && ids[n - 1] == id) {
            continue;
        }
        if (n == CO_CM_FILTER_IDS_MAX) {
            fits = false;
            break;
        }
        ids[n++] = id;
    }
    can->filters_stale = false;
    (void)can->ops->set_filters(can->hw, fits ? ids : NULL, fits ? n : 0);
}

/* ---- The main loop. */

void co_cm_can_init(co_cm_can_t *can, const co_cm_can_ops_t *ops, void *hw)
{
    *can = (co_cm_can_t){.ops = ops, .hw = hw, .state = CO_CM_CAN_ERROR_ACTIVE};
}

co_driver_t co_cm_can_driver(co_cm_can_t *can)
{
    return (co_driver_t){.tx = cm_tx, .on_routes_changed = cm_routes_changed, .ctx = can};
}

void co_cm_can_bind(co_cm_can_t *can, co_node_t *node)
{
    can->node = node;
    can->filters_stale = true;
}

bool co_cm_can_process(co_cm_can_t *can, uint64_t now_us)
{
    bool did = false;
    if (!can->node) {
        return false;
    }
    if (can->filters_stale) {
        program_filters(can);
        did = true;
    }
    uint16_t tail = can->rx_tail;
    for (uint32_t n = 0; n < CO_CM_RX_RING_LEN && tail != can->rx_head; n++) {
        co_cm_barrier(); /* the slot after the index that handed it over */
        co_node_ingest(can->node, now_us, &can->rx_ring[tail % CO_CM_RX_RING_LEN]);
        co_cm_barrier(); /* done with the slot before giving it back */
        tail = (uint16_t)(tail + 1u);
        can->rx_tail = tail;
        did = true;
    }
    uint32_t lost = can->rx_lost;
    if (lost != can->rx_lost_told) {
        can->rx_lost_told = lost;
        co_node_bus_event(can->node, CO_BUS_RX_OVERRUN);
        did = true;
    }
    if (can->events && report_bus_events(can)) {
        did = true;
    }
    if (can->tx_room) {
        can->tx_room = false; /* (a single byte: the interrupt only ever sets it) */
        did = true;           /* the caller's poll hands the node's frames over */
    }
    return did;
}

bool co_cm_can_idle(const co_cm_can_t *can)
{
    return can->rx_head == can->rx_tail && can->rx_lost == can->rx_lost_told && !can->events &&
           !can->tx_room && !can->filters_stale;
}

co_err_t co_cm_can_set_bit_rate(co_cm_can_t *can, uint32_t bit_rate)
{
    return can->ops->set_bit_rate(can->hw, bit_rate);
}

uint32_t co_cm_lss_bit_rate(uint8_t index)
{
    static const uint16_t kbit[9] = {1000, 800, 500, 250, 125, 0, 50, 20, 10};
    return index < 9 ? kbit[index] * 1000u : 0u;
}

void co_cm_can_lss_bit_timing(void *ctx, uint8_t index)
{
    uint32_t rate = co_cm_lss_bit_rate(index);
    if (rate != 0) {
        (void)co_cm_can_set_bit_rate(ctx, rate);
    }
}
