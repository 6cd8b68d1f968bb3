"""What one estimate costs on a microcontroller: the one-chip headers (shear_table.h,
offset_table.h) compiled with the distribution's gcc-arm-none-eabi for a Cortex-M4F and a
Cortex-M0+ and run in QEMU (mps2-an386, microbit), instructions per reading counted by SysTick
under -icount shift=0 (benchmarks/board/count.c). Prints markdown tables; asserts nothing.

    python benchmarks/bench_board.py [--per-class 40] [--tail 10000] [--kind offset] [--seed 45]

On the bundled sensor (configs/mohammadi2021-forward.yaml, spring), the header-sized tables
(every other node of the default tables, as `mst calibrate` writes them: force nodes following
every kink of the part's laws; offset 2 mm, shear ratio step 0.1), readings in classes: rest
(no load, 2 uT noise), light touch (the first regime's lower half), loaded (over the range),
out of range (beyond the last lock); and loaded to the edges (any force, anywhere in the cone or
on the whole face, as tests/test_c_header.py draws: the tail; --tail N draws N of these, the
other classes --per-class each). Per class: the median, 99th percentile and worst instructions
per reading, how many readings take longer than the goal (1 ms on the M4F, 20 ms on the M0+),
and the time at 64 MHz (M4F) or 48 MHz (M0+) taking one instruction a cycle (the M4F's FPU
divides in 14 cycles, loads take 2: a lower bound within a factor of about 1.5; the M0+ has no
FPU, its float arithmetic is the soft-float library's instructions, counted). Also the flash
(text + data, the list of readings left out) and the reader's stack: its deepest call chain
below <kind>_from_codes, summed from -fstack-usage's frames (the caller's own frame comes on top).
Needs arm-none-eabi-gcc, libnewlib-arm-none-eabi and qemu-system-arm.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("MST_WORKERS", "2")

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.estimation.inverse_table import TableGrid, build_table
from mst_cli.estimation.table_reader import OffsetTableReader, ShearTableReader
from mst_cli.estimation.table_store import grid_of, table_edges_N
from mst_cli.firmware.table_header import C_FLAGS, table_header
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"
BOARD = Path(__file__).resolve().parent / "board"
STRICT = ["-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Wconversion", "-Wdouble-promotion", "-Werror"]
TARGETS = {  # cpu: (gcc flags, QEMU machine, flash kB, RAM kB, MHz)
    "Cortex-M4F": (
        ["-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16"],
        "mps2-an386",
        4096,
        4096,
        64,
    ),
    "Cortex-M0+": (["-mcpu=cortex-m0plus", "-mthumb"], "microbit", 256, 16, 48),
}
CAL_INSNS = 200_000  # count.c's calibration loop
GOAL_MS = {"Cortex-M4F": 1.0, "Cortex-M0+": 20.0}  # issue 45: the most a reading may take
STRUCTS = {"shear": "mst_shear", "offset": "mst_offset"}


def readings(table, imap, rng, n: int, n_tail: int) -> dict[str, np.ndarray]:
    """Fields (uT) per class, ``n`` of each (``n_tail`` loaded to the edges), from the table's own
    field (its nodes interpolated) and 2 uT noise."""
    g = table.grid
    at = RegularGridInterpolator((g.force_N, g.u, g.v), 1e6 * table.B_T)
    top, first = g.force_N[-1], imap.edges_N[1]

    def draw(lo, hi, reach=0.6, n=n):
        p = np.column_stack(
            [rng.uniform(lo, hi, n), rng.uniform(*g.u[[0, -1]], n) * reach, rng.uniform(*g.v[[0, -1]], n) * reach]
        )
        return at(p) + rng.normal(0.0, 2.0, (n, 3))

    beyond = at(np.column_stack([np.full(n, top), np.zeros(n), np.zeros(n)])) * rng.uniform(1.05, 1.3, (n, 1))
    return {
        "rest": at(np.zeros((n, 3))) + rng.normal(0.0, 2.0, (n, 3)),
        "light touch": draw(0.02 * first, 0.5 * first),
        "loaded": draw(0.05 * top, top),
        "out of range": beyond,
        "loaded, to the edges": draw(0.0, top, 1.0, n_tail),
    }


def build(folder: Path, header: str, kind: str, codes: np.ndarray, cpu: str) -> tuple[Path, str, int]:
    """The counting program for ``cpu``: (its ELF, size's line, the deepest stack in bytes)."""
    flags, _, flash, ram, _ = TARGETS[cpu]
    (folder / "table.h").write_text(header)
    rows = ",\n".join(f"    {{{x}, {y}, {z}}}" for x, y, z in codes)
    (folder / "codes.h").write_text(
        f"#define N_CODES {len(codes)}\n#define MST_STRUCT struct {STRUCTS[kind]}\n"
        f"#define MST_FROM_CODES {STRUCTS[kind]}_from_codes\n"
        f"static const int32_t codes[N_CODES][3] = {{\n{rows}\n}};\n"
    )
    cc = ["arm-none-eabi-gcc", "-std=c99", "-O2", "-ffreestanding", *flags]
    subprocess.run([*cc, "-c", BOARD / "startup.c", "-o", folder / "s.o"], check=True)
    subprocess.run(
        [*cc, *STRICT, "-fstack-usage", "-I", folder, "-c", BOARD / "count.c", "-o", folder / "c.o"], check=True
    )
    elf = folder / "count.elf"
    link = ["-nostartfiles", "--specs=nano.specs", "--specs=nosys.specs", "-T", BOARD / "board.ld"]
    mem = [f"-Wl,--defsym=FLASH_K={flash}", f"-Wl,--defsym=RAM_K={ram}"]
    subprocess.run([*cc, *link, *mem, folder / "s.o", folder / "c.o", "-lm", "-o", elf], check=True)
    size = subprocess.run(["arm-none-eabi-size", elf], capture_output=True, text=True).stdout.splitlines()[-1]
    return elf, size, reader_stack((folder / "c.su").read_text())


# the reader's call chains below <kind>_from_codes (a function gcc inlined has no frame of its own)
CHAINS = (
    ("from_codes", "descend_", "held_step_", "step_"),
    ("from_codes", "descend_", "field_", "trilinear_"),
    ("from_codes", "descend_", "field_", "locate_"),
    ("from_codes", "judge_", "trilinear_"),
    ("from_codes", "judge_", "locate_"),
)


def reader_stack(su: str) -> int:
    """The deepest of the reader's call chains (CHAINS) in bytes, from -fstack-usage's frames."""
    frames: dict[str, int] = {}
    for name, size in re.findall(r":([A-Za-z_][\w.]*)\t(\d+)\t", su):
        key = name.split(".")[0]
        frames[key] = max(frames.get(key, 0), int(size))

    def frame(part: str) -> int:  # mst_<prefix>_<part> (held_step_ is not step_)
        return max((v for k, v in frames.items() if k.startswith("mst_") and k.split("_", 2)[-1] == part), default=0)

    return max(sum(frame(f) for f in chain) for chain in CHAINS)


def run(elf: Path, cpu: str) -> tuple[np.ndarray, np.ndarray]:
    """(flags, instructions) per reading, from QEMU."""
    machine = TARGETS[cpu][1]
    out = subprocess.run(
        [
            "qemu-system-arm",
            "-M",
            machine,
            "-nographic",
            "-monitor",
            "none",
            "-serial",
            "none",
            "-semihosting-config",
            "enable=on,target=native",
            "-icount",
            "shift=0",
            "-kernel",
            elf,
        ],
        capture_output=True,
        text=True,
        timeout=3600,
        check=True,
    ).stderr.split()  # semihosting writes to QEMU's stderr
    per_tick = CAL_INSNS / float(out[1])
    vals = np.array(out[2:], dtype=float).reshape(-1, 2)
    return vals[:, 0].astype(int), vals[:, 1] * per_tick


CHUNK = 6000  # readings per program: their codes (12 bytes each) share the M0+'s 256 kB of flash


def count(header: str, kind: str, codes: np.ndarray, cpu: str) -> tuple[np.ndarray, np.ndarray, int, int]:
    """(flags, instructions) per reading of ``codes`` through ``header`` on ``cpu``, CHUNK
    readings a program; the program's flash (text + data) less its list of codes, and the
    reader's stack (bytes)."""
    flags, insns = [], []
    for part in np.array_split(codes, -(-len(codes) // CHUNK)):
        with tempfile.TemporaryDirectory() as tmp:
            elf, size, stack = build(Path(tmp), header, kind, part, cpu)
            f, i = run(elf, cpu)
        flags.append(f)
        insns.append(i)
        text, data = (int(v) for v in size.split()[:2])
    return np.concatenate(flags), np.concatenate(insns), text + data - 12 * len(part), stack


def two_chip_table(grids: dict[str, tuple[TableGrid, ...]]) -> str:
    """What a two-chip header's table would hold: the fields at both chips (6 numbers) on every
    node of the five coordinates (F, Fx / Fz, Fy / Fz, x0, y0), the shear grid's force and ratio
    nodes by the offset grid's press positions, for ``grids`` ((shear grid, offset grid) pairs),
    as int16 (the most compact that keeps the chip's resolution) and as float."""
    rows = []
    for name, (shear, offset) in grids.items():
        s, o = shear.shape, offset.shape
        nodes = s[0] * s[1] * s[2] * o[1] * o[2]
        rows.append(
            f"| {name} | {s[0]} x {s[1]} x {s[2]} x {o[1]} x {o[2]} | {nodes:,} | "
            f"{6 * 2 * nodes / 2**20:.1f} MB | {6 * 4 * nodes / 2**20:.1f} MB |"
        )
    head = "| two-chip table | nodes (F, Fx/Fz, Fy/Fz, x0, y0) | count | int16 | float |\n|---|---|---|---|---|\n"
    return head + "\n".join(rows)


def header_grid(kind: str, doc, top: float, edges) -> TableGrid:
    """The grid of the header ``mst calibrate --{kind}-table`` writes: every other node of the
    default table's (its force nodes following every kink of the part's laws, ``edges``); the
    table is built on it directly rather than halved from the default table (the same nodes)."""
    return grid_of(kind, doc, top, None, edges).every_other()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--per-class", type=int, default=40)
    ap.add_argument("--tail", type=int, default=None, help="readings loaded to the edges (default: --per-class)")
    ap.add_argument("--kind", choices=tuple(STRUCTS), action="append", help="only this header (repeatable)")
    ap.add_argument("--seed", type=int, default=45)
    args = ap.parse_args()
    if not all(shutil.which(t) for t in ("arm-none-eabi-gcc", "qemu-system-arm")):
        sys.exit(
            "needs arm-none-eabi-gcc and qemu-system-arm "
            "(apt: gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm)"
        )
    rng = np.random.default_rng(args.seed)
    doc, _ = load_design_document(DESIGN)
    imap, resp = inverse_map(doc, "spring")
    setting, top = resp.chip_setting, float(imap.force_N[-1])
    lsb = np.array([setting.xy_uT_per_lsb, setting.xy_uT_per_lsb, setting.z_uT_per_lsb])
    print(
        "| header | CPU | class | flags | instructions median / p99 / worst | ms median / worst | over the goal "
        "| flash | stack B |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    edges = table_edges_N(doc, imap, "spring", 1.0)
    for kind in args.kind or ("shear", "offset"):
        table = build_table(doc.geometry(), doc.material, "spring", header_grid(kind, doc, top, edges))
        reader = ShearTableReader(table, 2e-6) if kind == "shear" else OffsetTableReader(table, 2e-6, 1.0)
        header = table_header(reader, imap, setting, doc.name, "bench_board", ["a benchmark"])
        classes = readings(table, imap, rng, args.per_class, args.tail or args.per_class)
        codes = np.vstack([np.rint(b / lsb) for b in classes.values()]).astype(np.int64)
        for cpu in TARGETS:
            flags, insns, flash, stack = count(header, kind, codes, cpu)
            mhz = TARGETS[cpu][4]
            ends = np.cumsum([0, *(len(c) for c in classes.values())])
            for k, name in enumerate(classes):
                part = slice(ends[k], ends[k + 1])
                f = ", ".join(f"{int(np.sum(flags[part] == i))} {C_FLAGS[i]}" for i in np.unique(flags[part]))
                m, q, w = np.median(insns[part]), np.percentile(insns[part], 99), np.max(insns[part])
                over = int(np.sum(insns[part] > GOAL_MS[cpu] * mhz * 1e3))
                print(
                    f"| {kind}_table.h {table.grid.shape} | {cpu} | {name} | {f} | {m:,.0f} / {q:,.0f} / {w:,.0f} | "
                    f"{m / mhz / 1e3:.2f} / {w / mhz / 1e3:.2f} | {over} of {ends[k + 1] - ends[k]} | "
                    f"{flash / 1024:.0f} kB | {stack} |"
                )
        sys.stdout.flush()
    print()
    kinds = ("shear", "offset")
    grids = {
        "the headers' grids": tuple(header_grid(k, doc, top, edges) for k in kinds),
        "the default tables' grids": tuple(grid_of(k, doc, top, None, edges) for k in kinds),
    }
    print(two_chip_table(grids))


if __name__ == "__main__":
    main()
