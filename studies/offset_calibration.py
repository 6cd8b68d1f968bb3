"""Calibrate the tilt from presses at known offsets, then read presses elsewhere (issue 24).

A synthetic printed sensor, the bundled design (configs/mohammadi2021-forward.yaml) whose layers
follow L2 (the continuum rung) and whose levers are --true-lever-factor times the tilt rung's
(a stand-in for what the rung leaves out: plates that bend), read by a chip with --noise-uT rms
noise per axis (seeded; 2 uT is one fast sample, 0.5 uT the mean of 16). Its load test:
--centred rows on the axis from 0 to the last lock, and --per-press rows at each of --presses
random points within 80 % of the top face (x_mm, y_mm columns). `mst calibrate` fits it with
each of --readers (spring: L0, the default reader; continuum: L2, the truth's own rung, so only
the lever factor and the noise stand between them); then readings at --presses other random
points are read three ways: the centred reading, `mst read --estimate-offset` with the rung's
own levers (lever factor 1), and with the calibrated one. Printed, one row per reader and
noise: the fitted lever factor, the force errors of the three readings (median / max, on the
readings each one gives a force for; a flagged reading keeps its centred force), how many
calibrated readings are within 5 %, how many the reader calls identifiable, and how many of
those are more than 5 % off (a wrong force the flag does not warn of); with
--worst N, the N calibrated readings furthest off, where they were pressed and where the reader
put the press.

Run:  .venv/bin/python studies/offset_calibration.py [--noise-uT 2,0.5 --readers spring,continuum] [--worst 5]
      (about 4 min)
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from mst_cli import api
from mst_cli.model.general_load import pose_field_T
from mst_cli.model.stack_pose import tilt_laws
from mst_cli.sensor.document import load_design_document

DESIGN = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"
NOISE_T = 2e-6


def synthetic_rows(geo, layers, forces, presses, rng, noise_T: float = NOISE_T) -> list[tuple]:
    """(force, x, y, Bx, By, Bz in uT) of every force at every press, with the chip's noise."""
    rows = []
    for x, y in presses:
        B = pose_field_T(geo, layers, forces, (x, y)) + rng.normal(0.0, noise_T, (len(forces), 3))
        rows += [(f, x, y, *(b * 1e6)) for f, b in zip(forces, B)]
    return rows


def write_csv(path: Path, rows, with_offsets: bool) -> None:
    head = "force_N,x_mm,y_mm,Bx_uT,By_uT,Bz_uT" if with_offsets else "force_N,Bx_uT,By_uT,Bz_uT"
    lines = [head] + [",".join(f"{v:.9g}" for v in (r if with_offsets else (r[0], *r[3:]))) for r in rows]
    path.write_text("\n".join(lines) + "\n")


def errors(F_read: np.ndarray, F_true: np.ndarray) -> np.ndarray:
    """|read / true - 1| of every reading that has a force."""
    ok = np.isfinite(F_read) & (F_true > 0)
    return np.abs(F_read[ok] / F_true[ok] - 1.0)


def stats(e: np.ndarray) -> str:
    return f"{100 * np.median(e):.1f} / {100 * e.max():.1f} %"


