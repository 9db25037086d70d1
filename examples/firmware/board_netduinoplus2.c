/* SPDX-License-Identifier: Apache-2.0 */
/*
 * board_netduinoplus2.c -- the STM32F405 of a Netduino Plus 2 (QEMU's netduinoplus2), from
 * ST's RM0090: USART1 (PA9/PA10, QEMU's first serial port) carries the CAN stand-in, SysTick
 * on the 168 MHz core clock is the time base, and the stored parameters live in two 16 KB
 * slots of RAM (0x20018000 and 0x2001C000, outside every section of netduinoplus2.ld), which
 * keep their contents across a system reset: QEMU does not let this part write its flash.
 * The RAM is driven as the F4's flash is (sectors erased to 0xFF, 32-bit words programmed,
 * bits only cleared), so the storage above it runs as it would on sectors 1 and 2.
 *
 * Priorities (4 bits, the upper nibble): USART1 0xA0, SysTick 0xF0; the port masks at
 * CO_CM_BASEPRI 0x80 (the Makefile sets it for this board), so both are masked by its
 * critical section and anything at 0x00..0x70 would stay live.
 *
 * The clock tree stays as QEMU starts it (the core at 168 MHz, no PLL to lock): a real
 * board starts HSE and the PLL first (RM0090 §6.3) and then does what follows.
 */
#include <string.h>

#include "board.h"
#include "canola/cm_systick.h"

#define REG(addr) (*(volatile uint32_t *)(addr))

#define CPU_HZ 168000000u
#define TICK_US 1000u

#define RCC_AHB1ENR 0x40023830u
#define RCC_APB2ENR 0x40023844u
#define GPIOA_MODER 0x40020000u
#define GPIOA_AFRH 0x40020024u

#define USART1_SR 0x40011000u
#define USART1_DR 0x40011004u
#define USART1_BRR 0x40011008u
#define USART1_CR1 0x4001100Cu
#define SR_ORE (1u << 3)
#define SR_RXNE (1u << 5)
#define SR_TXE (1u << 7)
#define CR1_RE (1u << 2)
#define CR1_TE (1u << 3)
#define CR1_RXNEIE (1u << 5)
#define CR1_TXEIE (1u << 7)
#define CR1_UE (1u << 13)
#define USART1_IRQ 37u
#define IRQ_COUNT 82u

#define NVIC_ISER 0xE000E100u
#define NVIC_ISPR 0xE000E200u
#define NVIC_IPR 0xE000E400u

#define SLOTS 0x20018000u
#define SLOT_SIZE 0x4000u

typedef void (*vector_t)(void);
void fault_handler(void);
void systick_handler(void);

static co_cm_systick_t g_systick;

void systick_handler(void) { co_cm_systick_isr(&g_systick); }

static void usart1_handler(void) { board_uart_irq(); }

__attribute__((section(".vectors.irq"), used)) static const vector_t k_irq_vectors[IRQ_COUNT] = {
    [USART1_IRQ] = usart1_handler,
};

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

/* ---- start */

void board_init(void)
{
    REG(RCC_AHB1ENR) |= 1u << 0;                                          /* GPIOA */
    REG(RCC_APB2ENR) |= 1u << 4;                                          /* USART1 */
    REG(GPIOA_MODER) = (REG(GPIOA_MODER) & ~(0xFu << 18)) | (0xAu << 18); /* PA9, PA10: AF */
    REG(GPIOA_AFRH) = (REG(GPIOA_AFRH) & ~(0xFFu << 4)) | (0x77u << 4);   /* AF7: USART1 */
    REG(USART1_BRR) = (45u << 4) | 9u; /* 115200 bit/s from APB2's 84 MHz */
    REG(USART1_CR1) = CR1_UE | CR1_TE | CR1_RE;
    *(volatile uint8_t *)(NVIC_IPR + USART1_IRQ) = 0xA0;
    (void)co_cm_systick_start(&g_systick, CPU_HZ, TICK_US);
}

co_cm_time_t board_time(void) { return co_cm_systick_time(&g_systick); }

/* ---- USART1 */

void board_uart_start(void)
{
    REG(USART1_CR1) |= CR1_RXNEIE;
    REG(NVIC_ISER + 4 * (USART1_IRQ / 32)) = 1u << (USART1_IRQ % 32);
}

bool board_uart_rx(uint8_t *byte)
{
    uint32_t sr = REG(USART1_SR);
    if ((sr & (SR_RXNE | SR_ORE)) == 0) {
        return false;
    }
    *byte = (uint8_t)REG(USART1_DR); /* reading SR then DR also clears an overrun */
    return (sr & SR_RXNE) != 0;
}

bool board_uart_tx_ready(void) { return (REG(USART1_SR) & SR_TXE) != 0; }

void board_uart_tx(uint8_t byte) { REG(USART1_DR) = byte; }

void board_uart_tx_irq(bool on)
{
    uint32_t cr1 = REG(USART1_CR1);
    REG(USART1_CR1) = on ? cr1 | CR1_TXEIE : cr1 & ~CR1_TXEIE;
}

void board_uart_pend(void) { REG(NVIC_ISPR + 4 * (USART1_IRQ / 32)) = 1u << (USART1_IRQ % 32); }
