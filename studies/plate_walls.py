"""Why the plates between layers add several times their closed form (issue 44, docs/design.md
4.7): two mechanisms of the walls' roots, put against the whole-part rung. Prints a table,
changes nothing.

    PYTHONPATH=. .venv/bin/python studies/plate_walls.py [--configs a.yaml ...]
    PYTHONPATH=. .venv/bin/python studies/plate_walls.py --plate-sweep

The closed form of :mod:`mst_cli.model.load_path` bends a plate only by the offset of the wall
feet above it from the wall heads below it, and on the bundled designs the two nearly coincide.
The rung (:mod:`mst_cli.model.mechanics.whole_part`, plates in TPU, the cap and the base rigid,
the layers locked before the regime closed) gives 7-8 times more. Two mechanisms of the walls'
roots, neither in the closed form, are tried here, each in closed form:

* **the roots turn locally.** A wall's root on a TPU plate is not clamped: it turns into the
  plate like a beam built into an elastic body, M / theta = c E' D t^2 (t the wall's thickness, D
  the depth; a constant c of order one, the form of a built-in end's rotation on a body of the
  same modulus). The wall is then clamped-guided with a rotational spring at its root: its tip's
  transverse deflection per unit transverse force grows by L/k m + (m L^2/2 - L^3/6)/EI - L^3/(12 EI)
  with m = (L^2 / 2EI) / (1/k + L/EI), times cos^2 theta for the vertical. Every open wall with a
  root on a plate counts, half of it per layer (two chevrons of two walls);
* **the plate turns at the heads.** The walls' root moments, P L cos(theta) / 2 each for the
  clamped-guided wall, turn the plate where it meets the heads and bend it between them (uniform
  moment, E'I_p / head per end, I_p the sandwich of the two pads and the plate). By the cell's
  mirror symmetry about each layer's mid-plane, the upper walls of the layer below and the lower
  walls of the layer above put opposite moments into the plate, so only their difference turns it,
  against the plate and both walls (E'I / L each for a guided far end); a locked layer's walls
  put none, and the layer bends with the plate as one block of its whole height.

(Since 2026-11-30 the closed form carries a fitted form of the first, with the plate's squeeze
under the roots: mst_cli.model.plate_joint, fitted by studies/root_turn_sweep.py; the "closed
form" column here stays the plates' beams alone, as the study was written.)

c is fitted on two designs whose three layers are the same (the forward design's middle layer,
and that layer 0.5 mm thick), in regime 1, where the second mechanism vanishes by symmetry;
the rest is prediction. The rung is solved twice per regime (members rigid; plates as printed),
about 10 s a solve.

``--plate-sweep``: on the two same-layer designs, regime 1 (the first mechanism alone), the plate
0.4, 0.8, 1.6 and 3.0 mm thick, the c that matches the rung on each (about 3 min): whether one
c serves every plate and wall.
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import yaml

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.cell import wall_centreline_length_mm
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.plate_joint import root_turn_mm_per_N
from mst_cli.model.stack import Stack

ROOT = Path(__file__).resolve().parents[1]
FORWARD = ROOT / "configs" / "mohammadi2021-forward.yaml"
IDENTICAL = {"same-layers-t1.0": 1.0, "same-layers-t0.5": 0.5}  # the forward design's middle layer, 3 times


def identical_designs(folder: Path, plate_mm: float | None = None) -> list[Path]:
    """The forward config with its middle layer three times, at each thickness of IDENTICAL (and
    its plates ``plate_mm`` thick, when given)."""
    base = yaml.safe_load(FORWARD.read_text())
    out = []
    for i, (name, t) in enumerate(IDENTICAL.items()):
        layer = dict(base["layers"][1], t_mm=t)
        doc = {**base, "name": name, "layers": [layer] * 3}
        if plate_mm is not None:
            doc["housing"] = {"plate_mm": plate_mm}
        path = folder / f"identical{i}.yaml"
        path.write_text(yaml.safe_dump(doc))
        out.append(path)
    return out


def wall(cell, E_prime: float, depth: float) -> tuple[float, float, float]:
    """(L, E'I, cos theta) of the cell's inclined wall."""
    L = float(wall_centreline_length_mm(cell.theta_rad, cell.t_mm, cell.h_mm))
    return L, E_prime * depth * cell.t_mm**3 / 12.0, math.cos(cell.theta_rad)


def mechanisms(g, m, locked: tuple[int, ...], c: float) -> tuple[float, float]:
    """(the roots' local turn, the plates' turn at the heads) in mm/N over every plate."""
    E = m.youngs_modulus_MPa / (1.0 - m.poisson_ratio**2)
    D = g.depth_mm
    walls = [wall(cell, E, D) for cell in g.layers]
    heads = [lp.wall_head_x_mm(cell) for cell in g.layers]
    local = bend = 0.0
    for j in range(len(walls) - 1):
        moment_arm = stiff = 0.0  # sum of s_i L_i cos_i / 2 (per unit wall force), the walls' own E'I/L
        for i, s in ((j, 1.0), (j + 1, -1.0)):
            if i in locked:
                continue
            L, EI, cos = walls[i]
            local += 0.5 * root_turn_mm_per_N(L, EI, cos, c * E * D * g.layers[i].t_mm ** 2)
            moment_arm += s * 0.5 * L * cos
            stiff += EI / L
        # the sandwich the moments bend: the two pads and the plate, or a locked layer's whole height
        # (its cavity closed, it bends with the plate as one block)
        below, above = (g.layers[i].h_mm if i in locked else g.layers[i].t_mm for i in (j, j + 1))
        plate = below + g.housing.plate_mm + above
        k_plate = E * D * plate**3 / 12.0 / (0.5 * (heads[j] + heads[j + 1]))
        bend += 0.5 * moment_arm**2 / (k_plate + stiff)  # each chevron carries half the force
    return local, bend


def rung_rows(path: Path, regimes: int | None = None) -> list[dict]:
    """Per regime (the first ``regimes``, or all): the rung's extra drop with the plates as
    printed (cap and base rigid)."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    stack = Stack(layer_laws(g.layers, m, "spring"))
    rows = []
    for r, locked in enumerate(wp.regime_locked(stack)[:regimes]):
        opts = {"locked": locked, "member_factor": wp.RIGID_FACTOR}
        rigid = wp.press(g, m, wp.PartOptions(**opts)).drop_mm_per_N
        plates = wp.press(g, m, wp.PartOptions(**opts, scaled=("base", "cap"))).drop_mm_per_N
        closed = sum(lp.members(g, m).plates_mm_per_N)
        rows.append({"name": doc.name, "regime": r + 1, "g": g, "m": m, "locked": locked,
                     "rung": plates - rigid, "closed": closed})  # fmt: skip
        print(f"  {doc.name} regime {r + 1}: rung {1e3 * (plates - rigid):.2f} um/N", flush=True)
    return rows


def fit_c(rows: list[dict]) -> float:
    """c whose local turn makes the closed form's geometric mean over ``rows`` the rung's."""

    def misfit(c: float) -> float:
        return sum(math.log((r["closed"] + mechanisms(r["g"], r["m"], r["locked"], c)[0]) / r["rung"]) for r in rows)

    lo, hi = 0.01, 100.0  # misfit falls as c grows (a stiffer root)
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if misfit(mid) > 0.0 else (lo, mid)
    return math.sqrt(lo * hi)


def plate_sweep() -> None:
    """The c that matches the rung's regime 1 on each same-layer design at each plate thickness."""
    print("| plate, mm | " + " | ".join(f"{name}: rung um/N, c" for name in IDENTICAL) + " |")
    print("|---" * (1 + len(IDENTICAL)) + "|")
    for plate in (0.4, 0.8, 1.6, 3.0):
        with tempfile.TemporaryDirectory() as tmp:
            rows = [rung_rows(p, regimes=1)[0] for p in identical_designs(Path(tmp), plate)]
        print(f"| {plate} | " + " | ".join(f"{1e3 * r['rung']:.2f}, {fit_c([r]):.3f}" for r in rows) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = [ROOT / "configs" / n for n in ("mohammadi2021-forward.yaml", "mohammadi2021.yaml", "fingertip.yaml",
                                             "mohammadi2021-compact.yaml")]  # fmt: skip
    ap.add_argument("--configs", nargs="*", type=Path, default=default)
    ap.add_argument("--plate-sweep", action="store_true", help="only c per plate thickness, same-layer designs")
    args = ap.parse_args()
    if args.plate_sweep:
        plate_sweep()
        return
    with tempfile.TemporaryDirectory() as tmp:
        print("solving the rung (members rigid, then the plates as printed):")
        same = [row for p in identical_designs(Path(tmp)) for row in rung_rows(p)]
        rows = [row for p in args.configs for row in rung_rows(p)]
    c = fit_c([r for r in same if r["regime"] == 1])
    print(f"\nc = {c:.3f} (fitted on the same-layer designs' regime 1), plates' extra drop in um/N:")
    print("| design | regime | rung | closed form | + roots' local turn | + plates' turn at the heads | / rung |")
    print("|---|---|---|---|---|---|---|")
    for r in same + rows:
        local, bend = mechanisms(r["g"], r["m"], r["locked"], c)
        total = r["closed"] + local + bend
        cells = " | ".join(f"{1e3 * v:.2f}" for v in (r["rung"], r["closed"], r["closed"] + local, total))
        print(f"| {r['name']} | {r['regime']} | {cells} | {total / r['rung']:.2f} |")
    print(f"\n(the rung's default mesh; {len(same + rows)} regimes, two solves each)")


if __name__ == "__main__":
    main()