def one_case(args, reader: str, noise_uT: float) -> str:
    """Calibrate and read one synthetic print with the given reader rung and chip noise: a table row."""
    doc, _ = load_design_document(DESIGN)
    geo, mat = doc.geometry(), doc.material
    truth = tilt_laws(geo, mat, "continuum", args.true_lever_factor)
    rng = np.random.default_rng(args.seed)  # the same presses in every case
    top = api.simulate(doc, mechanics="continuum").lock_forces_N[-1]
    half = 0.4 * np.array([geo.width_mm, geo.depth_mm])
    fit_presses = [tuple(rng.uniform(-half, half)) for _ in range(args.presses)]
    read_presses = [tuple(rng.uniform(-half, half)) for _ in range(args.presses)]
    F_press = np.linspace(0.05, 0.95, args.per_press) * top
    noise_T = 1e-6 * noise_uT
    load_test = synthetic_rows(geo, truth, np.linspace(0.0, top, args.centred), [(0.0, 0.0)], rng, noise_T)
    load_test += synthetic_rows(geo, truth, F_press, fit_presses, rng, noise_T)
    readings = synthetic_rows(geo, truth, F_press, read_presses, rng, noise_T)
    F_true = np.array([r[0] for r in readings])
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        # the design as the reader knows it: its chip's noise is the synthetic chip's
        design = d / "design.yaml"
        design.write_text(DESIGN.read_text().replace("noise_uT_rms: 2.0", f"noise_uT_rms: {noise_uT}"))
        write_csv(d / "loadtest.csv", load_test, True)
        write_csv(d / "readings.csv", readings, False)
        api.calibrate(design, d / "loadtest.csv", out=d / "cal", mechanics=reader)
        rec = json.loads((d / "cal" / "calibration.json").read_text())
        calibrated = d / "cal" / "calibrated.yaml"
        tilted = api.read(calibrated, d / "readings.csv", estimate_offset=True, mechanics=reader)
        tilt, rec["tilt"] = rec["tilt"], None  # the same calibration without its tilt: the rung's own levers
        (d / "cal" / "calibration.json").write_text(json.dumps(rec))
        untilted = api.read(calibrated, d / "readings.csv", estimate_offset=True, mechanics=reader)
    e_cal = errors(tilted.force_N, F_true)
    row = (
        f"| {reader} | {noise_uT:g} | {tilt['lever_factor']:.4f} +- {tilt['std']:.1g} | {tilt['rms_residual_uT']:.3g} "
        f"| {stats(errors(tilted.force_centred_N, F_true))} | {stats(errors(untilted.force_N, F_true))} "
        f"| {stats(e_cal)} | {100 * np.percentile(e_cal, 90):.1f} % | {int(np.sum(e_cal <= 0.05))} of {e_cal.size} "
        f"| {int(np.sum(tilted.offset.flag == 'ok'))} | {silent_misses(tilted, F_true)} |"
    )
    return row + worst_readings(readings, tilted, args.worst)


def silent_misses(read, F_true: np.ndarray) -> int:
    """Readings whose offset the reader calls identifiable ("ok") but whose force is > 5 % off."""
    ok = read.offset.flag == "ok"
    return int(np.sum(ok & (np.abs(np.asarray(read.force_N, float) / F_true - 1.0) > 0.05)))


def worst_readings(readings, read, n: int) -> str:
    """The ``n`` calibrated readings furthest from the truth: where pressed, what was read."""
    F, F_true = np.asarray(read.force_N, float), np.array([r[0] for r in readings])
    err = F / F_true - 1.0
    lines = [
        f"\n  - {F_true[i]:.2f} N pressed at ({readings[i][1]:.1f}, {readings[i][2]:.1f}) mm: read {F[i]:.2f} N "
        f"({100 * err[i]:+.1f} %), press estimated at ({read.offset.x_mm[i]:.2f}, {read.offset.y_mm[i]:.2f}) mm, "
        f"flag {read.offset.flag[i]}"
        for i in np.argsort(-np.nan_to_num(np.abs(err), nan=np.inf))[:n]
    ]
    return "".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--true-lever-factor", type=float, default=0.8)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--presses", type=int, default=5)
    ap.add_argument("--per-press", type=int, default=12)
    ap.add_argument("--centred", type=int, default=40)
    ap.add_argument("--readers", default="spring,continuum", help="rungs mst calibrate fits and mst read reads with")
    ap.add_argument("--noise-uT", default="2,0.5", help="chip noise per axis (uT rms), comma-separated")
    ap.add_argument("--worst", type=int, default=0, help="list the N worst calibrated readings under each row")
    args = ap.parse_args()
    t0 = time.perf_counter()
    print(
        f"true lever factor {args.true_lever_factor}; {args.presses} presses of {args.per_press} rows calibrate, "
        f"{args.presses} others are read ({args.presses * args.per_press} readings); force errors median / max"
    )
    print(
        "| reader | noise [uT] | fitted lever factor | field residual [uT RMS] | centred reading "
        "| offset estimate, rung's levers | calibrated tilt | 90th pct | within 5 % | identifiable "
        "| identifiable, > 5 % off |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for reader in args.readers.split(","):
        for noise in (float(n) for n in args.noise_uT.split(",")):
            print(one_case(args, reader, noise), flush=True)
    print(f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
