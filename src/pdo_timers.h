/* SPDX-License-Identifier: Apache-2.0 */
/*
 * src/pdo_timers.h -- the PDO timers of pdo_timers.c (inhibit time, event timer, RPDO
 * deadline) as the rest of the PDO family calls them; with CO_CONFIG_PDO_TIMERS 0, stand-ins
 * that do nothing. Included by pdo_internal.h only. Not installed.
 */
#ifndef CANOLA_PDO_TIMERS_H
#define CANOLA_PDO_TIMERS_H

/* The timers' due work at `now_us` (the node's poll: pdo_rx.c, which hands the TPDOs' to
 * pdo_tx.c); their next deadlines go to co_node_schedule. Without timers PDOs have nothing
 * to wait for. */
#if CO_CONFIG_PDO_TIMERS
void co_pdo_poll(co_node_t *node, uint64_t now_us);
static inline void pdo_timers_restart(co_pdo_t *p)
{
    p->next_us = CO_TIME_NEVER;
    p->inhibit_until_us = 0;
}
/* pdo.c: entering operational / new parameters, an event-driven TPDO's event timer starts. */
void tpdo_start(co_node_t *node, co_pdo_t *p);
/* Inside the inhibit time: true, and a poll is scheduled for its end. */
bool tpdo_inhibited(co_node_t *node, const co_pdo_t *p);
void tpdo_event_sent(co_node_t *node, co_pdo_t *p); /* inhibit time and event timer restart */
void rpdo_received(co_node_t *node, co_pdo_t *p);   /* deadline restarts, a missed one ends */
/* At the poll: an RPDO's deadline missed is reported (EMCY 0x8250, the error behaviour);
 * pdo_tx.c: an event-driven TPDO's event timer and pending event. */
void rpdo_deadline(co_node_t *node, co_pdo_t *p, uint64_t now_us);
void tpdo_poll(co_node_t *node, co_pdo_t *p, uint64_t now_us);
#else
static inline void co_pdo_poll(co_node_t *node, uint64_t now_us)
{
    (void)node;
    (void)now_us;
}
static inline void pdo_timers_restart(co_pdo_t *p) { (void)p; }
static inline void tpdo_start(co_node_t *node, co_pdo_t *p)
{
    (void)node;
    (void)p;
}
static inline bool tpdo_inhibited(co_node_t *node, const co_pdo_t *p)
{
    (void)node;
    (void)p;
    return false;
}
static inline void tpdo_event_sent(co_node_t *node, co_pdo_t *p)
{
    (void)node;
    (void)p;
}
static inline void rpdo_received(co_node_t *node, co_pdo_t *p)
{
    (void)node;
    (void)p;
}
#endif

#endif /* CANOLA_PDO_TIMERS_H */
