/* SPDX-License-Identifier: Apache-2.0 */
/*
 * board_mps2_an386.c -- Arm's MPS2+ board with the AN386 FPGA image (Cortex-M4 at 25 MHz;
 * QEMU's mps2-an386), from Arm's Cortex-M System Design Kit (CMSDK) peripherals: APB UART0
 * (QEMU's first serial port) carries the CAN stand-in, APB timer 0, free-running over 32 bits
 * at 25 MHz, is the time base, APB timer 1 the wake-up at the main loop's deadline (no
 * periodic tick), and the stored parameters live in two 16 KB slots at the top of SSRAM2/3
 * (0x203F8000 and 0x203FC000, outside every section of mps2_an386.ld), which keep their
 * contents across a system reset. The board has no flash to write, so that RAM is driven as
 * flash is (pages erased to 0xFF, 32-bit words programmed, bits only cleared) and the
 * storage above it runs as it would on a part's flash sectors.
 *
 * Priorities (3 bits, the upper ones): UART0 and timer 1 at 0xA0; the port masks at
 * CO_CM_BASEPRI 0x80 (the Makefile sets it for this board), so both are masked by its
 * critical section and anything at 0x00..0x60 would stay live.
 */
#include <string.h>

#include "board.h"

#define REG(addr) (*(volatile uint32_t *)(addr))

#define TICKS_PER_US 25u        /* the APB clock: 25 MHz */
#define SLEEP_MAX_US 100000000u /* 100 s: timer 0 wraps in 171 s */

#define UART0 0x40004000u
#define UART_DATA (UART0 + 0x00)
#define UART_STATE (UART0 + 0x04)
#define UART_CTRL (UART0 + 0x08)
#define UART_INTCLEAR (UART0 + 0x0C)
#define UART_BAUDDIV (UART0 + 0x10)
#define STATE_TX_FULL (1u << 0)
#define STATE_RX_FULL (1u << 1)
#define CTRL_TX_EN (1u << 0)
#define CTRL_RX_EN (1u << 1)
#define CTRL_TX_INT (1u << 2)
#define CTRL_RX_INT (1u << 3)
#define UART0_RX_IRQ 0u
#define UART0_TX_IRQ 1u

#define TIMER0 0x40000000u /* the time base */
#define TIMER1 0x40001000u /* the wake-up */
#define TIMER_CTRL 0x00u
#define TIMER_VALUE 0x04u
#define TIMER_RELOAD 0x08u
#define TIMER_INTCLEAR 0x0Cu
#define TIMER_ENABLE 1u
#define TIMER_INT 8u
#define TIMER1_IRQ 9u

#define NVIC_ISER 0xE000E100u
#define NVIC_ISPR 0xE000E200u
#define NVIC_IPR 0xE000E400u
#define IRQ_COUNT 32u

#define SLOTS 0x203F8000u
#define SLOT_SIZE 0x4000u

typedef void (*vector_t)(void);

/* Timer 0 as microseconds: the count last read, and the ticks short of a whole microsecond
 * since (no 64-bit division: 32 bits hold the ticks between two reads). */
typedef struct board_state {
    uint64_t now_us;
    uint32_t count;
    uint32_t ticks_left;
} board_state_t;

static board_state_t g_board;

static void uart0_handler(void)
{
    REG(UART_INTCLEAR) = 3u; /* TX and RX: what is left is seen in STATE */
    board_uart_irq();
}

static void timer1_handler(void)
{
    REG(TIMER1 + TIMER_INTCLEAR) = 1; /* it only wakes the loop: once */
    REG(TIMER1 + TIMER_CTRL) = 0;
}

__attribute__((section(".vectors.irq"), used)) static const vector_t k_irq_vectors[IRQ_COUNT] = {
    [UART0_RX_IRQ] = uart0_handler,
    [UART0_TX_IRQ] = uart0_handler,
    [TIMER1_IRQ] = timer1_handler,
};

static void nvic_enable(uint32_t irq, uint8_t priority)
{
    *(volatile uint8_t *)(NVIC_IPR + irq) = priority;
    REG(NVIC_ISER) = 1u << irq;
}

