"""Calibrating from a rig's load test (issue 38): before and after, on the synthetic rig.
Prints tables; asserts nothing (tests/test_rig_flow.py holds the done-when checks).

    python benchmarks/bench_rig.py [--seed 1] [--mechanics spring|continuum]

The rig (studies/rig_loadtest.py): configs/mohammadi2021-forward.yaml with the default 0.3 mm air, printed with walls
+0.04 mm, modulus x0.9, the chip 0.2 mm further; three calibration cycles to full scale,
hysteresis 6 % of the turning force, cycle 1 8 % stiffer, 2 uT noise, the chip's LSB; then a
held-out stream of two further cycles (another seed).

* "before": the calibration that ignores branches (every row as loading, ``use_branches=False``),
  read without branches;
* "after": the loading rows fitted (a first cycle that differs left out), each reading of the
  stream on its branch with the unloading model.

Tables: the fitted parameters against the truth (value +- 1 sigma), the hysteresis per regime
against the truth, and the held-out stream's force errors per branch and per regime (readings
from a tenth of each regime's top; median and 95th percentile of |F - F_true| / F_true); then
print 2: ``mst design configs/mohammadi2021.yaml --calibration`` of the "after" calibration,
printed by the truth's printer (walls +0.04 mm, modulus x0.9, gap +0.2 mm, the grade's magnet),
its S and R per layer against the spec's targets.

    python benchmarks/bench_rig.py --temperature [--seed 1]

The rig at 20, 30 and 40 degC (one cycle each, remanence at the grade's -0.12 %/K, the TPU's
modulus at the stated test coefficient -0.8 %/K): the fitted modulus_temp_coeff_per_K, and the
held-out stream's median force error per temperature read with T_C and without it.

    python benchmarks/bench_rig.py --real [--seed 1]

The real rig's log (issue 47, studies/rig_log.py at eFlesh's measured sizes: 3/3/4.5 uT noise,
a 0.2 s lag, the force on half the rows (-1 elsewhere) and clipped at 0, a 1.1 s gap at every
turn, 15 uT/min drift, the zero 1.6 % of the span off after each unloading (3.2 % after the first
press) recovering 1.5 % a decade, the loop -3 % near no load / +2 % mid-range / +2.5 % open after a
hold, softening +68/+20/+8 % at 10/50/90 % of full scale fading as press^-1.5, creep 1 % a decade
on two 5 s holds; 10 presses): what the calibration recovers against the truth, and a held-out
stream of presses 11-14 (its zero moved 117 uT) read with ``--track-zero`` and without.
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

from rig_loadtest import PRINT, Rig, forward_curve, rig_design, rig_loadtest, truth_hysteresis_pct  # noqa: E402

from mst_cli import api  # noqa: E402

DESIGN = rig_design()  # the forward design with the default air (studies/rig_loadtest.py)
SPEC = ROOT / "configs" / "mohammadi2021.yaml"
TEMPS = (20.0, 30.0, 40.0)
COLUMNS = ("force_N", "Bx_uT", "By_uT", "Bz_uT", "time_s", "cycle", "branch", "T_C")


def write_csv(path: Path, rows: dict, columns: tuple[str, ...] = COLUMNS) -> Path:
    lines = [",".join(columns)] + [",".join(str(rows[c][i]) for c in columns) for i in range(len(rows["force_N"]))]
    path.write_text("\n".join(lines) + "\n")
    return path


def errors(F: np.ndarray, F_true: np.ndarray, use: np.ndarray) -> str:
    ok = use & np.isfinite(F)
    if not ok.any():
        return f"{'-':>8} {'-':>8} {int(use.sum()):>5}"
    rel = 100 * np.abs(F[ok] - F_true[ok]) / F_true[ok]
    return f"{np.median(rel):8.2f} {np.percentile(rel, 95):8.2f} {int(use.sum()):>5}"


def print2(cal_dir: Path, out: Path) -> list[str]:
    """Print 2 designed with the calibration, printed by the truth's printer: S and R per layer
    against the spec's targets (lines of a table)."""
    from mst_cli.model.response import simulate
    from mst_cli.sensor.as_printed import apply_parameters
    from mst_cli.sensor.document import load_document

    api.run_design(SPEC, calibration=cal_dir / "calibration.json", out=out, plot=False)
    doc = load_document(out / "design.yaml")
    Br = load_document(DESIGN).magnet.remanence_T
    truth, _ = apply_parameters(doc, {**PRINT, "remanence_factor": Br / doc.magnet.remanence_T})
    resp = simulate(truth.geometry(), truth.material, mechanics="spring")
    spec = load_document(SPEC)
    lines = [f"{'print 2, layer':<16} {'S target':>9} {'S':>9} {'%':>6} {'R target':>9} {'R':>9} {'%':>6}"]
    for r in sorted(resp.regimes, key=lambda r: r.layer):
        la = spec.layers[r.layer - 1]
        S, R = r.sensitivity_secant_per_N, r.force_to_N
        tS, tR = la.target_sensitivity_per_N, la.target_range_N
        lines.append(
            f"{r.layer:<16} {tS:9.4f} {S:9.4f} {100 * (S / tS - 1):+6.2f} {tR:9.3f} {R:9.3f} {100 * (R / tR - 1):+6.2f}"
        )
    return lines


