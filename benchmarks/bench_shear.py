"""Speed and accuracy of `mst read --estimate shear` (one chip, the shear table). Prints markdown
tables; asserts nothing.

    python benchmarks/bench_shear.py [--presses 200] [--polished 60] [--readings 20000] [--seed 39]

On the bundled sensor as printed (configs/mohammadi2021-forward.yaml):

* the shear table's build time and size on one core (the default grid and the C header's coarse
  one), on L0 (spring, `mst read`'s default rung) and on L2 (continuum);
* readings per second on one core: `api.read` of a CSV (parse, centred force, forces.csv) with
  --estimate none and shear, the table's estimate alone, and one reading at a time (--serial);
* round trips: the truth is the general-load model on L2 (tilts and slides from L2's laws,
  evaluated press by press, not from a table), centred presses with the normal force uniform over
  5-100 % of the range and a tangential force up to 0.3 of it; the table readers on L0 and on L2
  at 0.5 and 2 uT per axis. Median errors (normal: relative; tangential: the vector error over
  |F_t|, presses with |F_t| >= 0.2 N) beside the median Cramer-Rao 1-sigma at the truth (L2's
  exact Jacobian), and the efficiency sum(sigma_CRB^2) / sum(error^2) (1: efficient and unbiased;
  a model or table error pulls it below 1), and the L2 table polished by the exact fit
  (--polished presses: what the table's interpolation costs);
* shear_table.h compiled on this host: its size and the time per reading (needs cc or gcc).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MST_WORKERS", "1")  # one core: the table build too
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the C driver, shared with the test

import c_drivers
import numpy as np
from scipy.interpolate import RegularGridInterpolator

from mst_cli import api
from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.estimation.inverse_table import SHEAR_GRID_DEFAULT, SHEAR_TABLE_RATIO, InverseTable, TableGrid, build_table
from mst_cli.estimation.shear_reading import ShearReader
from mst_cli.estimation.table_reader import ShearTableReader
from mst_cli.estimation.table_store import table_hash
from mst_cli.firmware.table_header import table_header
from mst_cli.model.general_load import field_T, loaded_stack
from mst_cli.model.load_bound import CENTRED, crb_sigma, field_jacobian
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"
NOISES_T = (0.5e-6, 2e-6)
SHEAR_MAX = 0.3
FT_MIN_N = 0.2


def presses(rng, n: int, range_N: float) -> np.ndarray:
    """(n, 3) centred loads Fz, Fx, Fy: Fz over 5-100 % of the range, |F_t| <= SHEAR_MAX Fz,
    uniform over the cone's disc."""
    Fz = rng.uniform(0.05, 1.0, n) * range_N
    r = SHEAR_MAX * np.sqrt(rng.uniform(0.0, 1.0, n))
    a = rng.uniform(0.0, 2 * np.pi, n)
    return np.column_stack([Fz, r * Fz * np.cos(a), r * Fz * np.sin(a)])


def truth_of(stack, L: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the exact fields (n, 3) T, the bound (n, 3) at 1 T of noise) on the truth's model."""
    chip = [stack.geometry.chip_offset_mm]
    B = np.array([field_T(stack, F, (fx, fy), (0.0, 0.0))[0] for F, fx, fy in L])
    crb = np.array([crb_sigma(field_jacobian(stack, np.array([*t, 0.0, 0.0]), chip, list(CENTRED)), 1.0) for t in L])
    return B, crb


def tables(doc, top_N: float) -> dict[str, InverseTable]:
    out = {}
    print("| rung | table nodes | build s (one core) | bytes as floats | coarse (C header) nodes | bytes |")
    print("|---|---|---|---|---|---|")
    for name, mech in (("L0 (spring)", "spring"), ("L2 (continuum)", "continuum")):
        grid = TableGrid.cone(top_N, SHEAR_GRID_DEFAULT[0], SHEAR_TABLE_RATIO, SHEAR_GRID_DEFAULT[1])
        t0 = time.perf_counter()
        out[name] = build_table(doc.geometry(), doc.material, mech, grid)
        dt = time.perf_counter() - t0
        c = out[name].every_other()
        print(
            f"| {name} | {grid.shape} | {dt:.1f} | {out[name].size_bytes_float32} | {c.grid.shape} | "
            f"{c.size_bytes_float32} |"
        )
    print()
    return out