/* ---- the stored parameters' flash, in RAM */

static co_err_t ram_erase(void *hw, uintptr_t addr)
{
    (void)hw;
    memset((void *)addr, 0xFF, SLOT_SIZE);
    return CO_OK;
}

static co_err_t ram_program(void *hw, uintptr_t addr, const uint8_t *data)
{
    (void)hw;
    *(volatile uint32_t *)addr &= co_get_u32(data); /* as flash: bits only cleared */
    return CO_OK;
}

static const board_flash_t k_flash = {
    .flash = {.erase_page = ram_erase, .program = ram_program, .page_size = SLOT_SIZE, .unit = 4},
    .slot = {SLOTS, SLOTS + SLOT_SIZE},
    .slot_size = SLOT_SIZE,
    .what = "RAM kept across resets",
};

const board_flash_t *board_flash(void) { return &k_flash; }

/* ---- the time base: timer 0 counts down from 0xFFFFFFFF, for ever */

static uint64_t timer_now_us(void *ctx)
{
    board_state_t *b = ctx;
    uint32_t count = ~REG(TIMER0 + TIMER_VALUE); /* counting up */
    uint32_t ticks = count - b->count + b->ticks_left;
    b->count = count;
    b->now_us += ticks / TICKS_PER_US;
    b->ticks_left = ticks % TICKS_PER_US;
    return b->now_us;
}

/* Timer 1 from the deadline's distance, its interrupt the wake-up (at most 100 s ahead: the
 * loop reads timer 0 once per wrap); a deadline already passed pends it at once. */
static void timer_wake_at(void *ctx, uint64_t deadline_us)
{
    uint64_t now = timer_now_us(ctx);
    REG(TIMER1 + TIMER_CTRL) = 0;
    REG(TIMER1 + TIMER_INTCLEAR) = 1;
    if (deadline_us <= now) {
        REG(NVIC_ISPR) = 1u << TIMER1_IRQ;
        return;
    }
    uint32_t wait_us =
        deadline_us - now < SLEEP_MAX_US ? (uint32_t)(deadline_us - now) : SLEEP_MAX_US;
    REG(TIMER1 + TIMER_RELOAD) = wait_us * TICKS_PER_US;
    REG(TIMER1 + TIMER_VALUE) = wait_us * TICKS_PER_US;
    REG(TIMER1 + TIMER_CTRL) = TIMER_ENABLE | TIMER_INT;
}

co_cm_time_t board_time(void)
{
    return (co_cm_time_t){.now_us = timer_now_us, .wake_at = timer_wake_at, .ctx = &g_board};
}

/* ---- start */

void board_init(void)
{
    REG(TIMER0 + TIMER_RELOAD) = 0xFFFFFFFFu;
    REG(TIMER0 + TIMER_VALUE) = 0xFFFFFFFFu;
    REG(TIMER0 + TIMER_CTRL) = TIMER_ENABLE;
    nvic_enable(TIMER1_IRQ, 0xA0);

    REG(UART_BAUDDIV) = 25000000u / 115200u;
    REG(UART_CTRL) = CTRL_TX_EN | CTRL_RX_EN;
}

/* ---- UART0 */

void board_uart_start(void)
{
    REG(UART_CTRL) |= CTRL_RX_INT;
    nvic_enable(UART0_RX_IRQ, 0xA0);
    nvic_enable(UART0_TX_IRQ, 0xA0);
}

bool board_uart_rx(uint8_t *byte)
{
    if ((REG(UART_STATE) & STATE_RX_FULL) == 0) {
        return false;
    }
    *byte = (uint8_t)REG(UART_DATA);
    return true;
}

bool board_uart_tx_ready(void) { return (REG(UART_STATE) & STATE_TX_FULL) == 0; }

void board_uart_tx(uint8_t byte) { REG(UART_DATA) = byte; }

void board_uart_tx_irq(bool on)
{
    uint32_t ctrl = REG(UART_CTRL);
    REG(UART_CTRL) = on ? ctrl | CTRL_TX_INT : ctrl & ~CTRL_TX_INT;
}

void board_uart_pend(void) { REG(NVIC_ISPR) = 1u << UART0_RX_IRQ; }
