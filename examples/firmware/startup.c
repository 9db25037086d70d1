/* SPDX-License-Identifier: Apache-2.0 */
/*
 * startup.c -- the start of the QEMU example images, any Cortex-M: the core's exception
 * vectors (the board file's interrupt vectors follow them: section .vectors.irq), and the
 * reset handler: .data copied from flash, .bss zeroed, main(). A fault stops the processor
 * in a loop (a debugger finds it there; a watchdog would reset a real board).
 */
#include <stdint.h>

extern uint32_t __data_load[], __data_start[], __data_end[], __bss_start[], __bss_end[];
extern uint32_t __stack_top[];

int main(void);
void reset_handler(void);
void fault_handler(void);
void systick_handler(void) __attribute__((weak, alias("fault_handler")));
void pendsv_handler(void) __attribute__((weak, alias("fault_handler")));

void fault_handler(void)
{
    for (;;) {
    }
}

void reset_handler(void)
{
    for (uint32_t *src = __data_load, *dst = __data_start; dst < __data_end;) {
        *dst++ = *src++;
    }
    for (uint32_t *dst = __bss_start; dst < __bss_end;) {
        *dst++ = 0;
    }
    (void)main();
    for (;;) {
    }
}

typedef void (*vector_t)(void);

__attribute__((section(".vectors"), used)) static const vector_t k_core_vectors[16] = {
    (vector_t)(uintptr_t)__stack_top, /* the initial stack pointer */
    reset_handler,
    fault_handler, /* NMI */
    fault_handler, /* HardFault */
    fault_handler, /* MemManage (M3 and up) */
    fault_handler, /* BusFault */
    fault_handler, /* UsageFault */
    0,
    0,
    0,
    0,
    fault_handler, /* SVCall */
    0,
    0,
    pendsv_handler,
    systick_handler,
};
