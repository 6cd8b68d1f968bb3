/* Time each reading of codes.h's list through table.h by SysTick, and print per reading its flag
 * and SysTick ticks. QEMU's -icount shift=0 runs one instruction per ns of virtual time and
 * SysTick counts the board's clock of it, so ticks convert to instructions by the first line
 * printed: "cal TICKS" for a loop of CAL_INSNS instructions (2 a turn: subs, bne). */
#include <stdint.h>
#define MST_OFF_IMPLEMENTATION
#define MST_SHR_IMPLEMENTATION
#include "table.h"
#include "codes.h"

void semihost_write(const char *text);

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)

static void put_u32(char *buf, uint32_t v)
{
    char tmp[11];
    int n = 0;
    do { tmp[n++] = (char)('0' + v % 10u); v /= 10u; } while (v);
    while (n) *buf++ = tmp[--n];
    *buf = 0;
}

#define CAL_TURNS 100000u /* 200,000 instructions */

int main(void)
{
    char line[32];
    SYST_RVR = 0x00FFFFFFu;
    SYST_CVR = 0u;
    SYST_CSR = 5u; /* enable, processor clock */
    {
        uint32_t n = CAL_TURNS, t0 = SYST_CVR;
        __asm volatile(".syntax unified\n1: subs %0, %0, #1\n bne 1b" : "+l"(n) : : "cc");
        uint32_t t1 = SYST_CVR;
        semihost_write("cal ");
        put_u32(line, (t0 - t1) & 0x00FFFFFFu);
        semihost_write(line);
        semihost_write("\n");
    }
    for (unsigned r = 0; r < N_CODES; r++) {
        MST_STRUCT e;
        uint32_t t0 = SYST_CVR;
        int flag = MST_FROM_CODES(codes[r][0], codes[r][1], codes[r][2], &e);
        uint32_t t1 = SYST_CVR;
        uint32_t ticks = (t0 - t1) & 0x00FFFFFFu; /* counts down */
        put_u32(line, (uint32_t)flag);
        char *p = line;
        while (*p) p++;
        *p++ = ' ';
        put_u32(p, ticks);
        while (*p) p++;
        *p++ = '\n';
        *p = 0;
        semihost_write(line);
    }
    return 0;
}
