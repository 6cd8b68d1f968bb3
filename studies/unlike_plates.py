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
"""

from __future__ import annotations

import itertools
import tempfile
from pathlib import Path

import yaml

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.mechanics import layer_laws
from studies.plate_walls import FORWARD, rung_rows

THETA_DEG = (13.0, 20.0, 28.0, 40.0, 57.0)
T_MM, H_MM, PLATE_MM = 0.4, 1.8, 1.6


def stack(folder: Path, theta_a: float, theta_b: float) -> Path:
    """The forward config with layers A, B, A (angles ``theta_a``, ``theta_b``)."""
    base = yaml.safe_load(FORWARD.read_text())
    a, b = ({"theta_deg": th, "t_mm": T_MM, "h_mm": H_MM} for th in (theta_a, theta_b))
    name = f"aba-{theta_a:g}-{theta_b:g}"
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump({**base, "name": name, "layers": [a, b, a], "housing": {"plate_mm": PLATE_MM}}))
    return path


def main() -> None:
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
