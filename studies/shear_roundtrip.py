"""Reading shear (issue 39, item 4): round trips of `--estimate shear` (one chip: Fz, Fx, Fy of a
centred press) and of the two-chip estimate of all five (Fz, Fx, Fy, x, y), against the
Cramer-Rao bound.

Synthetic readings of the bundled sensor as printed (configs/mohammadi2021-forward.yaml): the
truth is the general-load model (mst_cli.model.general_load) on the *continuum* rung (L2 layer
laws for the tilts, L2 lateral tangents for the slides); the readers run the same model on the
spring rung (L0, what `mst read` would use by default) and on L2 (the reader's model exact: what
the noise alone leaves). Presses (seeded): normal force uniform over 5 to 100 % of the range
(L2's last lock), tangential force of magnitude up to 0.3 of it in a uniform direction; one chip:
at the axis; two chips: uniform over the middle 60 % of the face. Chip noise 0.5 and 2 uT per
axis (seeded Gaussian). Two-chip layouts: the bound of a few candidates over the middle 60 %
is printed first, the round trip uses --layout (default: the second chip at (10, 6) mm).

Printed: medians of the normal force's relative error, the tangential force's (vector error over
|F_t|, presses with |F_t| >= 0.2 N), and the position's (mm), each beside the median of the
bound at the truth (L2) and the efficiency sum(sigma_CRB^2) / sum(error^2) (1: an efficient
unbiased estimate; a model error or a bias pulls it below 1).

Run:  .venv/bin/python studies/shear_roundtrip.py [--presses 60 --seed 39]   # ~5 min on 2 cores
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from mst_cli.estimation.shear_reading import ShearReader
from mst_cli.model.general_load import field_T, loaded_stack
from mst_cli.model.load_bound import ALL, CENTRED, crb_sigma, field_jacobian, layout_bound
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import load_design_document

DESIGN = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"
NOISES_uT = (0.5, 2.0)
SHEAR_MAX = 0.3
FT_MIN_N = 0.2
LAYOUTS = {
    "(0,0)+(6,0)": [(0.0, 0.0), (6.0, 0.0)],
    "(0,0)+(6,6)": [(0.0, 0.0), (6.0, 6.0)],
    "(0,0)+(10,6)": [(0.0, 0.0), (10.0, 6.0)],
    "(-10,0)+(0,8)": [(-10.0, 0.0), (0.0, 8.0)],
    "(-6,0)+(6,0)": [(-6.0, 0.0), (6.0, 0.0)],
}


def presses(rng, n: int, range_N: float, half_mm: tuple[float, float] | None) -> np.ndarray:
    """(n, 5) loads: Fz, Fx, Fy, x, y (x, y = 0 without ``half_mm``)."""
    Fz = rng.uniform(0.05, 1.0, n) * range_N
    ratio = SHEAR_MAX * np.sqrt(rng.uniform(0.0, 1.0, n))  # uniform over the disc of the cone
    ang = rng.uniform(0.0, 2 * np.pi, n)
    xy = np.zeros((n, 2)) if half_mm is None else rng.uniform(-1.0, 1.0, (n, 2)) * np.array(half_mm)
    return np.column_stack([Fz, ratio * Fz * np.cos(ang), ratio * Fz * np.sin(ang), xy])


def truth_fields(stack, loads: np.ndarray, chips) -> tuple[np.ndarray, np.ndarray]:
    """(the clean fields (n, 3k), the bound at 1 T per unknown (n, p)) on the truth's model."""
    free = CENTRED if len(chips) == 1 else ALL
    B = np.array([field_T(stack, t[0], (t[1], t[2]), (t[3], t[4]), chips).ravel() for t in loads])
    crb = np.array([crb_sigma(field_jacobian(stack, t, chips, free), 1.0) for t in loads])
    return B, crb


def scores(loads, est, crb, noise_T, chips) -> dict:
    """The medians of the errors and of the bound, and the efficiencies."""
    e = np.stack([est.estimate[k] for k in ("force_N", "shear_x_N", "shear_y_N", "x_mm", "y_mm")], -1) - loads
    s = crb * noise_T
    Fz = loads[:, 0]
    Ft = np.hypot(loads[:, 1], loads[:, 2])
    big = Ft >= FT_MIN_N
    eft = np.hypot(e[:, 1], e[:, 2])
    out = {
        "Fz_err": np.median(np.abs(e[:, 0]) / Fz),
        "Fz_crb": np.median(s[:, 0] / Fz),
        "Fz_eff": np.sum(s[:, 0] ** 2) / np.sum(e[:, 0] ** 2),
        "Ft_err": np.median(eft[big] / Ft[big]),
        "Ft_crb": np.median(np.hypot(s[big, 1], s[big, 2]) / Ft[big]),
        "Ft_eff": np.sum(s[:, 1] ** 2 + s[:, 2] ** 2) / np.sum(eft**2),
        "flagged": int(np.sum(est.flag != "ok")),
    }
    if len(chips) > 1:
        ep = np.hypot(e[:, 3], e[:, 4])
        out.update(
            p_err=np.median(ep),
            p_crb=np.median(np.hypot(s[:, 3], s[:, 4])),
            p_eff=np.sum(s[:, 3] ** 2 + s[:, 4] ** 2) / np.sum(ep**2),
        )
    return out


