/* SPDX-License-Identifier: Apache-2.0 */
/*
 * board_microbit.c -- the nRF51822 of a BBC micro:bit (QEMU's microbit), from Nordic's nRF51
 * Series Reference Manual: UART0 (P0.24 TX, P0.25 RX; QEMU's first serial port) carries the
 * CAN stand-in; TIMER0, free-running at 1 MHz over 32 bits, is the time base (this core has
 * no SysTick), its compare 0 the wake-up at the main loop's deadline (no periodic tick);
 * the stored parameters live in the last 4 KB of flash, written through the NVMC (QEMU
 * models it: pages erase to 0xFF, words program by clearing bits, and flash keeps its
 * contents across a system reset).
 *
 * Priorities (2 bits, the upper ones): UART0 and TIMER0 at 0x80. The Cortex-M0 masks by
 * PRIMASK (no BASEPRI).
 */
#include "board.h"

#define REG(addr) (*(volatile uint32_t *)(addr))

#define CLOCK_TASKS_HFCLKSTART 0x40000000u

#define UART0 0x40002000u
#define UART_STARTRX (UART0 + 0x000)
#define UART_STARTTX (UART0 + 0x008)
#define UART_EVENTS_RXDRDY (UART0 + 0x108)
#define UART_EVENTS_TXDRDY (UART0 + 0x11C)
#define UART_INTENSET (UART0 + 0x304)
#define UART_INTENCLR (UART0 + 0x308)
#define UART_ENABLE (UART0 + 0x500)
#define UART_PSELTXD (UART0 + 0x50C)
#define UART_PSELRXD (UART0 + 0x514)
#define UART_RXD (UART0 + 0x518)
#define UART_TXD (UART0 + 0x51C)
#define UART_BAUDRATE (UART0 + 0x524)
#define UART_INT_RXDRDY (1u << 2)
#define UART_INT_TXDRDY (1u << 7)
#define UART0_IRQ 2u

#define TIMER0 0x40008000u
#define TIMER_START (TIMER0 + 0x000)
#define TIMER_CLEAR (TIMER0 + 0x00C)
#define TIMER_CAPTURE1 (TIMER0 + 0x044)
#define TIMER_EVENTS_COMPARE0 (TIMER0 + 0x140)
#define TIMER_INTENSET (TIMER0 + 0x304)
#define TIMER_MODE (TIMER0 + 0x504)
#define TIMER_BITMODE (TIMER0 + 0x508)
#define TIMER_PRESCALER (TIMER0 + 0x510)
#define TIMER_CC0 (TIMER0 + 0x540)
#define TIMER_CC1 (TIMER0 + 0x544)
#define TIMER0_IRQ 8u
#define SLEEP_MAX_US 0x80000000u /* half the counter's range: it is read once per wrap */

#define NVMC_READY 0x4001E400u
#define NVMC_CONFIG 0x4001E504u
#define NVMC_ERASEPAGE 0x4001E508u
#define NVMC_READ_ONLY 0u
#define NVMC_WRITE 1u
#define NVMC_ERASE 2u

#define NVIC_ISER 0xE000E100u
#define NVIC_ISPR 0xE000E200u
#define NVIC_IPR 0xE000E400u
#define IRQ_COUNT 32u

#define SLOTS 0x3F000u
#define PAGE_SIZE 1024u

typedef void (*vector_t)(void);

typedef struct board_state {
    uint64_t now_us; /* TIMER0 widened to 64 bits (co_cm_clock_extend) */
    bool tx_busy;    /* UART0: a byte written, its TXDRDY not seen yet */
} board_state_t;

static board_state_t g_board;

static void uart0_handler(void) { board_uart_irq(); }

static void timer0_handler(void) { REG(TIMER_EVENTS_COMPARE0) = 0; /* it only wakes the loop */ }

__attribute__((section(".vectors.irq"), used)) static const vector_t k_irq_vectors[IRQ_COUNT] = {
    [UART0_IRQ] = uart0_handler,
    [TIMER0_IRQ] = timer0_handler,
};

static void nvic_priority(uint32_t irq, uint8_t priority)
{
    /* ARMv6-M: word access only to the priority registers */
    volatile uint32_t *ipr = (volatile uint32_t *)(NVIC_IPR + 4 * (irq / 4));
    uint32_t shift = 8 * (irq % 4);
    *ipr = (*ipr & ~(0xFFu << shift)) | ((uint32_t)priority << shift);
}

static void nvic_enable(uint32_t irq) { REG(NVIC_ISER) = 1u << irq; }

/* ---- the stored parameters' flash: the NVMC */

static void nvmc_wait(void)
{
    while (REG(NVMC_READY) == 0) {
    }
}

