"""Calibrating from a rig's load test (issue 38): before and after, on the synthetic rig.
Prints tables; asserts nothing (tests/test_rig_flow.py holds the done-when checks).

    python benchmarks/bench_rig.py [--seed 1] [--mechanics spring|continuum]

The rig (studies/rig_loadtest.py): configs/mohammadi2021-forward.yaml printed with walls
+0.04 mm, modulus x0.9, the chip 0.2 mm further; three calibration cycles to full scale,
hysteresis 6 % of the turning force, cycle 1 8 % stiffer, 2 uT noise, the chip's LSB; then a
held-out stream of two further cycles (another seed).

* "before": the calibration that ignores branches (every row as loading, ``use_branches=False``),
  read without branches;
* "after": the loading rows fitted (a first cycle that differs left out), each reading of the
  stream on its branch with the unloading model.

Tables: the fitted parameters against the truth (value +- 1 sigma), the hysteresis per regime
against the truth, and the held-out stream's force errors per branch and per regime (readings
from a tenth of each regime's top; median and 95th percentile of |F - F_true| / F_true).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "studies"))
sys.path.insert(0, str(ROOT))

from rig_loadtest import PRINT, Rig, forward_curve, rig_loadtest, truth_hysteresis_pct  # noqa: E402

from mst_cli import api  # noqa: E402

DESIGN = ROOT / "configs" / "mohammadi2021-forward.yaml"
COLUMNS = ("force_N", "Bx_uT", "By_uT", "Bz_uT", "time_s", "cycle", "branch", "T_C")


def write_csv(path: Path, rows: dict) -> Path:
    lines = [",".join(COLUMNS)] + [",".join(str(rows[c][i]) for c in COLUMNS) for i in range(len(rows["force_N"]))]
    path.write_text("\n".join(lines) + "\n")
    return path


def errors(F: np.ndarray, F_true: np.ndarray, use: np.ndarray) -> str:
    ok = use & np.isfinite(F)
    if not ok.any():
        return f"{'-':>8} {'-':>8} {int(use.sum()):>5}"
    rel = 100 * np.abs(F[ok] - F_true[ok]) / F_true[ok]
    return f"{np.median(rel):8.2f} {np.percentile(rel, 95):8.2f} {int(use.sum()):>5}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mechanics", default="spring", help="the truth's rung (continuum: ~1 s more)")
    ap.add_argument("--fit-mechanics", default="spring", help="the calibration's and the reader's rung")
    args = ap.parse_args()
    curve = forward_curve(args.mechanics)
    rows, truth = rig_loadtest(Rig(cycles=3, hysteresis_pct=6.0, first_cycle_pct=8.0, seed=args.seed), curve)
    stream, _ = rig_loadtest(Rig(cycles=2, hysteresis_pct=6.0, seed=args.seed + 10), curve)
    with tempfile.TemporaryDirectory() as d:
        lt = write_csv(Path(d) / "lt.csv", rows)
        st = write_csv(Path(d) / "stream.csv", stream)
        runs = {}
        for name, use_branches in (("before", False), ("after", True)):
            fit = args.fit_mechanics
            cal = api.calibrate(DESIGN, lt, out=Path(d) / name, use_branches=use_branches, mechanics=fit)
            runs[name] = (cal, api.read(Path(d) / name / "calibrated.yaml", st, mechanics=fit))
    print(f"truth rung: {args.mechanics}; calibration rung: {args.fit_mechanics}; seed {args.seed}")
    print(f"\n{'parameter':<18} {'truth':>8} {'before':>18} {'after':>18}")
    for p, v in {**PRINT, "remanence_factor": 1.0}.items():
        cells = [f"{runs[n][0].fit.values[p]:9.4f} +-{runs[n][0].fit.std.get(p, float('nan')):7.4f}" for n in runs]
        print(f"{p:<18} {v:>8.4f} {cells[0]:>18} {cells[1]:>18}")
    for n, (cal, _) in runs.items():
        q = cal.record.fit_quality or {}
        print(
            f"{n}: chi2_nu {q.get('chi2_nu', float('nan')):.2f}, runs z {q.get('runs_z', float('nan')):.1f}, "
            f"warning: {'yes (' + str(q.get('cause')) + ')' if q.get('warning') else 'no'}"
        )
    print(f"\n{'hysteresis':<28} {'truth %band':>11} {'measured':>9} {'%FS':>6}")
    for r in runs["after"][0].record.hysteresis["by_regime"]:
        pct, _ = truth_hysteresis_pct(truth, r["force_from_N"], r["force_to_N"])
        band = f"regime {r['regime']} ({r['force_from_N']:.1f}-{r['force_to_N']:.1f} N)"
        print(f"{band:<28} {pct:11.2f} {r['max_pct_of_band']:9.2f} {r['max_pct_of_full_scale']:6.2f}")
    F_true, branch = stream["force_N"], stream["branch"]
    edges = runs["after"][0].inverse_map.edges_N
    print(
        f"\n{'held-out stream':<34} {'before: median':>14} {'p95 %':>8} {'n':>5}"
        f"   {'after: median':>13} {'p95 %':>8} {'n':>5}"
    )
    groups = {f"branch {b}": (branch == b) & (F_true >= 0.1 * edges[-1]) for b in ("loading", "unloading")}
    for i, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        for b in ("loading", "unloading"):
            groups[f"regime {i + 1} {b}"] = (branch == b) & (F_true >= max(lo, 0.1 * hi)) & (F_true < hi)
    for label, use in groups.items():
        cells = [errors(runs[n][1].force_N, F_true, use) for n in runs]
        print(f"{label:<34} {cells[0]:>29}   {cells[1]:>28}")


if __name__ == "__main__":
    main()
