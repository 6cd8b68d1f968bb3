"""What the closed form's plates still miss between unlike layers (issue 44, docs/design.md 4.7):
the whole-part rung on stacks A, B, A, regime 1. Prints a table, changes nothing.

    PYTHONPATH=. .venv/bin/python studies/unlike_plates.py

The walls' joints with the plates (mst_cli.model.plate_joint) are fitted on stacks of like layers
(studies/root_turn_sweep.py). Between unlike layers the walls above and below a plate stand at
different x and put unlike root moments into it, so the plate also bends and turns at the heads.
Each stack here is the forward config with three layers A, B, A (t 0.4 mm, h 1.8 mm, the designed
specs' kind of layer) and 1.6 mm plates, so both plates stand between A and B. Per pair: the
rung's plates (their extra drop, plates in TPU less every member rigid: studies/plate_walls.py's
rung_rows), the closed form's (the plates' beams and the layers' joints with them), and what is
missing, also as a share of the layers' and plates' compliance. Two rung solves a stack, about
10 s each.

``--per-plate`` (two more solves a stack, 10 min in all): each plate alone in TPU, the other held
rigid (``PartOptions.rigid_plates``), against the closed form's beam and joints of that plate.
Plate 1 stands on A's heads under B's feet, plate 2 on B's heads under A's feet: one is the
other's mirror image about B's mid-plane, so the rung gives both the same. The closed form's beam
does not: where the feet above stand outside the heads below (an overhang, e = head below - head
above < 0) it bends only the overhang, clamped at the head; where they stand inside, the span
between the heads bends too. The last column is the free body both cases share, a beam loaded by
P = 1/2 at each foot and held by P at each head: the span between the nearer pair carries the
moment P |e| and the rest bends as a cantilever, P (e^2 x_near + |e|^3 / 3) / E'I (x_near the
nearer pair's x, E'I the plate with both pads), without the walls' restraint. The last two are
the closed form's error and what it was with the overhang's root held (its turn against pi/8 E'D
d^2 taken out of the beam; docs/design.md 4.7, "The overhang's root"). ``--plate-mm`` and
``--pairs 13,40 20,57 ...`` choose the stacks.
"""

from __future__ import annotations

import argparse
import itertools
import tempfile
from pathlib import Path

import numpy as np
import yaml

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.beams import END_BUILT_IN, section_EI_kGA
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.plate_joint import root_joint_mm_per_N
from studies.plate_walls import FORWARD, rung_rows

THETA_DEG = (13.0, 20.0, 28.0, 40.0, 57.0)
T_MM, H_MM, PLATE_MM = 0.4, 1.8, 1.6


def stack(
    folder: Path, theta_a: float, theta_b: float, t_b_mm: float = T_MM, plate_mm: float = PLATE_MM, h_b_mm: float = H_MM
) -> Path:
    """The forward config with layers A, B, A (angles ``theta_a``, ``theta_b``; B's walls
    ``t_b_mm`` thick and ``h_b_mm`` high, A's T_MM and H_MM) and plates ``plate_mm`` thick."""
    base = yaml.safe_load(FORWARD.read_text())
    a, b = ({"theta_deg": th, "t_mm": t, "h_mm": h} for th, t, h in ((theta_a, T_MM, H_MM), (theta_b, t_b_mm, h_b_mm)))
    name = f"aba-{theta_a:g}-{theta_b:g}-{t_b_mm:g}-{plate_mm:g}" + ("" if h_b_mm == H_MM else f"-{h_b_mm:g}")
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump({**base, "name": name, "layers": [a, b, a], "housing": {"plate_mm": plate_mm}}))
    return path