def speed(doc_file: Path, n: int, rng) -> tuple[InverseTable, np.ndarray]:
    """Readings of the design as drawn (its L0 table's own field at random loads in the cone,
    0.5 uT of noise) read by `api.read` with its table current beside it; the table and the
    readings (T) back."""
    doc, _ = load_design_document(doc_file)
    imap, _ = inverse_map(doc, "spring")
    grid = TableGrid.cone(float(imap.force_N[-1]), SHEAR_GRID_DEFAULT[0], SHEAR_TABLE_RATIO, SHEAR_GRID_DEFAULT[1])
    table = build_table(doc.geometry(), doc.material, "spring", grid)
    p = np.column_stack([rng.uniform(0.05, 1.0, n) * grid.force_N[-1], rng.uniform(-0.3, 0.3, (n, 2))])
    rows = RegularGridInterpolator((grid.force_N, grid.u, grid.v), table.B_T)(p) + rng.normal(0.0, 0.5e-6, (n, 3))
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        shutil.copy(doc_file, d / "model.yaml")
        g = table.grid
        InverseTable(g, table.B_T, table_hash(d / "model.yaml", "spring", g)).save(d / "shear_table.npz")
        (d / "r.csv").write_text(
            "Bx_uT,By_uT,Bz_uT\n" + "".join(f"{x:.4f},{y:.4f},{z:.4f}\n" for x, y, z in rows * 1e6)
        )
        print("| path | readings | s | readings/s |\n|---|---|---|---|")
        for est in ("none", "shear"):
            t0 = time.perf_counter()
            api.read(d / "model.yaml", d / "r.csv", out=d / "o", estimate=est)
            dt = time.perf_counter() - t0
            print(f"| api.read, --estimate {est} (CSV in, forces.csv out) | {n} | {dt:.2f} | {n / dt:.0f} |")
    reader = ShearTableReader(table, 0.5e-6)
    table.estimate(rows[:10], 0.5e-6, np.inf)  # the corners, once
    t0 = time.perf_counter()
    table.estimate(rows, 0.5e-6, np.inf)
    dt = time.perf_counter() - t0
    print(f"| the table's estimate alone | {n} | {dt:.2f} | {n / dt:.0f} |")
    t0 = time.perf_counter()
    for b in rows[:500]:
        reader.estimate_all(b[None], np.array([1.0]))
    dt = time.perf_counter() - t0
    print(f"| one reading at a time (--serial) | 500 | {dt:.2f} | {500 / dt:.0f} |\n")
    return table, rows


def polished(table: InverseTable, stack, noisy: np.ndarray, noise: float, n: int) -> np.ndarray:
    """(n, 3) the first ``n`` readings polished by the exact fit on ``stack`` (NaN: not ok)."""
    r = ShearTableReader(table, noise, ShearReader(stack)).estimate_all(noisy[:n], np.ones(n))
    return np.column_stack([np.where(r.flag == "ok", r.force_N, np.nan), r.shear_x_N, r.shear_y_N])


