"""Lateral stiffness of the layers (issue 39, part 1; docs/design.md section 4.4).

Prints three tables:

1. small load, on the five check cells (tools/lateral_check.py): k_x of L2 (continuum_lateral,
   the quarter odd about the mid-plane) against the independent whole-profile plane-strain FE,
   their difference, k_x / k_z (L2's normal small-load k); k_y of an infinitely deep web (L2's
   antiplane solve against the independent one), the 3D check's k_y of the web D deep (stored by
   tools/fit_lateral.py; ``--3d`` recomputes it, ~4 min) and L0's (lateral.py) k_x and k_y;
2. the bundled sensor's three layers, the same;
3. through the lock, per bundled layer: L2's normal tangent k_z and the lateral tangents with
   frictionless and with stuck contacts (k_y of an infinitely deep web), at fractions of the lock.

Run:  PYTHONPATH=. .venv/bin/python studies/lateral_stiffness.py [--3d]     # ~30 s
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum_lateral as CL
from mst_cli.model.mechanics import lateral
from mst_cli.model.mechanics.continuum import linear_stiffness_N_per_mm

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
import lateral_check as LC

BUNDLED = {"top": HexCell(25, 0.6, 2.0), "middle": HexCell(33, 1.0, 2.8), "bottom": HexCell(37, 1.4, 3.5)}


def _stored_3d() -> dict[str, float]:
    rows = json.loads(lateral.DATA.read_text())["depth_end"].get("cells", [])
    return {r["cell"]: r["k_y_3d"] for r in rows}


def small_load_table(cells: dict[str, HexCell], mat: Material, k_y_3d: dict[str, float]) -> None:
    print(
        f"{'cell':>8} {'theta':>5} {'t':>5} {'h':>5} | {'kx L2':>7} {'kx chk':>7} {'diff':>6} {'kx/kz':>6} |"
        f" {'ky L2':>7} {'ky chk':>7} {'diff':>6} {'ky 3D':>7} {'ky/kz':>6} | {'kx L0':>7} {'ky L0':>7}"
    )
    for name, c in cells.items():
        kz = linear_stiffness_N_per_mm(c, mat)
        kx, kx_c = CL.lateral_stiffness_x_N_per_mm(c, mat), LC.check_k_x_N_per_mm(c, mat)
        ky, ky_c = CL.lateral_stiffness_y_N_per_mm(c, mat), LC.check_k_y_inf_N_per_mm(c, mat)
        k3 = k_y_3d.get(name, float("nan"))
        l0x, l0y = lateral.lateral_stiffness_N_per_mm(c, mat)
        print(
            f"{name:>8} {c.theta_deg:5g} {c.t_mm:5g} {c.h_mm:5g} | {kx:7.2f} {kx_c:7.2f} {100 * (kx / kx_c - 1):+5.2f}%"
            f" {kx / kz:6.3f} | {ky:7.2f} {ky_c:7.2f} {100 * (ky / ky_c - 1):+5.2f}% {k3:7.2f} {k3 / kz:6.3f} |"
            f" {l0x:7.2f} {l0y:7.2f}"
        )


def path_table(cells: dict[str, HexCell], mat: Material) -> None:
    for name, c in cells.items():
        p = CL.lateral_path(c, mat)
        print(f"\n{name} {c}: L2 lock on the path mesh d = {p.d_lock_mm:.3f} mm (N/mm; k_y infinitely deep)")
        print(f"{'d/d_lock':>8} {'k_z':>8} {'kx free':>8} {'kx stuck':>8} {'ky free':>8} {'ky stuck':>8}")
        for i, d in enumerate(p.d_mm):
            print(
                f"{d / p.d_lock_mm:8.2f} {p.k_z_N_per_mm[i]:8.2f} {p.k_x_free_N_per_mm[i]:8.2f}"
                f" {p.k_x_stuck_N_per_mm[i]:8.2f} {p.k_y_free_N_per_mm[i]:8.2f} {p.k_y_stuck_N_per_mm[i]:8.2f}"
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--3d", dest="three_d", action="store_true", help="recompute the 3D check of k_y (~4 min)")
    args = ap.parse_args()
    mat = Material()
    k3 = _stored_3d()
    if args.three_d:
        k3 = {n: LC.check_k_y_3d_N_per_mm(c, mat) for n, c in LC.CHECK_CELLS.items()}
    print("Small load, the five check cells (N/mm; k_y L2/check infinitely deep, 3D the web D = 20 mm deep)")
    small_load_table(LC.CHECK_CELLS, mat, k3)
    print("\nSmall load, the bundled sensor's layers")
    small_load_table(BUNDLED, mat, {})
    path_table(BUNDLED, mat)


if __name__ == "__main__":
    main()
