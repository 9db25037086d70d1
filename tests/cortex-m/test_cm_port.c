/* SPDX-License-Identifier: Apache-2.0 */
/*
 * test_cm_port.c -- port/cortex-m's main loop (cm_port.c) and time bases (cm_systick.c,
 * co_cm_clock_extend) on the host: SysTick as a register model whose wrap can be pending
 * while the time is read; the loop's step handing the receive ring to the node and its
 * sleep, which must not sleep with work waiting or a deadline passed, and must ask the time
 * base for a wake-up at the deadline it was given.
 */
#include "canola/cm_port.h"
#include "canola/cm_systick.h"
#include "check.h"
#include "cm_host.h"
#include "harness.h"

/* ---- SysTick as registers */

static co_cm_systick_regs_t g_regs;
static volatile uint32_t g_icsr;
static volatile uint32_t g_shpr3;

#define PENDSTSET (1u << 26)

static void test_systick_start(void)
{
    co_cm_systick_t t;
    CHECK_EQ(co_cm_systick_start_at(&t, &g_regs, &g_icsr, &g_shpr3, 168000000u, 1000), CO_OK);
    CHECK_EQ(g_regs.rvr, 167999);
    CHECK_EQ(g_regs.csr, 7); /* enabled, interrupt, core clock */
    CHECK_EQ(g_shpr3 >> 24, 0xFF);
    CHECK_EQ(co_cm_systick_start_at(&t, &g_regs, &g_icsr, &g_shpr3, 16500000u, 1000),
             CO_ERR_ARG); /* not whole MHz */
    CHECK_EQ(co_cm_systick_start_at(&t, &g_regs, &g_icsr, &g_shpr3, 168000000u, 100000),
             CO_ERR_ARG); /* 16.8 M ticks: more than 24 bits */
    CHECK_EQ(co_cm_systick_start_at(&t, &g_regs, &g_icsr, &g_shpr3, 168000000u, 99000), CO_OK);
}

static void test_systick_time(void)
{
    co_cm_systick_t t;
    CHECK_EQ(co_cm_systick_start_at(&t, &g_regs, &g_icsr, &g_shpr3, 16000000u, 1000), CO_OK);
    g_regs.cvr = 15999; /* just reloaded */
    CHECK_EQ(co_cm_systick_now_us(&t), 0);
    g_regs.cvr = 8000 - 1; /* half way */
    CHECK_EQ(co_cm_systick_now_us(&t), 500);
    co_cm_systick_isr(&t);
    co_cm_systick_isr(&t);
    g_regs.cvr = 15999 - 16 * 250;
    CHECK_EQ(co_cm_systick_now_us(&t), 2250);
    /* a wrap while the interrupt is masked: pending, the counter already from the reload */
    g_icsr = PENDSTSET;
    g_regs.cvr = 15999 - 16 * 3;
    CHECK_EQ(co_cm_systick_now_us(&t), 3003);
    g_icsr = 0;
    co_cm_systick_isr(&t);
    CHECK_EQ(co_cm_systick_now_us(&t), 3003);
    /* a long run of periods: no drift, no wrap of the 64-bit count */
    for (uint32_t i = 0; i < 5000000u; i++) {
        co_cm_systick_isr(&t);
    }
    CHECK_EQ(co_cm_systick_now_us(&t), 5000003003ull);
}

static void test_clock_extend(void)
{
    uint64_t now = 0;
    CHECK_EQ(co_cm_clock_extend(&now, 0xFFF0u, 0xFFFFu), 0xFFF0u);
    CHECK_EQ(co_cm_clock_extend(&now, 0x0010u, 0xFFFFu), 0x10010u); /* 16 bits wrapped */
    CHECK_EQ(co_cm_clock_extend(&now, 0x0010u, 0xFFFFu), 0x10010u);
    now = 0xFFFFFFF0u;
    CHECK_EQ(co_cm_clock_extend(&now, 0x00000005u, 0xFFFFFFFFu), 0x100000005ull);
    now = 0x3FFFFFFF0ull;
    CHECK_EQ(co_cm_clock_extend(&now, 0x00000001u, 0xFFFFFFFFu), 0x400000001ull);
}

/* ---- the main loop */

typedef struct fake_board {
    uint64_t now_us;
    uint64_t wake_at;
    uint32_t wfi;
    co_frame_t sent[64];
    uint32_t sent_count;
    co_frame_t arrives_in_wfi; /* a frame the CAN interrupt brings during the WFI */
    bool arrives;
    co_cm_port_t *port;
} fake_board_t;

static fake_board_t g_board;

static uint32_t count_id(uint32_t id)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < g_board.sent_count; i++) {
        n += g_board.sent[i].id == id;
    }
    return n;
}

static bool board_put(void *hw, const co_frame_t *frame)
{
    fake_board_t *b = hw;
    if (b->sent_count < 64) {
        b->sent[b->sent_count++] = *frame;
    }
    return true;
}

