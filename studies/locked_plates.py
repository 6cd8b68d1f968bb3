"""The plate over a locked layer, on the whole-part rung (issue 44, docs/design.md 4.7): what it
gives, and a closed form of it fitted to that. Prints a table; writes a CSV when asked.

    PYTHONPATH=. .venv/bin/python studies/locked_plates.py --out studies/data/locked_plates.csv
    PYTHONPATH=. .venv/bin/python studies/locked_plates.py --fit studies/data/locked_plates.csv

Each stack is studies/unlike_plates.py's: the forward config with layers A, B, A (t 0.4 mm,
h 1.8 mm, 1.6 mm plates), here for every A and B of 13, 20, 28, 40 and 57 degrees, A below B.
Regime 2 of the rung, layer A (the lowest) locked, its cavity filled; the rung's plate 1 alone
in TPU (plate 2, the cap and the base rigid: ``PartOptions.rigid_plates``) less every member
rigid is what that plate gives over the locked layer, B's root joint on it included. Two rung
solves a stack, about 10 s each (kept in mst's cache: a second run reads them back).

mst's closed form stops a plate's bending when the layer under it locks and keeps only the upper
layer's root joint on it (model.plate_joint). The candidate form here (:func:`over_locked_mm_per_N`,
not in mst's model on main: the branch plates-past-lock wires it in, docs/design.md 4.7) adds:

* the upper walls' root turning unbalanced: over a filled layer nothing meets its moment, so
  the joint times (1 + a);
* where B's feet stand beyond A's heads (c = head B - head A > 0), the plate and B's pad (p + t)
  hang off the filled block as a cantilever c long, its root turning against k E'D (p + t)^2:
  P c^3/(3 E'I) + P c/kGA + P c^2/(k E'D (p + t)^2), P = 1/2.

``--fit`` fits (a, k) to the rows, the error of each row being the log of the form (B's root
joint plus the candidate's term) over the rung, and prints the rows, the constants and the joint
alone's errors beside them (2 s).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import tempfile
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.beams import section_EI_kGA
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.plate_joint import root_joint_mm_per_N
from studies.unlike_plates import THETA_DEG, stack

COLUMNS = ("theta_a_deg", "theta_b_deg", "t_a_mm", "t_b_mm", "h_a_mm", "h_b_mm", "head_a_mm", "head_b_mm",
           "plate_mm", "depth_mm", "E_prime_MPa", "G_MPa", "rung_um_per_N")  # fmt: skip


def over_locked_mm_per_N(row: dict, constants: tuple[float, float]) -> float:
    """The candidate's term (module docstring) of one row, mm/N, beyond B's root joint."""
    a, k = constants
    theta_b, t_b, h_b = math.radians(row["theta_b_deg"]), row["t_b_mm"], row["h_b_mm"]
    p, D, E, G = row["plate_mm"], row["depth_mm"], row["E_prime_MPa"], row["G_MPa"]
    joint = float(root_joint_mm_per_N(theta_b, t_b, h_b, p, D, E))
    c = max(row["head_b_mm"] - row["head_a_mm"], 0.0)
    EI, kGA = section_EI_kGA(D, p + t_b, E, G)
    return a * joint + 0.5 * (c**3 / (3.0 * EI) + c / kGA + c * c / (k * E * D * (p + t_b) ** 2))


def rung_row(path: Path) -> dict:
    """One stack's row: its two lower layers, the scene, and the rung's plate over locked layer A."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    scene = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    _, head, _ = lp.layer_supports(scene, theta, t, h)
    locked = {"locked": (0,), "member_factor": wp.RIGID_FACTOR}
    rigid = wp.kept_press(g, m, wp.PartOptions(**locked)).drop_mm_per_N
    alone = wp.PartOptions(**locked, scaled=("base", "cap"), rigid_plates=(1,))
    rung = wp.kept_press(g, m, alone).drop_mm_per_N - rigid
    values = (math.degrees(theta[0]), math.degrees(theta[1]), t[0], t[1], h[0], h[1], head[0], head[1],
              scene.plate_mm, scene.depth_mm, scene.E_prime_MPa, scene.G_MPa, 1e3 * rung)  # fmt: skip
    return dict(zip(COLUMNS, (float(v) for v in values)))


def closed_form_um_per_N(row: dict, constants: tuple[float, float] | None) -> float:
    """B's root joint on the plate, plus the candidate's term with ``constants`` (None: the joint
    alone, mst's closed form)."""
    scene = (row["plate_mm"], row["depth_mm"], row["E_prime_MPa"])
    joint = float(root_joint_mm_per_N(math.radians(row["theta_b_deg"]), row["t_b_mm"], row["h_b_mm"], *scene))
    return 1e3 * (joint + (0.0 if constants is None else over_locked_mm_per_N(row, constants)))


def sweep(out: Path) -> None:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for theta_a, theta_b in itertools.product(THETA_DEG, THETA_DEG):
            rows.append(rung_row(stack(Path(tmp), theta_a, theta_b)))
            print(f"  A {theta_a:g}, B {theta_b:g}: rung {rows[-1]['rung_um_per_N']:.2f} um/N", flush=True)
    with out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {out}")


def fit(path: Path) -> None:
    with path.open() as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]

    def logs(q) -> list[float]:
        return [math.log(closed_form_um_per_N(r, tuple(q)) / r["rung_um_per_N"]) for r in rows]

    q = least_squares(logs, [0.5, 1.0], bounds=([-1.0, 1e-3], [10.0, 100.0])).x
    print("| θ_A, ° | θ_B, ° | rung, µm/N | joint alone | joint + the candidate (fitted) |")
    print("|---|---|---|---|---|")
    errors: dict[str, list[float]] = {"alone": [], "fitted": []}
    for r in rows:
        rung, alone, fitted = r["rung_um_per_N"], closed_form_um_per_N(r, None), closed_form_um_per_N(r, tuple(q))
        errors["alone"].append(100 * (alone / rung - 1))
        errors["fitted"].append(100 * (fitted / rung - 1))
        print(f"| {r['theta_a_deg']:.0f} | {r['theta_b_deg']:.0f} | {rung:.1f} | {alone:.1f} | {fitted:.1f} |")
    print(f"\nfitted a = {q[0]:.3f}, k = {q[1]:.3f}")
    for name, e in errors.items():
        rms = math.sqrt(sum(v * v for v in e) / len(e))
        print(f"{name}: worst {max(map(abs, e)):.1f} %, rms {rms:.1f} %")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, help="solve the sweep and write its rows here (CSV)")
    parser.add_argument("--fit", type=Path, help="fit the candidate's constants to these rows (CSV)")
    args = parser.parse_args()
    if args.out is None and args.fit is None:
        parser.error("give --out FILE (the sweep) or --fit FILE (the fit)")
    if args.out is not None:
        sweep(args.out)
    if args.fit is not None:
        fit(args.fit)


if __name__ == "__main__":
    main()