def temperature(seed: int) -> None:
    """The --temperature table (module doc)."""
    curve = forward_curve()
    rows, _ = rig_loadtest(Rig(cycles=3, T_C=TEMPS, hysteresis_pct=6.0, seed=seed), curve)
    stream, _ = rig_loadtest(Rig(cycles=3, T_C=TEMPS, hysteresis_pct=6.0, seed=seed + 10), curve)
    no_T = tuple(c for c in COLUMNS if c != "T_C")
    with tempfile.TemporaryDirectory() as d:
        cal = api.calibrate(DESIGN, write_csv(Path(d) / "lt.csv", rows), out=Path(d) / "cal")
        got = api.read(Path(d) / "cal" / "calibrated.yaml", write_csv(Path(d) / "s.csv", stream))
        plain = api.read(Path(d) / "cal" / "calibrated.yaml", write_csv(Path(d) / "p.csv", stream, no_T))
    t = cal.record.temperature or {}
    print(f"seed {seed}; {cal.temperature.line() if cal.temperature else 'no temperature'}")
    print(f"truth: modulus_temp_coeff_per_K -0.8 %/K; fitted {100 * t.get('modulus_temp_coeff_per_K', 0):+.3f} %/K")
    print(f"\n{'held-out, T degC, branch':<26} {'with T_C: median %':>18} {'without':>8} {'n':>4} {'above_range':>11}")
    F = stream["force_N"]
    for T in TEMPS:
        for b in ("loading", "unloading", "both"):
            use = (stream["T_C"] == T) & (F >= 0.1 * curve.full_scale_N) & ((stream["branch"] == b) | (b == "both"))
            ok = use & np.isfinite(got.force_N)  # the same readings for both readers
            cells = [np.median(np.abs(r.force_N[ok] - F[ok]) / F[ok]) * 100 for r in (got, plain)]
            n_above = int(np.sum(use & (got.flag == "above_range")))
            print(f"{f'{T:g} {b}':<26} {cells[0]:18.2f} {cells[1]:8.2f} {int(ok.sum()):>4} {n_above:>11}")


