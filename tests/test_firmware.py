"""The headers as firmware builds them (issue 45 item 7): the example sketch
(docs/examples/firmware/read_shear.c) and both one-chip headers in one program compile with every
warning a firmware build may turn on, for a Cortex-M0+ and a Cortex-M4F (the distribution's
gcc-arm-none-eabi; .ci/run installs it), and an unsign-extended code is refused, not read.
The compile checks need no particular table: a field linear in the load fills them."""

import os
import shutil
import subprocess
from pathlib import Path

import c_drivers
import numpy as np
import pytest
from test_c_header import c_compiler

from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.estimation.inverse_table import SHEAR_TABLE_RATIO, InverseTable, TableGrid
from mst_cli.estimation.table_reader import OffsetTableReader, ShearTableReader
from mst_cli.firmware.table_header import C_FLAGS, read_codes, table_header
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
SKETCH = ROOT / "docs" / "examples" / "firmware" / "read_shear.c"
CPUS = {
    "cortex-m0plus": ["-mcpu=cortex-m0plus", "-mthumb"],
    "cortex-m4f": ["-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16"],
}


@pytest.fixture(scope="module")
def headers():
    doc, _ = load_design_document(FORWARD)
    imap, resp = inverse_map(doc, "spring")
    top, setting = float(imap.force_N[-1]), resp.chip_setting
    A = np.array([[2.0, 30.0, 1.0], [1.0, 2.0, 30.0], [60.0, 1.0, 2.0]])  # uT per (N, unit, unit)

    def linear(grid):
        P = np.stack(np.meshgrid(grid.force_N, grid.u, grid.v, indexing="ij"), axis=-1)
        return InverseTable(grid, 1e-6 * (P @ A.T + np.array([0.0, 0.0, 1e6 * imap.B_abs_T[0]])), "linear")

    shear = ShearTableReader(linear(TableGrid.cone(top, 9, SHEAR_TABLE_RATIO, 0.25, imap.edges_N)), 2e-6)
    offset = OffsetTableReader(linear(TableGrid.over(doc.geometry(), top, 9, 6.0, imap.edges_N)), 2e-6, 1.0)
    texts = {
        "shear_table.h": table_header(shear, imap, setting, doc.name, "the test", ["a test"]),
        "offset_table.h": table_header(offset, imap, setting, doc.name, "the test", ["a test"]),
    }
    return texts, shear, imap, setting


def arm_gcc() -> str:
    cc = shutil.which("arm-none-eabi-gcc")
    if cc is None:
        if os.environ.get("CI") == "true":
            pytest.fail("no arm-none-eabi-gcc on the CI image: .ci/run installs gcc-arm-none-eabi")
        pytest.skip("no arm-none-eabi-gcc: the firmware builds cannot be checked here")
    return cc


@pytest.mark.parametrize("cpu", sorted(CPUS))
def test_the_sketch_and_both_headers_compile_for_the_board_with_every_warning(headers, tmp_path, cpu):
    cc = arm_gcc()
    texts, *_ = headers
    for name, text in texts.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "both.c").write_text(
        '#include "offset_table.h"\n#include "shear_table.h"\n'
        "int both(int32_t x, int32_t y, int32_t z);\n"
        "int both(int32_t x, int32_t y, int32_t z)\n{\n    struct mst_shear s;\n    struct mst_offset o;\n"
        "    return mst_shear_from_codes(x, y, z, &s) + mst_offset_from_codes(x, y, z, &o);\n}\n"
    )
    for source in (SKETCH, tmp_path / "both.c"):
        cmd = [
            cc,
            "-std=c99",
            "-O2",
            *CPUS[cpu],
            *c_drivers.STRICT,
            "-I",
            tmp_path,
            "-c",
            source,
            "-o",
            tmp_path / "x.o",
        ]
        subprocess.run(cmd, check=True)
        nm = subprocess.run([cc.replace("gcc", "nm"), tmp_path / "x.o"], capture_output=True, text=True).stdout
        assert "__aeabi_ldiv" not in nm and "__aeabi_uldivmod" not in nm and "__divdi3" not in nm  # no 64-bit division


def test_an_unsign_extended_code_is_refused_in_c_and_in_python(headers, tmp_path):
    texts, shear, imap, setting = headers
    exe = c_drivers.build(c_compiler(), tmp_path, {"shear_table.h": texts["shear_table.h"]}, "shear")
    z = -int(round(1e6 * imap.B_abs_T[0] / setting.z_uT_per_lsb))  # the unloaded field, magnet flipped
    codes = np.array([[0, 0, z], [0, 0, z & 0xFFFF]])  # sign-extended, and the 16-bit word as unsigned
    c_out, _ = c_drivers.run(exe, codes)
    py_flag, _ = read_codes(shear, imap, setting, codes)
    assert [C_FLAGS[int(f)] for f in c_out[:, 0]] == list(py_flag)
    assert py_flag[1] == "bad_code" and py_flag[0] != "bad_code"


