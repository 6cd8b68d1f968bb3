/* read_shear.c: read an MLX90393 and print the normal and tangential force of a centred press
 * through shear_table.h (written by `mst calibrate ... --shear-table` beside calibrated.yaml).
 *
 * Plain C99 for any Cortex-M board (tests/test_firmware.py compiles it for a Cortex-M0+ and a
 * Cortex-M4F with -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wdouble-promotion -Werror).
 * The board gives three functions, declared below: an I2C write-then-read, a millisecond delay
 * and a line printer (on Arduino: Wire.beginTransmission/write/endTransmission(false)/
 * requestFrom, delay and Serial.println).
 *
 * The chip is set to the header's GAIN_SEL and RES (register 0 bits 6:4, register 2 bits 10:5),
 * HALLCONF 0xC, temperature compensation off: codes read at any other setting are not valid for
 * the table. Each 16-bit word is two's complement at RES 0 and 1 and is passed sign-extended,
 * (int32_t)(int16_t)word; a word passed as unsigned comes back MST_SHR_BAD_CODE, never a force.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define MST_SHR_IMPLEMENTATION /* this file defines the table and its code (one file of the program does) */
#include "shear_table.h"

#define MLX_ADDR 0x0C /* A0 = A1 = 0 (Adafruit 4022: 0x0C) */

int board_i2c(uint8_t addr, const uint8_t *tx, size_t n_tx, uint8_t *rx, size_t n_rx); /* 0: done */
void board_delay_ms(uint32_t ms);
void board_print(const char *line);

static int mlx_write_register(uint8_t reg, uint16_t value)
{
    uint8_t tx[4] = {0x60, (uint8_t)(value >> 8), (uint8_t)(value & 0xFFu), (uint8_t)(reg << 2)};
    uint8_t status;
    return board_i2c(MLX_ADDR, tx, sizeof tx, &status, 1);
}

static int mlx_setup(void)
{
    uint16_t res = (uint16_t)(MST_SHR_RES & 3);
    if (mlx_write_register(0, (uint16_t)((MST_SHR_GAIN_SEL & 7) << 4 | 0xC))) return 1; /* GAIN_SEL, HALLCONF */
    /* RES_Z, RES_Y, RES_X; no digital filter change (DIG_FILT 0), OSR 0 */
    return mlx_write_register(2, (uint16_t)(res << 9 | res << 7 | res << 5));
}

/* one single measurement of X, Y, Z: the raw codes, sign-extended */
static int mlx_read_xyz(int32_t codes[3])
{
    uint8_t sm = 0x3E, rm = 0x4E, status, rx[7];
    if (board_i2c(MLX_ADDR, &sm, 1, &status, 1)) return 1;
    board_delay_ms(10); /* conversion time at OSR 0, DIG_FILT 0, three axes (data sheet: a few ms) */
    if (board_i2c(MLX_ADDR, &rm, 1, rx, sizeof rx)) return 1;
    for (int axis = 0; axis < 3; axis++) {
        uint16_t word = (uint16_t)((uint16_t)rx[1 + 2 * axis] << 8 | rx[2 + 2 * axis]);
        codes[axis] = (int32_t)(int16_t)word; /* two's complement at RES 0 and 1: sign-extend */
    }
    return 0;
}

static const char *const flag_names[] = {"ok", "not_identifiable", "ambiguous", "no_fit", "below_range",
                                         "above_range", "saturated", "above_calibrated", "bad_code"};

int main(void)
{
    char line[96];
    if (mlx_setup()) board_print("MLX90393 not answering at 0x0C");
    for (;;) {
        int32_t c[3];
        struct mst_shear e;
        if (mlx_read_xyz(c)) {
            board_print("read failed");
            continue;
        }
        int flag = mst_shear_from_codes(c[0], c[1], c[2], &e);
        if (flag == MST_SHR_OK)
            snprintf(line, sizeof line, "Fz %ld mN +- %ld, Fx %ld mN, Fy %ld mN", (long)(1000.0f * e.force_N),
                     (long)(1000.0f * e.sigma_force_N), (long)(1000.0f * e.shear_x_N), (long)(1000.0f * e.shear_y_N));
        else
            snprintf(line, sizeof line, "%s (codes %ld %ld %ld)", flag_names[flag], (long)c[0], (long)c[1], (long)c[2]);
        board_print(line);
    }
}