def roundtrip(readers: dict[str, InverseTable], L: np.ndarray, B: np.ndarray, crb: np.ndarray, rng, polish) -> None:
    """Every table reader on the same noisy readings, and (``polish`` = (the L2 stack, n)) the
    L2 table polished by the exact fit on the first n."""
    print(
        "| reader | noise uT | Fz error (CRB) | eff | F_t error (CRB) | eff | flagged |\n|---|---|---|---|---|---|---|"
    )
    for noise in NOISES_T:
        noisy = B + rng.normal(0.0, noise, B.shape)
        rows = [(name, table.estimate(noisy, noise, np.inf).p) for name, table in readers.items()]
        stack, n = polish
        if n:
            rows.append((f"L2, polished ({n})", polished(readers["L2 (continuum)"], stack, noisy, noise, n)))
        for name, p in rows:
            m = len(p)
            print(f"| {name} | {noise * 1e6:g} | " + score(p, L[:m], crb[:m] * noise) + " |")
    print()


def score(p: np.ndarray, L: np.ndarray, s: np.ndarray) -> str:
    """The medians of the errors and of the bound ``s`` (n, 3), the efficiencies, the flagged."""
    ok = np.isfinite(p[:, 0])
    Fz, Ft = L[:, 0], np.hypot(L[:, 1], L[:, 2])
    big = Ft >= FT_MIN_N
    e = p - L
    et = np.hypot(e[:, 1], e[:, 2])
    okb = ok & big
    crb_t = np.median(np.hypot(s[big, 1], s[big, 2]) / Ft[big])
    return (
        f"{100 * np.median(np.abs(e[ok, 0]) / Fz[ok]):.2f} % ({100 * np.median(s[:, 0] / Fz):.2f} %) | "
        f"{np.sum(s[ok, 0] ** 2) / np.sum(e[ok, 0] ** 2):.2f} | "
        f"{100 * np.median(et[okb] / Ft[okb]):.1f} % ({100 * crb_t:.1f} %) | "
        f"{np.sum(s[ok, 1] ** 2 + s[ok, 2] ** 2) / np.sum(et[ok] ** 2):.2f} | {int(np.sum(~ok))}"
    )


def c_header(doc, imap, resp, table: InverseTable, B: np.ndarray, rng) -> None:
    cc = shutil.which("cc") or shutil.which("gcc")
    coarse = ShearTableReader(table.every_other(), 0.5e-6)
    text = table_header(coarse, imap, resp.chip_setting, doc.name, "bench_shear", ["a benchmark"])
    print(f"shear_table.h: coarse table {coarse.table.grid.shape} nodes, {len(text)} bytes of C")
    if cc is None:
        print("no C compiler: the header's time per reading is not measured")
        return
    s = resp.chip_setting
    lsb = np.array([s.xy_uT_per_lsb, s.xy_uT_per_lsb, s.z_uT_per_lsb])
    n = 5000
    codes = np.rint(B[:n] * 1e6 / lsb).astype(int)  # the readings as the chip's codes
    with tempfile.TemporaryDirectory() as tmp:
        exe = c_drivers.build(cc, Path(tmp), {"shear_table.h": text}, "shear")
        size = c_drivers.size_line(exe)
        _, dt = c_drivers.run(exe, codes)
    print(f"  compiled driver (size): {size}")
    print(f"  {1e6 * dt / n:.0f} us per reading on this host ({n} readings, process start included)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--presses", type=int, default=200)
    ap.add_argument("--readings", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=39)
    ap.add_argument("--polished", type=int, default=60, help="presses polished by the exact fit (0.1 s each)")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    doc, _ = load_design_document(DESIGN)
    printed = as_printed(doc)
    truth = loaded_stack(printed.geometry(), printed.material, "continuum")
    range_N = max(t.lock_force_N for t in truth.tilt)
    print(f"{DESIGN.name} as printed: range {range_N:.2f} N (L2's last lock), {args.presses} centred presses\n")
    readers = tables(printed, range_N)
    L = presses(rng, args.presses, range_N)
    B, crb = truth_of(truth, L)
    roundtrip(readers, L, B, crb, rng, (truth, args.polished))
    table, rows = speed(DESIGN, args.readings, rng)
    imap, resp = inverse_map(doc, "spring")
    c_header(doc, imap, resp, table, rows, rng)
    sys.stdout.flush()


if __name__ == "__main__":
    main()
