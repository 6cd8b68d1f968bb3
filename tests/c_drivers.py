"""The C side of the one-chip headers' checks, shared by tests/test_c_header.py and the read
benchmarks: a driver that reads raw code triples from stdin and prints each reading's flag,
estimates and 1-sigma, compiled against the headers given (several in one program: their names
must not clash), and run on codes."""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

import numpy as np

# per kind: the struct, the function and its six printed fields
KINDS = {
    "offset": ("mst_offset", "force_N, x_mm, y_mm, sigma_force_N, sigma_x_mm, sigma_y_mm"),
    "shear": ("mst_shear", "force_N, shear_x_N, shear_y_N, sigma_force_N, sigma_shear_x_N, sigma_shear_y_N"),
}


# the warnings a firmware build may turn on: the headers compile clean under all of them
STRICT = ("-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wconversion", "-Wdouble-promotion", "-Werror")


def driver_source(kind: str, headers: list[str]) -> str:
    """The driver of ``kind``'s reader, including every header named in ``headers``."""
    name, fields = KINDS[kind]
    printed = ", ".join(f"(double)e.{f}" for f in fields.split(", "))
    # the one file that defines each header's table and code (single-file headers)
    includes = "#define MST_OFF_IMPLEMENTATION\n#define MST_SHR_IMPLEMENTATION\n"
    includes += "".join(f'#include "{h}"\n' for h in headers)
    return (
        f"#include <stdio.h>\n{includes}int main(void)\n{{\n    long x, y, z;\n"
        '    while (scanf("%ld %ld %ld", &x, &y, &z) == 3) {\n'
        f"        struct {name} e = {{0}};\n"
        f"        int flag = {name}_from_codes((int32_t)x, (int32_t)y, (int32_t)z, &e);\n"
        f'        printf("%d %.9g %.9g %.9g %.9g %.9g %.9g\\n", flag, {printed});\n'
        "    }\n    return 0;\n}\n"
    )


def build(cc: str, folder: Path, headers: dict[str, str], kind: str) -> Path:
    """The driver of ``kind`` compiled in ``folder`` (:data:`STRICT`) with ``headers`` (file name:
    text) written beside it; its path."""
    for file, text in headers.items():
        (folder / file).write_text(text)
    (folder / "driver.c").write_text(driver_source(kind, list(headers)))
    exe = folder / "driver"
    subprocess.run([cc, "-std=c99", "-O2", *STRICT, "-o", exe, folder / "driver.c", "-lm"], check=True)
    return exe


def run(exe: Path, codes: np.ndarray) -> tuple[np.ndarray, float]:
    """(the driver's output (n, 7): flag, three estimates, three 1-sigma; seconds it took, the
    process start included) on raw codes (n, 3)."""
    feed = "".join(f"{x} {y} {z}\n" for x, y, z in np.asarray(codes, dtype=np.int64))
    t0 = time.perf_counter()
    out = subprocess.run([exe], input=feed, capture_output=True, text=True, check=True).stdout
    seconds = time.perf_counter() - t0
    return np.array([[float(v) for v in line.split()] for line in out.splitlines()]), seconds


def size_line(exe: Path) -> str:
    """``size``'s line for the compiled driver ('?' without binutils)."""
    try:
        lines = subprocess.run(["size", exe], capture_output=True, text=True).stdout.strip().splitlines()
    except OSError:
        return "?"
    return lines[-1] if lines else "?"