def test_the_table_is_defined_once_in_a_program_of_two_files(headers, tmp_path):
    # one file defines MST_SHR_IMPLEMENTATION (the table and the code), another includes the header
    # plainly: the program links, the table is in the first object only, and both read alike
    cc = c_compiler()
    texts, shear, imap, setting = headers
    (tmp_path / "shear_table.h").write_text(texts["shear_table.h"])
    (tmp_path / "one.c").write_text('#define MST_SHR_IMPLEMENTATION\n#include "shear_table.h"\n')
    (tmp_path / "two.c").write_text(
        '#include <stdio.h>\n#include "shear_table.h"\nint main(void)\n{\n    long x, y, z;\n'
        '    while (scanf("%ld %ld %ld", &x, &y, &z) == 3) {\n        struct mst_shear e = {0};\n'
        "        int flag = mst_shear_from_codes((int32_t)x, (int32_t)y, (int32_t)z, &e);\n"
        '        printf("%d %.9g %.9g %.9g\\n", flag, (double)e.force_N, (double)e.shear_x_N, (double)e.shear_y_N);\n'
        "    }\n    return 0;\n}\n"
    )
    objs = []
    for name in ("one", "two"):
        obj = tmp_path / f"{name}.o"
        subprocess.run([cc, "-std=c99", "-O2", *c_drivers.STRICT, "-c", tmp_path / f"{name}.c", "-o", obj], check=True)
        objs.append(obj)
    nm = shutil.which("nm")
    if nm is not None:
        symbols = [subprocess.run([nm, o], capture_output=True, text=True).stdout for o in objs]
        assert "mst_shr_B_uT" in symbols[0] and "mst_shr_B_uT" not in symbols[1]
    exe = tmp_path / "two"
    subprocess.run([cc, *objs, "-o", exe, "-lm"], check=True)
    top = float(imap.force_N[-1])
    lsb = np.array([setting.xy_uT_per_lsb, setting.xy_uT_per_lsb, setting.z_uT_per_lsb])
    # presses at nodes, with negative X and Y codes among them
    B_uT = 1e6 * shear.table.B_T[[1, 2, 4], [0, 0, 1], [0, 1, 0]]
    codes = np.rint(B_uT / lsb).astype(np.int64)
    assert np.any(codes[:, :2] < 0)
    out = subprocess.run([exe], input="".join(f"{x} {y} {z}\n" for x, y, z in codes), capture_output=True, text=True)
    two = np.array([[float(v) for v in line.split()] for line in out.stdout.splitlines()])
    flag, values = read_codes(shear, imap, setting, codes)
    assert [C_FLAGS[int(f)] for f in two[:, 0]] == list(flag) == ["ok"] * 3
    np.testing.assert_allclose(two[:, 1:4], values[:, :3], atol=0.01 * top)


def test_the_sketch_sign_extends_the_chips_words(headers, tmp_path):
    # the sketch compiled for the host with a stub I2C bus that answers the chip's two's-complement
    # words for negative codes: they come back negative, as int32_t, through the header
    cc = c_compiler()
    texts, shear, imap, setting = headers
    (tmp_path / "shear_table.h").write_text(texts["shear_table.h"])
    codes = [-300, 450, -200]  # |B| below the range: the sketch prints the flag and the codes it read
    words = [c & 0xFFFF for c in codes]
    rx = ", ".join(str(b) for w in words for b in (w >> 8, w & 0xFF))
    (tmp_path / "board.c").write_text(
        "#include <stddef.h>\n#include <stdint.h>\n#include <stdio.h>\n#include <stdlib.h>\n#include <string.h>\n"
        "int board_i2c(uint8_t addr, const uint8_t *tx, size_t n_tx, uint8_t *rx, size_t n_rx);\n"
        "void board_delay_ms(uint32_t ms);\nvoid board_print(const char *line);\n"
        f"static const uint8_t answer[7] = {{0, {rx}}};\n"
        "int board_i2c(uint8_t addr, const uint8_t *tx, size_t n_tx, uint8_t *rx, size_t n_rx)\n{\n"
        "    (void)addr; (void)tx; (void)n_tx;\n    if (n_rx == 7) memcpy(rx, answer, 7); else memset(rx, 0, n_rx);\n"
        "    return 0;\n}\nvoid board_delay_ms(uint32_t ms) { (void)ms; }\n"
        "void board_print(const char *line) { puts(line); exit(0); }\n"
    )
    exe = tmp_path / "sketch"
    subprocess.run(
        [cc, "-std=c99", "-O2", *c_drivers.STRICT, "-I", tmp_path, SKETCH, tmp_path / "board.c", "-o", exe, "-lm"],
        check=True,
    )
    line = subprocess.run([exe], capture_output=True, text=True, check=True).stdout.strip()
    flag, _ = read_codes(shear, imap, setting, np.array([codes]))
    assert line == f"{flag[0]} (codes -300 450 -200)"
