/* SPDX-License-Identifier: Apache-2.0 */
/*
 * canola/sim.h -- a simulated CAN bus with a virtual clock (port/sim).
 *
 * Many nodes in one process, deterministic, as fast as the CPU allows. Each
 * participant is a port: either a canola node (the port is its driver) or a raw
 * port whose frames a test sends and receives directly. co_sim_run_until()
 * advances the virtual clock from event to event: node deadlines (co_node_poll)
 * and frame completions. Nothing depends on wall time.
 *
 * Timing: with bitrate 0 a frame arrives at the instant it is sent, in send
 * order. With a bitrate (10 000 .. 1 000 000 bit/s) the bus is modelled as CAN
 * is: when it is idle, the pending frame with the lowest identifier wins
 * arbitration (an 11-bit frame beats a 29-bit one with the same base ID); it
 * occupies the bus for its exact length in bits, bit stuffing included (the
 * stuff bits of its real SOF..CRC bit stream), plus 3 bits of interframe space,
 * and reaches the receivers at its end. Bus load is the fraction of time the
 * bus was occupied.
 *
 * Acceptance filtering: a node port receives only frames whose COB-ID its node
 * routes (co_node_accepts), as a CAN controller's filters would pass them. A raw
 * port receives every frame. A sender never receives its own frame. Ports receive a
 * frame in the order they were attached.
 *
 * Delivery cost: the bus keeps one index from 11-bit identifier to the node ports whose
 * routes take it (and the set of node ports with a 29-bit route), so a frame costs the
 * same whatever the number of ports that do not want it. A node port joins the index at
 * the first route notification of its node after co_sim_port_bind: the driver of
 * co_sim_port_driver notifies (on_routes_changed); a driver of your own calls
 * co_sim_port_routes_changed from its on_routes_changed. Until then, and for a node whose
 * driver never notifies, the port asks co_node_accepts for every frame (the same
 * behaviour, at the cost of one call per port and frame).
 *
 * Each port has `mailboxes` transmit slots (default 3, like most controllers):
 * while that many of its frames wait for the bus, tx answers CO_ERR_BUSY and the
 * node queues the frame itself; the port polls its node when a slot frees.
 *
 * Faults (all reproducible from the seed): drop the n-th frame sent on the bus,
 * drop each frame with probability p, corrupt each frame with probability p (one
 * data bit flipped in what the receivers get: corruption that CAN's CRC missed),
 * delay every frame's start by d us, take a port bus-off (it sends nothing, its
 * frames are discarded and it receives nothing).
 *
 * Trace: every frame delivered is reported as one line in candump log format,
 * `(0.001000) sim0 701#05` (29-bit IDs with 8 hex digits, RTR as `#R` plus the
 * length digit when it is not 0), to a callback.
 *
 * Not part of the portable core: this file may use the C library freely.
 * Memory: the bus and ports are owned by the caller; no allocation.
 */
#ifndef CANOLA_SIM_H
#define CANOLA_SIM_H

#include "canola/node.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef CO_SIM_PORTS_MAX
#define CO_SIM_PORTS_MAX 130
#endif
#ifndef CO_SIM_PENDING_MAX
#define CO_SIM_PENDING_MAX 1024
#endif

#define CO_SIM_PORT_WORDS ((CO_SIM_PORTS_MAX + 63) / 64)

typedef struct co_sim_bus co_sim_bus_t;

/** Receive callback of a raw port. */
typedef void (*co_sim_rx_fn)(void *ctx, uint64_t now_us, const co_frame_t *frame);

/** Trace callback: one candump-format line without newline. */
typedef void (*co_sim_trace_fn)(void *ctx, const char *line);

typedef struct co_sim_port {
    co_sim_bus_t *bus;
    co_node_t *node; /**< node behind this port, or NULL for a raw port */
    co_sim_rx_fn rx; /**< raw port receive callback */
    void *rx_ctx;
    co_sim_rx_fn sent;    /**< raw port: one of its frames left the wire (rx_ctx; NULL: none) */
    uint64_t node_due_us; /**< next co_node_poll deadline of the node */
    uint8_t mailboxes;    /**< transmit slots (1..255; attach sets 3: change it after) */
    uint8_t in_flight;    /**< own frames pending on the bus */
    uint8_t index;        /**< position on the bus */
    bool bus_off;
    bool indexed; /**< the node notifies its route changes: the bus index holds its routes */
} co_sim_port_t;

/** A set of ports, by position on the bus. Internal. */
typedef struct co_sim_portset {
    uint64_t bits[CO_SIM_PORT_WORDS];
} co_sim_portset_t;

/** A frame waiting for (or on) the bus. Internal. */
typedef struct co_sim_pending {
    co_frame_t frame;
    uint64_t ready_us; /**< earliest start of transmission */
    uint32_t seq;      /**< send order, breaks ties */
    uint32_t bits;     /**< co_sim_frame_bits of the frame, computed once when sent */
    uint32_t key;      /**< its arbitration field, computed once when sent */
    uint8_t port;
} co_sim_pending_t;

/** Statistics of the bus since co_sim_bus_init. */
typedef struct co_sim_stats {
    uint64_t frames;    /**< frames that completed on the bus */
    uint64_t bits;      /**< their bits, stuffing and interframe space included */
    uint64_t busy_us;   /**< time the bus was occupied (timing model only) */
    uint64_t dropped;   /**< frames removed by fault injection */
    uint64_t corrupted; /**< frames altered by fault injection */
    uint64_t refused;   /**< tx attempts answered busy (mailboxes full) */
    uint64_t overflow;  /**< frames lost because the pending list was full */
} co_sim_stats_t;