def plate_rows(path: Path) -> list[dict]:
    """Per plate of the stack at ``path``, regime 1: the rung's extra drop with that plate alone in
    TPU (the other plates, the cap and the base rigid), the closed form's beam and joints of it,
    the offset e and the free body's beam (module docstring), mm/N and mm."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    rigid = wp.press(g, m, wp.PartOptions(member_factor=wp.RIGID_FACTOR)).drop_mm_per_N
    scene = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    _, head, _, _ = lp.layer_supports(scene, theta, t, h)
    joint = root_joint_mm_per_N(theta, t, h, scene.plate_mm, scene.depth_mm, scene.E_prime_MPa)
    beams = lp.members(g, m).plates_mm_per_N
    rows = []
    for j in range(len(g.layers) - 1):
        others = tuple(k for k in range(len(g.layers) - 1) if k != j)
        opts = wp.PartOptions(member_factor=wp.RIGID_FACTOR, scaled=("base", "cap"), rigid_plates=others)
        EI, _ = section_EI_kGA(scene.depth_mm, t[j] + scene.plate_mm + t[j + 1], scene.E_prime_MPa, scene.G_MPa)
        e, near = head[j] - head[j + 1], min(head[j], head[j + 1])
        free = 0.5 * (e * e * near + abs(e) ** 3 / 3.0) / EI
        d = (t[j] if head[j] > head[j + 1] else t[j + 1]) + scene.plate_mm  # the overhang's thickness
        root = 0.5 * e * e / (END_BUILT_IN * scene.E_prime_MPa * scene.depth_mm * d * d)  # in the beam
        rung = wp.press(g, m, opts).drop_mm_per_N - rigid
        rows.append(
            {"rung": rung, "beam": beams[j], "joints": joint[j] + joint[j + 1], "e": e, "free": free, "root": root}
        )
    return rows


def per_plate(plate_mm: float = PLATE_MM, pairs=None) -> None:
    """The ``--per-plate`` table for stacks with ``plate_mm`` plates, every pair of THETA_DEG or
    ``pairs`` ((theta_A, theta_B), ...)."""
    print(
        "| θ_A, ° | θ_B, ° | plate | e, mm | rung, µm/N | closed form: beam + joints | free-body beam | "
        "closed / rung - 1 | its root held |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for theta_a, theta_b in pairs or itertools.combinations(THETA_DEG, 2):
            for j, row in enumerate(plate_rows(stack(Path(tmp), theta_a, theta_b, plate_mm=plate_mm))):
                um = {k: 1e3 * row[k] for k in ("rung", "beam", "joints", "free")}
                closed = row["beam"] + row["joints"]
                print(
                    f"| {theta_a:g} | {theta_b:g} | {j + 1} | {row['e']:+.2f} | {um['rung']:.1f} | "
                    f"{um['beam']:.1f} + {um['joints']:.1f} | {um['free']:.1f} | {closed / row['rung'] - 1:+.1%} | "
                    f"{(closed - row['root']) / row['rung'] - 1:+.1%} |",
                    flush=True,
                )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--per-plate", action="store_true", help="each plate alone in TPU (module docstring)")
    parser.add_argument("--plate-mm", type=float, default=PLATE_MM, help="with --per-plate: the plates' thickness")
    parser.add_argument("--pairs", nargs="*", default=None, help="with --per-plate: theta_A,theta_B pairs [all]")
    args = parser.parse_args()
    if args.per_plate:
        pairs = [tuple(float(x) for x in p.split(",")) for p in args.pairs] if args.pairs else None
        per_plate(args.plate_mm, pairs)
        return
    print("| θ_A, ° | θ_B, ° | rung, µm/N | closed form | missing | / layers and plates |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for theta_a, theta_b in itertools.combinations_with_replacement(THETA_DEG, 2):
            path = stack(Path(tmp), theta_a, theta_b)
            (row,) = rung_rows(path, regimes=1)
            doc, _ = mst.designed(path)
            g, m = doc.geometry(), doc.material
            closed = row["closed"] + sum(lp.members(g, m).joints_mm_per_N)
            layers = sum(1.0 / law.k_N_per_mm for law in layer_laws(g.layers, m, "spring"))
            missing = row["rung"] - closed
            cells = " | ".join(f"{1e3 * v:.2f}" for v in (row["rung"], closed, missing))
            share = 100 * missing / (layers + row["rung"])
            print(f"| {theta_a:g} | {theta_b:g} | {cells} | {share:+.1f} % |", flush=True)


if __name__ == "__main__":
    main()
