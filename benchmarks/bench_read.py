"""Speed and accuracy of `mst read --estimate offset` (the table reader). Prints markdown tables;
asserts nothing.

    python benchmarks/bench_read.py [--readings 20000] [--repeats 200] [--exact-repeats 30]

On the bundled sensor (configs/mohammadi2021-forward.yaml, spring, 2 uT chip noise):

* the table's build time and size (the default grid and the C header's coarse one);
* readings per second on one core: `api.read` of a CSV (parse, centred force, forces.csv) with
  --estimate none and offset, and the table's estimate alone (live rates: bench_live.py);
* the error against the truth and against the exact solve (the two-start Gauss-Newton of
  mst_cli/estimation/offset_reading.py) on presses at random points within 80 % of the face, 3
  forces per regime (the tilt rung's own field, so the truth is the reader's model: the table's
  error and the noise, nothing else), noise-free and at 0.5 and 2 uT;
* the estimator's efficiency, Cramer-Rao variance / empirical mean square error over --repeats
  noisy readings of one press (the CRB from the exact model's Jacobian at the truth), per
  coordinate, at 0.5 and 2 uT, for the table and (--exact-repeats) polished by the exact solve;
* offset_table.h compiled on this host: its size and the time per reading (needs cc or gcc).
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

from mst_cli import api
from mst_cli.estimation.inverse_map import inverse_map
from mst_cli.estimation.inverse_table import GRID_DEFAULT, InverseTable, TableGrid, build_table
from mst_cli.estimation.offset_reading import OffsetEstimator
from mst_cli.estimation.table_reader import OffsetTableReader
from mst_cli.estimation.table_store import table_hash
from mst_cli.firmware.table_header import table_header
from mst_cli.model.general_load import pose_field_T
from mst_cli.model.stack_pose import tilt_laws
from mst_cli.sensor.document import load_design_document

ROOT = Path(__file__).resolve().parents[1]
DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"
NOISES_T = (0.5e-6, 2e-6)


def presses(doc, resp, rng, n_offsets=6, per_regime=3):
    """(p (n, 3) truth force N / x0 / y0 mm, B (n, 3) T noise-free) of the tilt rung."""
    geo, mat = doc.geometry(), doc.material
    laws = tilt_laws(geo, mat, "spring")
    edges = np.concatenate([[0.0], resp.lock_forces_N])
    fr = (np.arange(per_regime) + 0.5) / per_regime
    F = np.concatenate([lo + fr * (hi - lo) for lo, hi in zip(edges[:-1], edges[1:])])
    half = 0.4 * np.array([geo.width_mm, geo.depth_mm])
    P, B = [], []
    for _ in range(n_offsets):
        off = rng.uniform(-half, half)
        B.append(pose_field_T(geo, laws, F, tuple(off)))
        P.append(np.column_stack([F, np.tile(off, (len(F), 1))]))
    return np.vstack(P), np.vstack(B)


def speed(doc, reader, B, n, rng):
    rows = B[rng.integers(0, len(B), n)] + rng.normal(0.0, 2e-6, (n, 3))
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        shutil.copy(DESIGN, d / "model.yaml")
        g = reader.table.grid
        current = InverseTable(g, reader.table.B_T, table_hash(d / "model.yaml", "spring", g))
        current.save(d / "inverse_table.npz")  # current beside the model: api.read builds none
        (d / "r.csv").write_text(
            "Bx_uT,By_uT,Bz_uT\n" + "".join(f"{x:.4f},{y:.4f},{z:.4f}\n" for x, y, z in rows * 1e6)
        )
        print("| path | readings | s | readings/s |\n|---|---|---|---|")
        for est in ("none", "offset"):
            t0 = time.perf_counter()
            api.read(d / "model.yaml", d / "r.csv", out=d / "o", estimate=est)
            dt = time.perf_counter() - t0
            print(f"| api.read, --estimate {est} (CSV in, forces.csv out) | {n} | {dt:.2f} | {n / dt:.0f} |")
    reader.table.estimate(rows[:10], reader.sigma_T, reader.max_sigma_mm)  # the corners, once
    t0 = time.perf_counter()
    reader.table.estimate(rows, reader.sigma_T, reader.max_sigma_mm)
    dt = time.perf_counter() - t0
    print(f"| the table's estimate alone | {n} | {dt:.2f} | {n / dt:.0f} |")
    print("(--serial reads in batches: benchmarks/bench_live.py gives its rates beside the file's)\n")


def accuracy(doc, imap, reader, exact, P, B, rng):
    print(
        "| noise | flags (table) | table vs truth: F median / max % (ok) | exact vs truth "
        "| table vs exact: F median / max % | x, y max mm |"
    )
    print("|---|---|---|---|---|---|")
    for sigma in (0.0, *NOISES_T):
        Bn = B + rng.normal(0.0, sigma, B.shape)
        reader.sigma_T = exact.sigma_T = sigma or 2e-6
        est = reader.table.estimate(Bn, reader.sigma_T, reader.max_sigma_mm)
        Fc, _, flag = imap.force(np.linalg.norm(Bn, axis=1), np.zeros(len(Bn), bool))
        ex = exact.estimate_all(Bn, np.where(flag == "ok", Fc, np.nan))
        ok, eok, both = est.flag == "ok", ex.flag == "ok", (est.flag == "ok") & (ex.flag == "ok")
        rel = lambda F, m: 100 * np.abs(F[m] / P[m, 0] - 1)  # noqa: E731
        d = 100 * np.abs(est.force_N[both] - ex.force_N[both]) / P[both, 0]
        dxy = max(np.max(np.abs(est.x_mm[both] - ex.x_mm[both])), np.max(np.abs(est.y_mm[both] - ex.y_mm[both])))
        counts = ", ".join(
            f"{int(np.sum(est.flag == f))} {f}" for f in ("ok", "not_identifiable", "ambiguous", "no_fit")
        )
        print(
            f"| {sigma * 1e6:g} uT{' (flags at 2)' if not sigma else ''} | {counts} | "
            f"{np.median(rel(est.force_N, ok)):.2f} / {np.max(rel(est.force_N, ok)):.1f} | "
            f"{np.median(rel(ex.force_N, eok)):.2f} / {np.max(rel(ex.force_N, eok)):.1f} | "
            f"{np.median(d):.2f} / {np.max(d):.1f} | {dxy:.2f} |"
        )
    reader.sigma_T = exact.sigma_T = 2e-6
    print()


def efficiency(reader, exact, P, B, repeats, exact_repeats, rng):
    print(
        "| noise | press (F N, x, y mm) | CRB 1-sigma (F, x, y) | table: efficiency F / x / y | "
        "ok of repeats | polished: efficiency F / x / y |"
    )
    print("|---|---|---|---|---|---|")
    per = len(P) // 6  # forces per press: one pick per press, spread over the regimes
    picks = [k * per + f for k, f in enumerate(np.linspace(1, per - 1, 6).astype(int))]
    for sigma in NOISES_T:
        reader.sigma_T = exact.sigma_T = sigma
        for i in picks:
            crb = exact._sigmas(exact._jacobian(P[i], exact.field_T(P[i])))
            Bn = B[i] + rng.normal(0.0, sigma, (repeats, 3))
            est = reader.table.estimate(Bn, sigma, np.inf)
            found = np.all(np.isfinite(est.best), axis=1)
            mse = np.mean((est.best[found] - P[i]) ** 2, axis=0)
            eff = crb**2 / mse
            pol = ""
            if exact_repeats:
                polished = OffsetTableReader(reader.table, sigma, np.inf, exact).estimate_table(Bn[:exact_repeats])
                f2 = np.all(np.isfinite(polished.best), axis=1)
                pol = " / ".join(f"{v:.2f}" for v in crb**2 / np.mean((polished.best[f2] - P[i]) ** 2, axis=0))
            print(
                f"| {sigma * 1e6:g} uT | ({P[i, 0]:.1f}, {P[i, 1]:.1f}, {P[i, 2]:.1f}) | "
                f"{crb[0]:.3g} N, {crb[1]:.3g}, {crb[2]:.3g} mm | {' / '.join(f'{v:.2f}' for v in eff)} | "
                f"{int(np.sum(est.flag[found] == 'ok'))} of {repeats} | {pol} |"
            )
    reader.sigma_T = exact.sigma_T = 2e-6
    print()


def c_header(doc, imap, resp, reader, B, rng):
    cc = shutil.which("cc") or shutil.which("gcc")
    coarse = OffsetTableReader(reader.table.every_other(), 2e-6, 1.0)
    text = table_header(coarse, imap, resp.chip_setting, doc.name, "bench_read", ["a benchmark"])
    s = resp.chip_setting
    print(f"offset_table.h: coarse table {coarse.table.grid.shape} nodes, {coarse.table.size_bytes_float32} bytes")
    print(f"  (the default table {reader.table.grid.shape}: {reader.table.size_bytes_float32} bytes as floats)")
    if cc is None:
        print("no C compiler: the header's time per reading is not measured")
        return
    lsb = np.array([s.xy_uT_per_lsb, s.xy_uT_per_lsb, s.z_uT_per_lsb])
    n = 5000
    codes = np.rint((B[rng.integers(0, len(B), n)] * 1e6 + rng.normal(0, 2.0, (n, 3))) / lsb).astype(int)
    with tempfile.TemporaryDirectory() as tmp:
        exe = c_drivers.build(cc, Path(tmp), {"offset_table.h": text}, "offset")
        size = c_drivers.size_line(exe)
        _, dt = c_drivers.run(exe, codes)
    print(f"  compiled driver (size): {size}")
    print(f"  {1e6 * dt / n:.0f} us per reading on this host ({n} readings, process start included)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--readings", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=200)
    ap.add_argument("--exact-repeats", type=int, default=30)
    ap.add_argument("--seed", type=int, default=5)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    doc, _ = load_design_document(DESIGN)
    geo, mat = doc.geometry(), doc.material
    imap, resp = inverse_map(doc, "spring")
    top = float(imap.force_N[-1])
    grid = TableGrid.over(geo, top, *GRID_DEFAULT)
    t0 = time.perf_counter()
    table = build_table(geo, mat, "spring", grid)
    took, size = time.perf_counter() - t0, table.size_bytes_float32
    print(f"table build: {grid.shape} nodes in {took:.1f} s on one core ({size} bytes as floats)\n")
    reader = OffsetTableReader(table, imap.field_resolution_T, 1.0)
    exact = OffsetEstimator(geo, mat, "spring", imap.field_resolution_T, top)
    P, B = presses(doc, resp, rng)
    speed(doc, reader, B, args.readings, rng)
    accuracy(doc, imap, reader, exact, P, B, rng)
    efficiency(reader, exact, P, B, args.repeats, args.exact_repeats, rng)
    c_header(doc, imap, resp, reader, B, rng)
    sys.stdout.flush()


if __name__ == "__main__":
    main()
