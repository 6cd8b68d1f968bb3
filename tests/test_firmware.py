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

from mst_cli.calibrate.inverse_map import inverse_map
from mst_cli.calibrate.inverse_table import SHEAR_TABLE_RATIO, InverseTable, TableGrid
from mst_cli.calibrate.table_header import C_FLAGS, read_codes, table_header
from mst_cli.calibrate.table_reader import OffsetTableReader, ShearTableReader
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
