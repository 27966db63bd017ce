/* startup.c - minimal Cortex-M4F startup for the test firmware: the vector
 * table (initial stack pointer, reset and fault handlers), .data copied from
 * flash, .bss zeroed, the FPU enabled (CPACR CP10/CP11 full access), then
 * main(). Linked with -nostartfiles and cortex_m4.ld. */
#include <stdint.h>

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
int main(void);
void Reset_Handler(void);
void Default_Handler(void);

void Default_Handler(void)
{
    for (;;) {
    }
}

void Reset_Handler(void)
{
    uint32_t *src = &_sidata, *dst = &_sdata;
    while (dst < &_edata) *dst++ = *src++;
    for (dst = &_sbss; dst < &_ebss;) *dst++ = 0;
    /* CPACR: full access to CP10 and CP11 (the FPU) before any float code */
    *(volatile uint32_t *)0xE000ED88u |= (0xFu << 20);
    __asm volatile("dsb\n\tisb");
    (void)main();
    for (;;) {
    }
}

typedef void (*vector_fn)(void);

/* initial SP, Reset, NMI, HardFault, MemManage, BusFault, UsageFault */
__attribute__((section(".isr_vector"), used))
const vector_fn fw_vectors[7] = {
    (vector_fn)(uintptr_t)&_estack, Reset_Handler, Default_Handler, Default_Handler,
    Default_Handler, Default_Handler, Default_Handler,
};
