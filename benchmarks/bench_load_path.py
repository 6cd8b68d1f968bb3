"""Load-path options (issue 44, docs/design.md 4.6): how much of the magnet's motion under a
centred fingertip press lies outside the layers, for the bundled forward design as exported and
with a thicker cap or a stiff plate over the magnet (the spec's ``insert`` section, its slot
and box as mst export builds them), by the closed form of
:mod:`mst_cli.model.load_path` (simply supported wall heads, then clamped: the stiff bound).

    python benchmarks/bench_load_path.py [--design configs/mohammadi2021-forward.yaml]

Not a speed benchmark: the table of numbers docs/design.md 4.6 and 10 quote. An insert's
modulus is taken in plane strain, E/(1 - nu^2), E and nu from the table
mst_cli.model.components.INSERT_MATERIALS; the plate spans its own depth, not the face's.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.assembly import InsertPlate
from mst_cli.model.components import INSERT_MATERIALS
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.response import simulate
from mst_cli.model.stack import Stack

ROOT = Path(__file__).resolve().parents[1]
# (material, thickness mm) of the spec's insert section: printed plates, then steel shims
INSERTS = (("petg", 1.0), ("petg", 2.0), ("pla", 1.0), ("pla", 2.0), ("steel", 0.5), ("steel", 1.0))


def row(label, g, material, stack) -> str:
    """One option: the cap's stiffness and the share outside the layers per regime (the
    geometry's own insert, its box from SensorGeometry.insert_box_mm)."""
    cells = [f"| {label} | {1.0 / lp.members(g, material).cap_mm_per_N:.1f}"]
    for support in lp.SUPPORTS:
        shares = lp.motion_shares(stack, lp.members(g, material, support=support))
        cells.append(" / ".join(f"{100 * r['outside_layers']:.0f}" for r in shares))
    return " | ".join(cells) + f" | {g.total_height_mm:.1f} |"


def prediction(label, g, material, insert=None) -> str:
    """One row of the whole part's L0 prediction: lock forces (the layer that locks) and the
    field change per newton at the chip per regime (secant, uT/N)."""
    part = simulate(g, material, parts=lp.members(g, material, insert=insert))
    locks = " / ".join(f"{r.force_to_N:.1f} ({r.layer})" for r in part.regimes)
    uT = " / ".join(f"{r.sensitivity_secant_per_N * part.B0_T * 1e6:.0f}" for r in part.regimes)
    return f"| {label} | {locks} | {uT} |"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--design", default=str(ROOT / "configs" / "mohammadi2021-forward.yaml"))
    args = ap.parse_args()
    doc = mst.load(args.design)
    g, m = doc.geometry(), doc.material
    stack = Stack(layer_laws(g.layers, m, "spring"))
    print(f"{doc.name}: outside the layers, regimes 1..{len(g.layers)} of the part (its own locks), %")
    print("| option | cap N/mm | simple | clamped | part height mm |\n|---|---|---|---|---|")
    bare = replace(g, insert_plate=None)
    insert = g.insert_plate
    said = f"{insert.material} {insert.thickness_mm:g} mm" if insert is not None and insert.present else "none"
    print(row(f"as designed (insert: {said})", g, m, stack))
    print(row(f"no insert (cap top {g.housing.cap_top_mm:g} mm)", bare, m, stack))
    for cap_top in (2.0, 4.0, 8.0):
        thick = replace(bare, housing=replace(g.housing, cap_top_mm=cap_top))
        print(row(f"no insert, cap top {cap_top:g} mm", thick, m, stack))
    for material, t in INSERTS:
        gi = replace(g, insert_plate=InsertPlate(material, t))
        print(row(f"{INSERT_MATERIALS[material].name} {t:g} mm over the magnet", gi, m, stack))
    layers = simulate(g, m, whole_part=False)
    print(f"\n{doc.name}: the prediction of `mst simulate` (rung L0, a centred {lp.FINGERTIP_PATCH_MM:g} mm press)")
    print("| model | lock forces N (layer) | field change per newton uT/N, per regime |\n|---|---|---|")
    print(
        "| layers alone (rigid members) | "
        + " / ".join(f"{r.force_to_N:.1f} ({r.layer})" for r in layers.regimes)
        + " | "
        + " / ".join(f"{r.sensitivity_secant_per_N * layers.B0_T * 1e6:.0f}" for r in layers.regimes)
        + " |"
    )
    print(prediction(f"whole part, as designed (insert: {said})", g, m))
    print(prediction(f"whole part, no insert (cap top {g.housing.cap_top_mm:g} mm)", bare, m))
    for material, t in INSERTS[1::2]:
        gi = replace(g, insert_plate=InsertPlate(material, t))
        print(prediction(f"whole part, {INSERT_MATERIALS[material].name} {t:g} mm", gi, m))


if __name__ == "__main__":
    main()
