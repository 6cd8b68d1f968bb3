"""The continuum rung's force-displacement path before the lock, against mst 0.5's.

0.5's L2 (git commit f00ed9a) had contact of the inner wall face only and declared the lock by
a gap rule. 0.6 adds the outer faces against the plate and the pads, and locks at the
stiffness knee (docs/design.md section 4). Before any face touches, the two solve the same
equations; this script shows where contact starts and how far 0.6's F sits above 0.5's at
0.5's own samples up to 0.5's lock. It reads 0.5's module from git, so it runs in a clone.

Run:  .venv/bin/python studies/compare_prelock.py [--rev f00ed9a]
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics import continuum as L2

CELLS = [
    (14, 0.4, 1.87),
    (5, 0.4, 1.25),
    (25, 0.6, 2.0),
    (33, 1.0, 2.8),
    (45, 2.5, 6.5),
    (60, 0.6, 4.0),
    (70, 1.5, 6.0),
]
ROOT = Path(__file__).resolve().parent.parent


def old_module(rev: str):
    src = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{rev}:mst_cli/model/mechanics/continuum.py"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    path = Path(tempfile.mkdtemp()) / "continuum_old.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location("continuum_old", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["continuum_old"] = mod
    spec.loader.exec_module(mod)
    return mod


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rev", default="f00ed9a", help="the commit whose L2 to compare with (0.5)")
    args = ap.parse_args()
    old = old_module(args.rev)
    mat = Material()
    print(
        f"{'cell (theta, t, h)':>22} {'first contact d':>15} {'0.5 lock d':>10} {'max |dF| before contact':>24} "
        f"{'F 0.6 / 0.5 - 1 at 0.5 lock':>28}"
    )
    for cell_args in CELLS:
        cell = HexCell(*cell_args)
        ro = old.solve_continuum(cell, mat)
        prob = L2.ContactProblem(cell, mat, L2.MeshOptions(levels=0))
        u, active = np.zeros(prob.basis.N), None
        first, worst_free, last = None, 0.0, 0.0
        for d, F_old in zip(ro.displacement_mm[1:], ro.force_N[1:]):
            u, _, active, r = prob._newton(u, d, active, pads=True)
            F = prob.force(u, active, r)[0] * ro.mesh_scale
            if active.any() and first is None:
                first = d
            if first is None:
                worst_free = max(worst_free, abs(F / F_old - 1))
            last = F / F_old - 1
        first_s = f"{first:.3f}" if first is not None else "none"
        print(f"{str(cell_args):>22} {first_s:>15} {ro.d_contact_mm:10.3f} {worst_free:24.1e} {100 * last:+27.2f}%")


if __name__ == "__main__":
    main()
