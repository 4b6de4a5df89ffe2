/* Vector table and reset handler for the C example on QEMU's mps2-an386 (Cortex-M4F):
 * enable the FPU, then enter newlib's semihosting C runtime (rdimon's _start), which
 * clears .bss, sets up stdio over semihosting and calls main. */
#include <stdint.h>

extern void _start(void);
extern uint32_t __stack_top;

void reset(void);
void reset(void) {
    /* CPACR: full access to coprocessors 10 and 11 (the FPU) before any float code. */
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20;
    __asm volatile("dsb\n\tisb");
    _start();
}

/* Any fault: report through semihosting's exit (reason "run-time error"). */
static void fault(void) {
    register uint32_t op __asm("r0") = 0x18;      /* SYS_EXIT */
    register uint32_t reason __asm("r1") = 0x20023; /* ADP_Stopped_RunTimeErrorUnknown */
    __asm volatile("bkpt 0xab" : : "r"(op), "r"(reason));
    for (;;) {
    }
}

__attribute__((section(".vectors"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))&__stack_top, reset, fault, fault, fault, fault, fault, 0,
    0, 0, 0, fault, fault, 0, fault, fault,
};
