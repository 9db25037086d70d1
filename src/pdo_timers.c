/* SPDX-License-Identifier: Apache-2.0 */
/*
 * pdo_timers.c -- the PDO timers (see canola/pdo.h): the TPDO inhibit time (0x1800+n sub3)
 * and event timer (sub5) as a TPDO sends, and RPDO deadline monitoring (0x1400+n sub5): a
 * deadline restarted, a missed one reported. It sends nothing (pdo_tx.c's poll sends what
 * is due) and calls only the family's base, pdo.c (which loads the timers' parameters and
 * starts the event timer). Left out with CO_CONFIG_PDO_TIMERS 0 (pdo_timers.h): those sub-indices
 * are then plain entries.
 */
#include "pdo_internal.h"

#if CO_CONFIG_PDO_TIMERS

#define EMCY_RPDO_TIMEOUT 0x8250u

bool tpdo_inhibited(co_node_t *node, const co_pdo_t *p)
{
    if (node->now_us >= p->inhibit_until_us) {
        return false;
    }
    co_node_schedule(node, p->inhibit_until_us);
    return true;
}

void tpdo_event_sent(co_node_t *node, co_pdo_t *p)
{
    uint32_t inhibit_us = (uint32_t)p->inhibit * 100u; /* 32-bit: fits */
    p->inhibit_until_us = node->now_us + inhibit_us;
    tpdo_start(node, p);
}

/* A frame of usable length arrived: the deadline restarts, a missed one is over. */
void rpdo_received(co_node_t *node, co_pdo_t *p)
{
    if (p->event_ms != 0) {
        p->next_us = node->now_us + co_ms_to_us(p->event_ms);
        co_node_schedule(node, p->next_us);
    }
    if (pdo_has(p, PDO_F_TIMED_OUT)) {
        pdo_clear(p, PDO_F_TIMED_OUT);
        if (!rpdo_other_has(node, p, PDO_F_TIMED_OUT)) {
            (void)co_emcy_clear(node, EMCY_RPDO_TIMEOUT);
        }
    }
}

/* Each PDO's next deadline goes to co_node_schedule (the node's poll takes the earliest):
 * one call each instead of a 64-bit minimum carried through the loops. */
void rpdo_deadline(co_node_t *node, co_pdo_t *p, uint64_t now_us)
{
    if (now_us < p->next_us) {
        co_node_schedule(node, p->next_us);
        return;
    }
    p->next_us = CO_TIME_NEVER; /* reported once, until the next RPDO */
    pdo_set(p, PDO_F_TIMED_OUT);
    (void)co_emcy_raise(node, EMCY_RPDO_TIMEOUT, NULL);
    node->wiring->error_behaviour(node); /* the error behaviour of 0x1029 (kernel.h) */
}

#endif
