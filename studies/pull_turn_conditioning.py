"""How well the turn per tangential newton is posed, design by design and regime by regime (issue 44,
docs/design.md 4.7, "How well posed the turn per tangential newton is"). Prints a table; solves
nothing on the rung unless asked (it reads the rows ``benchmarks/bench_whole_part.py --off-centre
--every-regime --out studies/data/member_turns.csv`` stored).

    PYTHONPATH=. .venv/bin/python studies/pull_turn_conditioning.py [--rows CSV]
        [--cover-tolerance-mm 0.05] [--mesh] [--design mohammadi2021-forward]

The whole-part rung's turn per tangential newton (mrad/N, its sign) is a sum of terms: the layers
(every member rigid), what each member class alone in TPU adds (the base, the plates, the cap),
and what they add together beyond that (the interaction). Past layer 1's lock the base's term is
itself a difference, the portal's sway S less the pull's moment's turn H k_M
(studies/base_portal.py). A model that misses every term by the same relative error e can miss
the sum by up to kappa e, kappa = sum |term| / |sum|, and by a e if the misses are independent,
a = sqrt(sum term^2) / |sum|. The last column is the e that gives 10 % on the sum, a's way: where
it is below the few per cent that a beam model holds a member to, the 10 % is out of a closed
form's reach, whatever its members.

``--cover-tolerance-mm`` solves the rung as printed with the housing's cover that much thinner
and thicker (the design's layers unchanged): how far the printed part's own figure moves with
one print tolerance, against the 10 %. ``--mesh`` solves it as printed on the rung's mesh, one
twice as coarse and one twice as fine (one refinement round fewer and more): how well the rung
itself holds the figure.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import math
from pathlib import Path

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model import plate_sway as ps
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.stack import Stack
from studies.base_portal import cover_depth_mm, member_rows

ROOT = Path(__file__).resolve().parents[1]
CLASSES = ("only the base", "only the plate", "only the cap")
TARGET_REL = 0.10  # the done-when's budget on the turn per tangential newton


def pull_terms(turn: dict, pull: dict, regime: int, H_mm: float, layer_1_locked: bool) -> dict[str, float]:
    """The rung's turn per tangential newton in ``regime`` as its terms, mrad/N (module docstring);
    ``turn``, ``pull``: one design's rows (studies/base_portal.member_rows), ``H_mm`` the cover's
    mid-plane under the top face."""
    rigid = pull[(regime, "rigid")]
    added = {c: pull[(regime, c)] - rigid for c in CLASSES}
    terms = {"layers": rigid}
    if layer_1_locked:  # the base's net is S - H k_M (studies/base_portal.py)
        k_M = turn[(regime, "rigid")] - turn[(regime, "only the base")]
        terms |= {"base: S": added["only the base"] + H_mm * k_M, "base: -H k_M": -H_mm * k_M}
    else:
        terms["base"] = added["only the base"]
    terms |= {"plates": added["only the plate"], "cap": added["only the cap"]}
    terms["interaction"] = pull[(regime, "as printed")] - rigid - sum(added.values())
    return terms


def conditioning(terms: dict[str, float]) -> tuple[float, float, float]:
    """(the sum, kappa, a) of ``terms`` (module docstring)."""
    total = sum(terms.values())
    kappa = sum(abs(v) for v in terms.values()) / abs(total)
    a = math.sqrt(sum(v * v for v in terms.values())) / abs(total)
    return total, kappa, a


def printed_turns(doc, **options) -> list[float]:
    """The rung's turn per tangential newton as printed, mrad/N, in each regime of ``doc`` (a
    Document), on the mesh ``options`` (wp.PartOptions' spacing_mm, levels) asks for."""
    g, m = doc.geometry(), doc.material
    part = Stack(tuple(lp.capped_units(layer_laws(g.layers, m, "spring"), lp.members(g, m))))
    return [
        1e3 * wp.press_general(g, m, wp.PartOptions(locked=locked, **options)).pull.turn_rad_per_N
        for locked in wp.regime_locked(part)
    ]


def cover_tolerance_rows(name: str, tol_mm: float) -> list[str]:
    """The rung as printed, each regime, with the cover ``tol_mm`` thinner, as designed and thicker."""
    doc, _ = mst.designed(ROOT / "configs" / f"{name}.yaml")
    cover = doc.housing.cover_mm
    rows = []
    for c in (cover - tol_mm, cover, cover + tol_mm):
        figures = printed_turns(dataclasses.replace(doc, housing=dataclasses.replace(doc.housing, cover_mm=c)))
        rows.append(f"| {c:.3f} | " + " | ".join(f"{v:.4f}" for v in figures) + " |")
    return rows


def mesh_rows(name: str) -> list[str]:
    """The rung as printed, each regime, on the mesh twice as coarse, the rung's, twice as fine."""
    doc, _ = mst.designed(ROOT / "configs" / f"{name}.yaml")
    base = wp.default_spacing_mm(doc.geometry())
    rows = []
    for scale, levels in ((2.0, wp.DEFAULT_LEVELS - 1), (1.0, wp.DEFAULT_LEVELS), (0.5, wp.DEFAULT_LEVELS + 1)):
        figures = printed_turns(doc, spacing_mm=scale * base, levels=levels)
        rows.append(f"| {scale * base:g} mm, {levels} levels | " + " | ".join(f"{v:.4f}" for v in figures) + " |")
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=Path, default=ROOT / "studies" / "data" / "member_turns.csv")
    ap.add_argument("--cover-tolerance-mm", type=float, default=None)
    ap.add_argument("--mesh", action="store_true")
    ap.add_argument("--design", default="mohammadi2021-forward", help="with --cover-tolerance-mm or --mesh")
    args = ap.parse_args()
    with args.rows.open() as f:
        raw = list(csv.DictReader(f))
    names = list(dict.fromkeys(r["design"] for r in raw))
    print("the rung's turn per tangential newton as its terms, mrad/N; kappa = sum |term| / |sum|, a = rms;")
    print(f"each term within e gives the sum within {TARGET_REL:.0%} (a's way)")
    print("| design | regime | terms | sum | kappa | a | e |")
    print("|---|---|---|---|---|---|---|")
    for name in names:
        doc, _ = mst.designed(ROOT / "configs" / f"{name}.yaml")
        g, m = doc.geometry(), doc.material
        order = [int(i) for i in Stack(layer_laws(g.layers, m, "spring")).lock_order]
        H = cover_depth_mm(ps.stack_section(g, m))
        turn, pull = member_rows(raw, name)
        for regime in sorted({k[0] for k in pull}):
            terms = pull_terms(turn, pull, regime, H, 0 in order[: regime - 1])
            total, kappa, a = conditioning(terms)
            listed = ", ".join(f"{k} {v:+.3f}" for k, v in terms.items())
            print(f"| {name} | {regime} | {listed} | {total:.3f} | {kappa:.1f} | {a:.1f} | {TARGET_REL / a:.1%} |")
    if args.cover_tolerance_mm is not None:
        print(f"\n{args.design}: the rung as printed, turn per tangential newton (mrad/N) per regime, by cover")
        print("| cover, mm | " + " | ".join(f"regime {r}" for r in (1, 2, 3)) + " |")
        print("|---|---|---|---|")
        print("\n".join(cover_tolerance_rows(args.design, args.cover_tolerance_mm)))
    if args.mesh:
        print(f"\n{args.design}: the rung as printed, turn per tangential newton (mrad/N) per regime, by mesh")
        print("| mesh | " + " | ".join(f"regime {r}" for r in (1, 2, 3)) + " |")
        print("|---|---|---|---|")
        print("\n".join(mesh_rows(args.design)))


if __name__ == "__main__":
    main()
