"""The README's loop from a first print to a second, measured (issue 21).

A synthetic printer the design never sees prints every wall 0.06 mm thicker and the TPU 15 %
softer. Print 1 is `mst design` of the reference spec; its load test (60 samples, 2 uT RMS
noise, rounded to the chip's LSB) goes through `mst calibrate`, then `mst design
--calibration`; print 2 is the written design printed by the same synthetic printer. The print
is made by editing design.yaml by hand and simulating it (tests/test_printer_loop.py runs the
same loop with this module's printer and asserts it).

Run:  .venv/bin/python studies/printer_loop.py [--seed 11]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml

from mst_cli.model import chip as mlx
from mst_cli.model.response import simulate
from mst_cli.sensor.document import load_document, parse_document

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "configs" / "mohammadi2021.yaml"
WALL_MM, MODULUS, NOISE_uT = 0.06, 0.85, 2.0


def mst(*args):
    exe = Path(sys.executable).with_name("mst")
    done = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(done.stdout + done.stderr)
    return done.stdout


def print_of(design_yaml, wall_mm: float = WALL_MM, modulus: float = MODULUS):
    """What the synthetic printer makes of a written design.yaml: its drawn walls + wall_mm, its
    material's modulus x modulus, the real magnet (the grade's) in the drawn housing; edited by
    hand and simulated, not through the printer code under test."""
    raw = yaml.safe_load(Path(design_yaml).read_text())
    raw["material"]["youngs_modulus_MPa"] *= modulus
    for layer in raw["layers"]:
        layer["t_mm"] += wall_mm
    raw["magnet"]["remanence_T"] = None
    doc = parse_document(raw)
    return simulate(doc.geometry(), doc.material, noise_uT_rms=NOISE_uT)


def write_load_test(resp, path, rng, samples: int = 60) -> None:
    """A load test of a print: the model's field + chip noise, rounded to the chip's LSB."""
    F = np.sort(rng.uniform(0.0, resp.max_force_N, samples))
    B = np.stack([np.interp(F, resp.force_N, resp.B_T[:, i]) for i in range(3)], -1)
    B = B + rng.normal(0.0, NOISE_uT * 1e-6, B.shape)
    s = resp.chip_setting
    lsb = (s.xy_uT_per_lsb, s.xy_uT_per_lsb, s.z_uT_per_lsb)
    rows = ["force_N,Bx_uT,By_uT,Bz_uT"]
    for f, b in zip(F, B):
        rows.append(f"{f:.4f}," + ",".join(f"{mlx.quantise_lsb(b[i], lsb[i]) * lsb[i]:.4f}" for i in range(3)))
    Path(path).write_text("\n".join(rows) + "\n")


def misses(resp, doc):
    S = np.array([r.sensitivity_secant_per_N for r in resp.regimes])
    R = np.zeros(len(S))
    for r in resp.regimes:
        R[r.layer - 1] = r.force_to_N
    S_t = np.array([la.target_sensitivity_per_N for la in doc.layers])
    R_t = np.array([la.target_range_N for la in doc.layers])
    return 100 * (S / S_t - 1), 100 * (R / R_t - 1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=11)
    args = ap.parse_args()
    doc = load_document(SPEC)
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        mst("design", SPEC, "--out", d / "print1", "--no-plot", "-q")
        p1 = print_of(d / "print1" / "design.yaml")
        write_load_test(p1, d / "loadtest.csv", np.random.default_rng(args.seed))
        mst("calibrate", d / "print1" / "design.yaml", d / "loadtest.csv", "--out", d / "cal", "--no-plot")
        cal = json.loads((d / "cal" / "calibration.json").read_text())
        mst("design", SPEC, "--calibration", d / "cal" / "calibration.json", "--out", d / "print2", "--no-plot", "-q")
        p2 = print_of(d / "print2" / "design.yaml")
        for name, resp in (("print 1", p1), ("print 2", p2)):
            dS, dR = misses(resp, doc)
            print(
                f"{name}: S_i {', '.join(f'{x:+.2f}' for x in dS)} %, R_i {', '.join(f'{x:+.2f}' for x in dR)} %; "
                f"worst {max(np.abs(dS).max(), np.abs(dR).max()):.2f} %"
            )
        for name, par in cal["parameters"].items():
            state = "taken" if par["identifiable"] else "held"
            print(f"calibration: {name} {par['value']:+.4f} +- {par['std']:.4f} ({state})")


if __name__ == "__main__":
    main()