def real(seed: int) -> None:
    """The --real table (module doc)."""
    from rig_log import RigLog, rig_log, write_log

    curve = forward_curve()
    rig = RigLog(seed=seed)
    rows, truth = rig_log(rig, curve)
    stream, st_truth = rig_log(RigLog(cycles=4, first_cycle=11, zero_shift_uT=117.0, hold_cycles=(13,), seed=seed + 6))
    with tempfile.TemporaryDirectory() as d:
        write_log(Path(d) / "lt.csv", rows)
        cal = api.calibrate(DESIGN, Path(d) / "lt.csv", out=Path(d) / "cal", missing_force=-1.0)
        cols = ("time_s", "Bx_uT", "By_uT", "Bz_uT")
        write_csv(Path(d) / "s.csv", stream, cols)
        reads = {tz: api.read(Path(d) / "cal" / "calibrated.yaml", Path(d) / "s.csv", track_zero=tz) for tz in (0, 1)}
    r, span = cal.record, truth.span_uT
    a, z, s = r.time_alignment or {}, r.zero or {}, r.softening or {}
    print(f"seed {seed}; {len(rows['time_s'])} rows, force on {np.isfinite(rows['force_N']).mean():.0%}")
    print(f"\n{'quantity':<34} {'truth':>9} {'calibrated':>20}")
    cells = [(p, v, cal.fit.values[p], cal.fit.std[p]) for p, v in PRINT.items()]
    cells += [
        ("lag s", rig.lag_s, a.get("lag_s"), a.get("lag_sigma_s")),
        ("drift uT/min", 60 * rig.drift_uT_per_s, z.get("drift_uT_per_min"), z.get("drift_sigma_uT_per_min")),
        ("offset after unloading uT", -0.01 * rig.zero_off_pct * span, z.get("offset_after_unloading_uT"),
         z.get("offset_after_unloading_sigma_uT")),
        ("offset after press 1 uT", -0.01 * rig.first_zero_off_pct * span, z.get("offset_after_first_press_uT"),
         z.get("offset_after_first_press_sigma_uT")),
        ("recovery uT/decade", 0.01 * rig.zero_recovery_pct_per_decade * span, z.get("recovery_uT_per_decade"),
         z.get("recovery_sigma_uT_per_decade")),
        ("softening decay q", rig.softening_decay, s.get("decay_q"), s.get("decay_q_sigma")),
    ]  # fmt: skip
    for key, want in zip(("10_pct_fs", "50_pct_fs", "90_pct_fs"), rig.softening_pct):
        got = (s.get("first_press_stiffer_pct") or {}).get(key)
        cells.append(
            (f"press 1 stiffer % at {key[:2]} % FS", want, got, (s.get("first_press_sigma_pct") or {}).get(key))
        )
    for name, want, got, sd in cells:
        print(f"{name:<34} {want:9.4g} {got if got is not None else float('nan'):11.4g} +- {sd or float('nan'):6.2g}")
    h = r.hysteresis or {}
    for c in h.get("creep", []):
        want = rig.creep_pct_per_decade
        print(f"{'creep % / decade':<34} {want:9.4g} {c['pct_per_decade']:11.4g} +- {c['sigma_pct']:6.2g}")
    u = h.get("unloading_model") or {}
    print(f"unloading model unexplained: {u.get('residual_pct_of_full_scale', float('nan')):.2f} % of full scale")
    print(f"presses left out {s.get('presses_left_out')}, presses to settle {s.get('presses_to_settle')}")
    print(f"\n{'held-out stream':<18} {'plain: median %':>15} {'p95 %':>7} {'--track-zero: median %':>23} {'p95 %':>7}")
    F = st_truth.force_N
    for b in ("loading", "unloading"):
        use = (st_truth.branch == b) & (F >= 0.1 * curve.full_scale_N)
        row = []
        for tz in (0, 1):
            rel = 100 * np.abs(reads[tz].force_N[use] - F[use]) / F[use]
            rel = np.where(np.isfinite(rel), rel, 100.0)  # a flagged reading counts as 100 % off
            row.append(f"{np.median(rel):15.2f} {np.percentile(rel, 95):7.2f}")
        print(f"{b:<18} {row[0]} {row[1]:>31}")


def gap_without_landing(seeds: int) -> None:
    """The gap offset fitted on the bundled forward config (0.65 mm of air: its cover does not
    land inside the range, so no corner of the load curve tells the gap from the remanence),
    over noise seeds 1..``seeds`` of the done-when rig (docs/design.md 4.6, Contacts)."""
    bundled = ROOT / "configs" / "mohammadi2021-forward.yaml"
    curve = forward_curve(design=bundled)
    truth = PRINT["gap_offset_mm"]
    print(f"gap offset on {bundled.name} (truth {truth} mm), fitted +- the fit's sigma:")
    misses = []
    with tempfile.TemporaryDirectory() as d:
        for seed in range(1, seeds + 1):
            rows, _ = rig_loadtest(Rig(cycles=3, hysteresis_pct=6.0, first_cycle_pct=8.0, seed=seed), curve)
            fit = api.calibrate(bundled, write_csv(Path(d) / f"lt{seed}.csv", rows), out=Path(d) / f"c{seed}").fit
            value, sd = fit.values["gap_offset_mm"], fit.std["gap_offset_mm"]
            misses.append(value - truth)
            print(f"  seed {seed}: {value:.3f} +- {sd:.3f} mm")
    print(f"RMS error {np.sqrt(np.mean(np.square(misses))):.3f} mm over {seeds} seeds")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--mechanics", default="spring", help="the truth's rung (continuum: ~1 s more)")
    ap.add_argument("--fit-mechanics", default="spring", help="the calibration's and the reader's rung")
    ap.add_argument("--temperature", action="store_true", help="the table at 20, 30 and 40 degC instead")
    ap.add_argument("--real", action="store_true", help="the real rig's log (issue 47) instead")
    ap.add_argument(
        "--gap-without-landing", type=int, metavar="SEEDS", help="the gap offset on the bundled config, SEEDS seeds"
    )
    args = ap.parse_args()
    if args.gap_without_landing:
        return gap_without_landing(args.gap_without_landing)
    if args.temperature:
        return temperature(args.seed)
    if args.real:
        return real(args.seed)
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
        print2_lines = print2(Path(d) / "after", Path(d) / "print2")
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

    print()
    print("\n".join(print2_lines))


if __name__ == "__main__":
    main()