static co_err_t nvmc_erase(void *hw, uintptr_t addr)
{
    (void)hw;
    REG(NVMC_CONFIG) = NVMC_ERASE;
    nvmc_wait();
    REG(NVMC_ERASEPAGE) = (uint32_t)addr; /* the CPU stalls until the page is erased */
    nvmc_wait();
    REG(NVMC_CONFIG) = NVMC_READ_ONLY;
    return CO_OK;
}

static co_err_t nvmc_program(void *hw, uintptr_t addr, const uint8_t *data)
{
    (void)hw;
    REG(NVMC_CONFIG) = NVMC_WRITE;
    nvmc_wait();
    *(volatile uint32_t *)addr = co_get_u32(data);
    nvmc_wait();
    REG(NVMC_CONFIG) = NVMC_READ_ONLY;
    return CO_OK;
}

static const board_flash_t k_flash = {
    .flash = {.erase_page = nvmc_erase, .program = nvmc_program, .page_size = PAGE_SIZE, .unit = 4},
    .slot = {SLOTS, SLOTS + 2 * PAGE_SIZE},
    .slot_size = 2 * PAGE_SIZE,
    .what = "flash (NVMC)",
};

const board_flash_t *board_flash(void) { return &k_flash; }

/* ---- TIMER0: the time base */

static uint64_t timer_now_us(void *ctx)
{
    board_state_t *b = ctx;
    REG(TIMER_CAPTURE1) = 1;
    return co_cm_clock_extend(&b->now_us, REG(TIMER_CC1), 0xFFFFFFFFu);
}

/* Compare 0 at the deadline (at most half a wrap ahead); one already passed while it was
 * being set pends the interrupt, so the WFI ends at once. */
static void timer_wake_at(void *ctx, uint64_t deadline_us)
{
    uint64_t now = timer_now_us(ctx);
    if (deadline_us > now + SLEEP_MAX_US) {
        deadline_us = now + SLEEP_MAX_US;
    }
    REG(TIMER_CC0) = (uint32_t)deadline_us;
    REG(TIMER_EVENTS_COMPARE0) = 0;
    if (timer_now_us(ctx) >= deadline_us) {
        REG(NVIC_ISPR) = 1u << TIMER0_IRQ;
    }
}

co_cm_time_t board_time(void)
{
    return (co_cm_time_t){.now_us = timer_now_us, .wake_at = timer_wake_at, .ctx = &g_board};
}

/* ---- start */

void board_init(void)
{
    REG(CLOCK_TASKS_HFCLKSTART) = 1; /* the crystal for the timer's accuracy (not waited for) */
    REG(TIMER_MODE) = 0;             /* timer */
    REG(TIMER_BITMODE) = 3;          /* 32 bits */
    REG(TIMER_PRESCALER) = 4;        /* 16 MHz / 2^4: 1 MHz */
    REG(TIMER_CLEAR) = 1;
    REG(TIMER_INTENSET) = 1u << 16; /* COMPARE0 */
    nvic_priority(TIMER0_IRQ, 0x80);
    nvic_enable(TIMER0_IRQ);
    REG(TIMER_START) = 1;

    REG(UART_PSELTXD) = 24;
    REG(UART_PSELRXD) = 25;
    REG(UART_BAUDRATE) = 0x01D7E000u; /* 115200 bit/s */
    REG(UART_ENABLE) = 4;
    REG(UART_STARTTX) = 1;
    REG(UART_STARTRX) = 1;
    nvic_priority(UART0_IRQ, 0x80);
}

/* ---- UART0 */

void board_uart_start(void)
{
    REG(UART_INTENSET) = UART_INT_RXDRDY;
    nvic_enable(UART0_IRQ);
}

bool board_uart_rx(uint8_t *byte)
{
    if (REG(UART_EVENTS_RXDRDY) == 0) {
        return false;
    }
    REG(UART_EVENTS_RXDRDY) = 0; /* before RXD: the next byte sets it again */
    *byte = (uint8_t)REG(UART_RXD);
    return true;
}

bool board_uart_tx_ready(void)
{
    if (g_board.tx_busy && REG(UART_EVENTS_TXDRDY) != 0) {
        REG(UART_EVENTS_TXDRDY) = 0;
        g_board.tx_busy = false;
    }
    return !g_board.tx_busy;
}

void board_uart_tx(uint8_t byte)
{
    g_board.tx_busy = true;
    REG(UART_TXD) = byte;
}

void board_uart_tx_irq(bool on) { REG(on ? UART_INTENSET : UART_INTENCLR) = UART_INT_TXDRDY; }

void board_uart_pend(void) { REG(NVIC_ISPR) = 1u << UART0_IRQ; }
