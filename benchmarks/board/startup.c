/* Bare-metal start for the emulated boards of benchmarks/bench_board.py: the vector table, .data
 * copied from flash, .bss zeroed, the FPU enabled where there is one, then main; output through
 * Arm semihosting (QEMU -semihosting). */
#include <stdint.h>

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
int main(void);

void reset_handler(void);
void reset_handler(void)
{
    uint32_t *src = &_sidata, *dst = &_sdata;
    while (dst < &_edata) *dst++ = *src++;
    for (dst = &_sbss; dst < &_ebss; dst++) *dst = 0;
#if defined(__ARM_FP)
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20; /* CPACR: CP10, CP11 full access */
    __asm volatile("dsb\n isb");
#endif
    (void)main();
    for (;;) {
        register uint32_t op __asm("r0") = 0x18u; /* SYS_EXIT */
        register uint32_t arg __asm("r1") = 0x20026u; /* ADP_Stopped_ApplicationExit */
        __asm volatile("bkpt 0xAB" : : "r"(op), "r"(arg) : "memory");
    }
}

static void hang(void) { for (;;) {} }

__attribute__((section(".isr_vector"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))(&_estack), reset_handler, hang, hang, hang, hang, hang, 0, 0, 0, 0, hang, hang, 0, hang, hang,
};

void semihost_write(const char *text);
void semihost_write(const char *text)
{
    register uint32_t op __asm("r0") = 0x04u; /* SYS_WRITE0 */
    register const char *arg __asm("r1") = text;
    __asm volatile("bkpt 0xAB" : : "r"(op), "r"(arg) : "memory");
}