struct co_sim_bus {
    uint64_t now_us;
    uint32_t bitrate;        /**< 0 = instant delivery */
    uint64_t idle_at_us;     /**< timing model: when the bus is free again ... */
    uint32_t idle_rem;       /**< ... exactly: idle_at_us + idle_rem / bitrate us (no drift) */
    bool transmitting;       /**< timing model: `on_bus` occupies the bus until then */
    co_sim_pending_t on_bus; /**< the frame on the wire (its mailbox is still taken) */
    co_sim_port_t *ports[CO_SIM_PORTS_MAX];
    uint32_t port_count;
    uint64_t due_min_us; /**< at most every node's node_due_us: "no poll due" in one test */
    /* Frames waiting for the bus: a binary heap, the next to go first (the timing model: the
     * lowest arbitration key; instant delivery: the oldest), with ties to the oldest. */
    co_sim_pending_t pending[CO_SIM_PENDING_MAX];
    uint32_t pending_count;
    uint32_t seq;
    /* Delivery index (see above): for each 11-bit identifier the indexed node ports whose
     * routes take it, the indexed node ports with a 29-bit route, and the ports that see
     * every frame (raw ports; node ports not indexed, which ask co_node_accepts). */
    co_sim_portset_t receivers[CO_ID_STD_MAX + 1];
    co_sim_portset_t ext_receivers;
    co_sim_portset_t every_frame;
    /* Frame length on the wire a byte at a time: CRC-15 of a byte, and the stuff bits of a
     * byte from each state of the stuffing (level and run of the latest bits). */
    uint16_t crc15_table[256];
    uint8_t stuff_table[10][256];
    /* faults */
    uint64_t rng;
    uint64_t drop_nth; /**< 0 = off; counts frames sent on the bus from 1 */
    uint64_t sent_count;
    double drop_p;
    double corrupt_p;
    uint64_t delay_us;
    /* trace */
    co_sim_trace_fn trace;
    void *trace_ctx;
    char name[16];
    co_sim_stats_t stats;
};

/** Initialise an empty bus at virtual time 0. `bitrate` 0 = instant, else 10000..1000000.
 *  Returns CO_ERR_ARG for another bitrate. The interface name in traces is "sim0". */
co_err_t co_sim_bus_init(co_sim_bus_t *bus, uint32_t bitrate);

/** Attach a port for a node. Call before co_node_init: use co_sim_port_driver(port) as
 *  the node's driver, then co_sim_port_bind(port, node). Returns CO_ERR_FULL past
 *  CO_SIM_PORTS_MAX ports. */
co_err_t co_sim_port_attach(co_sim_bus_t *bus, co_sim_port_t *port);
co_driver_t co_sim_port_driver(co_sim_port_t *port);
void co_sim_port_bind(co_sim_port_t *port, co_node_t *node);

/** For a driver of your own around a node port (its tx calls co_sim_send): call this from
 *  the driver's on_routes_changed, so that the port's node receives through the bus's
 *  index (see Delivery cost above). */
void co_sim_port_routes_changed(co_sim_port_t *port);

/** Attach a raw port: `rx` receives every frame others send. Set `port->sent` after it to
 *  hear when the port's own frames complete (a CAN controller's transmit-complete). */
co_err_t co_sim_port_attach_raw(co_sim_bus_t *bus, co_sim_port_t *port, co_sim_rx_fn rx, void *ctx);

/** Send a frame from a port at the bus's current time (raw ports; nodes send through
 *  their driver). Returns CO_ERR_BUSY when the port's mailboxes are full, CO_OK else
 *  (also when the port is bus-off: the frame is discarded). */
co_err_t co_sim_send(co_sim_port_t *port, const co_frame_t *frame);

/** Advance virtual time to `until_us`, delivering frames and polling nodes on the way.
 *  Returns CO_OK, or CO_ERR_STATE when more than a million events happened at a single
 *  instant (a frame storm in instant mode: the run stops there). */
co_err_t co_sim_run_until(co_sim_bus_t *bus, uint64_t until_us);

/** Faults. p in [0, 1]; n = 0 turns drop_nth off. */
void co_sim_seed(co_sim_bus_t *bus, uint64_t seed);
void co_sim_drop_nth(co_sim_bus_t *bus, uint64_t n);
void co_sim_drop_probability(co_sim_bus_t *bus, double p);
void co_sim_corrupt_probability(co_sim_bus_t *bus, double p);
void co_sim_delay(co_sim_bus_t *bus, uint64_t delay_us);
void co_sim_set_bus_off(co_sim_port_t *port, bool bus_off);

/** Trace every delivered frame to `fn` (NULL stops tracing). */
void co_sim_set_trace(co_sim_bus_t *bus, co_sim_trace_fn fn, void *ctx);

/** Format a frame as a candump log line into buf (returns buf). */
char *co_sim_format(char *buf, size_t cap, uint64_t t_us, const char *ifname,
                    const co_frame_t *frame);

/** Length of a frame on the wire in bits: SOF to end of EOF with its real stuff bits,
 *  plus 3 bits of interframe space. */
uint32_t co_sim_frame_bits(const co_frame_t *frame);

/** Bus statistics, and the load (busy time / elapsed time, 0..1) since time 0. */
const co_sim_stats_t *co_sim_stats(const co_sim_bus_t *bus);
double co_sim_load(const co_sim_bus_t *bus);

#ifdef __cplusplus
}
#endif
#endif /* CANOLA_SIM_H */