static bool board_filters(void *hw, const uint32_t *ids, size_t n)
{
    (void)hw;
    (void)ids;
    (void)n;
    return true;
}

static co_err_t board_bit_rate(void *hw, uint32_t bit_rate)
{
    (void)hw;
    (void)bit_rate;
    return CO_OK;
}

static void board_counters(void *hw, uint8_t *tec, uint8_t *rec)
{
    (void)hw;
    *tec = 0;
    *rec = 0;
}

static const co_cm_can_ops_t k_ops = {board_put, board_filters, board_bit_rate, board_counters};

static uint64_t board_now(void *ctx) { return ((fake_board_t *)ctx)->now_us; }

static void board_wake_at(void *ctx, uint64_t deadline_us)
{
    ((fake_board_t *)ctx)->wake_at = deadline_us;
}

/* The WFI: time moves to the wake-up (or 1 ms), and a frame may come in. */
void co_cm_wait_for_interrupt(void);
void co_cm_wait_for_interrupt(void)
{
    CHECK(cm_host_masked()); /* asked with interrupts masked */
    g_board.wfi++;
    if (g_board.arrives) { /* 10 us in, the CAN interrupt ends the WFI */
        g_board.arrives = false;
        g_board.now_us += 10;
        co_cm_isr_rx(g_board.port, &g_board.arrives_in_wfi);
        return;
    }
    g_board.now_us = g_board.wake_at != CO_TIME_NEVER ? g_board.wake_at : g_board.now_us + 1000;
}

/* A node (heartbeat every `hb_ms`) started on a port on the fake board, at time 0. */
static void start_on_port(co_cm_port_t *port, test_node_t *t, uint16_t hb_ms)
{
    cm_host_reset();
    g_board = (fake_board_t){.port = port, .wake_at = CO_TIME_NEVER};
    co_cm_port_init(port, &k_ops, &g_board,
                    (co_cm_time_t){.now_us = board_now, .wake_at = board_wake_at, .ctx = &g_board});
    CHECK_EQ(test_node_init(t, 5, hb_ms), CO_OK);
    t->node.cfg.driver = co_cm_can_driver(&port->can);
    co_cm_port_bind(port, &t->node);
    CHECK_EQ(co_node_start(&t->node, 0), CO_OK);
}

static void test_step_and_sleep(void)
{
    static co_cm_port_t port;
    static test_node_t t;
    start_on_port(&port, &t, 100);
    CHECK_EQ(g_board.sent_count, 1); /* the boot-up */

    uint64_t deadline = co_cm_port_step(&port);
    CHECK_EQ(deadline, 100000); /* the first heartbeat */
    /* idle: it sleeps, with a wake-up at the deadline */
    CHECK(co_cm_port_sleep(&port, deadline));
    CHECK_EQ(g_board.wake_at, 100000);
    CHECK_EQ(g_board.wfi, 1);
    co_cm_port_step(&port);
    CHECK_EQ(g_board.sent_count, 2);
    CHECK_EQ(g_board.sent[1].id, 0x705); /* the heartbeat, on time */

    /* a frame arrives after the step, before the sleep: no sleep, the next step takes it */
    co_frame_t sdo = frm(0x605, "40 00 10 00 00 00 00 00");
    co_cm_isr_rx(&port, &sdo);
    CHECK(!co_cm_port_sleep(&port, 200000));
    CHECK_EQ(g_board.wfi, 1);
    co_cm_port_step(&port);
    CHECK_EQ(g_board.sent_count, 3);
    CHECK_EQ(g_board.sent[2].id, 0x585); /* the SDO answer */

    /* a deadline already passed: no sleep */
    CHECK(!co_cm_port_sleep(&port, g_board.now_us));
    /* a frame during the WFI: the loop wakes and the next step answers it */
    g_board.arrives_in_wfi = sdo;
    g_board.arrives = true;
    uint32_t answers = count_id(0x585);
    CHECK(co_cm_port_sleep(&port, 200000));
    co_cm_port_step(&port);
    CHECK_EQ(count_id(0x585), answers + 1);
    CHECK(g_board.now_us < 200000); /* woken by the frame, not the deadline */
}

static void test_run_keeps_the_heartbeat(void)
{
    /* 10 s of the loop: ten heartbeats at 1 s, each at its deadline, one sleep per beat */
    static co_cm_port_t port;
    static test_node_t t;
    start_on_port(&port, &t, 1000);
    while (g_board.now_us <= 10000000u) {
        co_cm_port_sleep(&port, co_cm_port_step(&port));
    }
    CHECK_EQ(count_id(0x705), 11); /* the boot-up and ten heartbeats */
    CHECK_EQ(g_board.wfi, 11);     /* to 1 s, 2 s, ... 11 s: no other wake-up */
}

int main(void)
{
    RUN(test_systick_start);
    RUN(test_systick_time);
    RUN(test_clock_extend);
    RUN(test_step_and_sleep);
    RUN(test_run_keeps_the_heartbeat);
    return check_summary();
}
