/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/cm_port.h -- canola on a Cortex-M (M0, M0+, M3, M4, M7, M33): the port object, its
 * time base, and the main loop that sleeps between deadlines.
 *
 * A board gives the port three things:
 *   a CAN controller driver: co_cm_can_ops_t (cm_can.h), whose interrupt handlers call
 *     co_cm_isr_rx / _rx_overrun / _tx_done / _bus_state with this port;
 *   a time base (co_cm_time_t): the time in microseconds, 64 bits that never wrap, and
 *     optionally an interrupt at a deadline. SysTick is one on any core that has it
 *     (cm_systick.h: its interrupt every period wakes the loop); a free-running hardware
 *     counter with a compare interrupt is another (co_cm_clock_extend below widens it);
 *   optionally, parameter storage for the node (cm_flash_storage.h: two flash slots).
 *
 * The split between interrupts and the main loop:
 *   interrupts     the CAN controller's (a frame into the receive ring, a freed mailbox
 *                  refilled from the transmit queue, a bus state noted) and the time base's;
 *                  they never call the node.
 *   the main loop  co_cm_port_step: the CAN side's work (the ring's frames to co_node_ingest,
 *                  bus events, filters: co_cm_can_process), then co_node_poll, which returns
 *                  the next deadline; co_cm_port_sleep: WFI until that deadline or an
 *                  interrupt, unless work came in meanwhile (checked with PRIMASK set, so an
 *                  interrupt between the check and the WFI still ends the WFI).
 *
 *     for (;;) {                                  co_cm_port_run() is exactly this
 *         uint64_t deadline = co_cm_port_step(&port);
 *         ... the application's own work ...
 *         co_cm_port_sleep(&port, deadline);
 *     }
 *
 * Threading: everything here runs in the main loop; only the co_cm_isr_* calls come from
 * interrupts. The critical section is cm_critical.h's: PRIMASK, or BASEPRI on ARMv7-M and
 * ARMv8-M Mainline when CO_CM_BASEPRI is set (interrupts above that priority stay live and
 * must not call the port). Memory: co_cm_port_t (the CAN side's ring and queue: about
 * 16 * CO_CM_RX_RING_LEN + 12 * CO_CM_TX_QUEUE_LEN + 40 bytes); no allocation.
 */
#ifndef CANOLA_CM_PORT_H
#define CANOLA_CM_PORT_H

#include <stdbool.h>
#include <stdint.h>

#include "canola/cm_can.h"
#include "canola/node.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The time base. */
typedef struct co_cm_time {
    /** Microseconds since an arbitrary start; only grows. Main loop. */
    uint64_t (*now_us)(void *ctx);
    /** Optional: raise an interrupt at `deadline_us` (or earlier: the loop checks again) to
     *  end the WFI; CO_TIME_NEVER: none needed. NULL: the time base interrupts often enough
     *  by itself (a periodic tick), so a deadline is met to within one period. Called with
     *  interrupts masked, just before the WFI. */
    void (*wake_at)(void *ctx, uint64_t deadline_us);
    void *ctx;
} co_cm_time_t;

/** The port: its CAN side (where the driver's interrupt calls find it), time base and node. */
struct co_cm_port {
    co_cm_can_t can;
    co_cm_time_t time;
    co_node_t *node;
};

/** Prepare the port for the CAN driver `ops` on `hw` (the driver's own init comes first)
 *  and the time base `time`. Then: the node's config takes co_cm_can_driver(&port->can),
 *  co_node_init, co_cm_port_bind, co_node_start. */
void co_cm_port_init(co_cm_port_t *port, const co_cm_can_ops_t *ops, void *hw, co_cm_time_t time);

/** The node the port serves: received frames, bus events and polls go to it. */
void co_cm_port_bind(co_cm_port_t *port, co_node_t *node);

/** One pass of the main loop: the CAN side's work (co_cm_can_process), then co_node_poll.
 *  Returns the next deadline (absolute, microseconds; CO_TIME_NEVER: none). */
uint64_t co_cm_port_step(co_cm_port_t *port);

/** Sleep (WFI) until `deadline_us` or an interrupt, unless CAN work waits or the deadline
 *  has passed: returns at once then. Returns true when it slept. */
bool co_cm_port_sleep(co_cm_port_t *port, uint64_t deadline_us);

/** The main loop: step and sleep, for ever. */
_Noreturn void co_cm_port_run(co_cm_port_t *port);

/** Widen a free-running microsecond counter to 64 bits: `count` is its value now, `mask`
 *  its range (0xFFFF for 16 bits, 0xFFFFFFFF for 32). The low bits of `*now_us` are the
 *  count last seen, so it must be read at least once per wrap (71 minutes for 32 bits: a
 *  wake_at caps its sleep below that). Main loop. */
static inline uint64_t co_cm_clock_extend(uint64_t *now_us, uint32_t count, uint32_t mask)
{
    *now_us += (count - (uint32_t)*now_us) & mask;
    return *now_us;
}

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_CM_PORT_H */
