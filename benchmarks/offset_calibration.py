"""Calibrate the tilt from presses at known offsets, then read presses elsewhere (issue 24).

A synthetic printed sensor, the bundled design (configs/mohammadi2021-forward.yaml) whose layers
follow L2 (the continuum rung) and whose levers are --true-lever-factor times the tilt rung's
(a stand-in for what the rung leaves out: plates that bend), read by a chip with 2 uT rms noise
per axis (seeded). Its load test: --centred rows on the axis from 0 to the last lock, and
--per-press rows at each of --presses random points within 80 % of the top face
(x_mm, y_mm columns). `mst calibrate` (spring, L0) fits it; then readings at --presses other
random points are read three ways: the centred reading, `mst read --estimate-offset` with the
rung's own levers (lever factor 1), and with the calibrated one. Printed: the fitted lever
factor, and the force errors of the three readings (median, 90th percentile, max, on the
readings each one gives a force for).

Run:  .venv/bin/python benchmarks/offset_calibration.py [--true-lever-factor 0.8 --seed 5]   # ~1 min
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from mst_cli import api
from mst_cli.io.schema import load_design_document
from mst_cli.model.offcentre import pose_field_T, tilt_laws

DESIGN = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"
NOISE_T = 2e-6


def synthetic_rows(geo, layers, forces, presses, rng) -> list[tuple]:
    """(force, x, y, Bx, By, Bz in uT) of every force at every press, with the chip's noise."""
    rows = []
    for x, y in presses:
        B = pose_field_T(geo, layers, forces, (x, y)) + rng.normal(0.0, NOISE_T, (len(forces), 3))
        rows += [(f, x, y, *(b * 1e6)) for f, b in zip(forces, B)]
    return rows


def write_csv(path: Path, rows, with_offsets: bool) -> None:
    head = "force_N,x_mm,y_mm,Bx_uT,By_uT,Bz_uT" if with_offsets else "force_N,Bx_uT,By_uT,Bz_uT"
    lines = [head] + [",".join(f"{v:.9g}" for v in (r if with_offsets else (r[0], *r[3:]))) for r in rows]
    path.write_text("\n".join(lines) + "\n")


def errors(F_read: np.ndarray, F_true: np.ndarray) -> str:
    ok = np.isfinite(F_read) & (F_true > 0)
    e = np.abs(F_read[ok] / F_true[ok] - 1.0)
    return (
        f"median {100 * np.median(e):.1f} %, 90th pct {100 * np.percentile(e, 90):.1f} %, "
        f"max {100 * e.max():.1f} % ({ok.sum()} readings)"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--true-lever-factor", type=float, default=0.8)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--presses", type=int, default=5)
    ap.add_argument("--per-press", type=int, default=12)
    ap.add_argument("--centred", type=int, default=40)
    args = ap.parse_args()
    t0 = time.perf_counter()
    doc, _ = load_design_document(DESIGN)
    geo, mat = doc.geometry(), doc.material
    truth = tilt_laws(geo, mat, "continuum", args.true_lever_factor)
    rng = np.random.default_rng(args.seed)
    top = api.simulate(doc, mechanics="continuum").lock_forces_N[-1]
    half = 0.4 * np.array([geo.width_mm, geo.depth_mm])
    fit_presses = [tuple(rng.uniform(-half, half)) for _ in range(args.presses)]
    read_presses = [tuple(rng.uniform(-half, half)) for _ in range(args.presses)]
    F_press = np.linspace(0.05, 0.95, args.per_press) * top
    load_test = synthetic_rows(geo, truth, np.linspace(0.0, top, args.centred), [(0.0, 0.0)], rng)
    load_test += synthetic_rows(geo, truth, F_press, fit_presses, rng)
    readings = synthetic_rows(geo, truth, F_press, read_presses, rng)
    F_true = np.array([r[0] for r in readings])
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        write_csv(d / "loadtest.csv", load_test, True)
        write_csv(d / "readings.csv", readings, False)
        api.calibrate(DESIGN, d / "loadtest.csv", out=d / "cal")
        tilt = json.loads((d / "cal" / "calibration.json").read_text())["tilt"]
        calibrated = d / "cal" / "calibrated.yaml"
        tilted = api.read(calibrated, d / "readings.csv", estimate_offset=True)
        # the same calibration without its tilt: the rung's own levers
        rec = json.loads((d / "cal" / "calibration.json").read_text())
        rec["tilt"] = None
        (d / "cal" / "calibration.json").write_text(json.dumps(rec))
        untilted = api.read(calibrated, d / "readings.csv", estimate_offset=True)
    print(
        f"true lever factor {args.true_lever_factor}; fitted {tilt['lever_factor']:.4f} +- {tilt['std']:.2g} "
        f"from {tilt['rows']} rows at {len(tilt['presses_mm'])} presses (field residual "
        f"{tilt['rms_residual_uT']:.3g} uT RMS, {tilt['rms_residual_at_factor_1_uT']:.3g} at factor 1)"
    )
    print(f"readings at {args.presses} other presses, {len(readings)} readings:")
    print(f"  centred reading:                 {errors(tilted.force_centred_N, F_true)}")
    print(f"  offset estimate, levers as rung:  {errors(untilted.force_N, F_true)}")
    print(f"  offset estimate, calibrated tilt: {errors(tilted.force_N, F_true)}")
    ok = tilted.offset.flag == "ok"
    print(
        f"  identifiable: {ok.sum()} of {len(readings)} (calibrated), "
        f"{(untilted.offset.flag == 'ok').sum()} (rung's levers); {time.perf_counter() - t0:.0f} s"
    )


if __name__ == "__main__":
    main()