def print_layouts(truth, range_N: float) -> None:
    """The median 1-sigma bounds of every candidate layout over the middle 60 % of the face."""
    F = np.array([0.2, 0.5, 0.8]) * range_N
    print("\nTwo-chip layouts, median 1-sigma CRB over the middle 60 % (3 x 3 presses, 3 forces, shear 0.2, 0.1):")
    print("| chips (mm) | noise uT | Fz N | Fx N | Fy N | x mm | y mm |")
    print("|---|---|---|---|---|---|---|")
    for name, chips in LAYOUTS.items():
        b = layout_bound(truth, chips, F, (0.2, 0.1), grid=(3, 3))
        for row in b.summary(NOISES_uT)["noise"]:
            cells = [row[f"{k}_crb_median"] for k in ("force_N", "shear_x_N", "shear_y_N", "x_mm", "y_mm")]
            print(f"| {name} | {row['noise_uT']:g} | " + " | ".join(f"{c:.3g}" for c in cells) + " |")


def roundtrip(readers, truth, loads, chips, rng) -> list[tuple[str, float, dict]]:
    """Every reader at every noise on the same presses (the same noise draws per noise)."""
    B, crb = truth_fields(truth, loads, chips)
    out = []
    for noise in NOISES_uT:
        noisy = B + rng.normal(0.0, noise * 1e-6, B.shape)
        for name, stack in readers.items():
            est = ShearReader(stack, chips).read(noisy, noise * 1e-6)
            out.append((name, noise, scores(loads, est, crb, noise * 1e-6, chips)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--presses", type=int, default=60)
    ap.add_argument("--seed", type=int, default=39)
    ap.add_argument("--layout", choices=tuple(LAYOUTS), default="(0,0)+(10,6)")
    ap.add_argument("--no-layouts", action="store_true", help="skip the layouts' bound table")
    args = ap.parse_args()
    doc, _ = load_design_document(DESIGN)
    printed = as_printed(doc)
    geo, mat = printed.geometry(), printed.material
    t0 = time.perf_counter()
    truth = loaded_stack(geo, mat, "continuum")
    readers = {"L0 (spring)": loaded_stack(geo, mat, "spring"), "L2 (continuum)": truth}
    range_N = max(t.lock_force_N for t in truth.tilt)
    rng = np.random.default_rng(args.seed)
    print(f"{DESIGN.name} as printed, range {range_N:.2f} N (L2), face {geo.width_mm:g} x {geo.depth_mm:g} mm")
    if not args.no_layouts:
        print_layouts(truth, range_N)
    one = roundtrip(readers, truth, presses(rng, args.presses, range_N, None), [geo.chip_offset_mm], rng)
    print(f"\nOne chip at {geo.chip_offset_mm}, --estimate shear, {args.presses} centred presses:")
    print("| reader | noise uT | Fz error (CRB) | eff | F_t error (CRB) | eff | flagged |")
    print("|---|---|---|---|---|---|---|")
    for name, noise, s in one:
        print(
            f"| {name} | {noise:g} | {100 * s['Fz_err']:.2f} % ({100 * s['Fz_crb']:.2f} %) | {s['Fz_eff']:.2f} "
            f"| {100 * s['Ft_err']:.1f} % ({100 * s['Ft_crb']:.1f} %) | {s['Ft_eff']:.2f} | {s['flagged']} |"
        )
    half = (0.3 * geo.width_mm, 0.3 * geo.depth_mm)
    chips = LAYOUTS[args.layout]
    two = roundtrip(readers, truth, presses(rng, args.presses, range_N, half), chips, rng)
    print(f"\nTwo chips {args.layout} mm, all five, {args.presses} presses over the middle 60 %:")
    print("| reader | noise uT | Fz error (CRB) | eff | position error mm (CRB) | eff | F_t error (CRB) | flagged |")
    print("|---|---|---|---|---|---|---|---|")
    for name, noise, s in two:
        print(
            f"| {name} | {noise:g} | {100 * s['Fz_err']:.2f} % ({100 * s['Fz_crb']:.2f} %) | {s['Fz_eff']:.2f} "
            f"| {s['p_err']:.3f} ({s['p_crb']:.3f}) | {s['p_eff']:.2f} "
            f"| {100 * s['Ft_err']:.1f} % ({100 * s['Ft_crb']:.1f} %) | {s['flagged']} |"
        )
    print(f"\n{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
