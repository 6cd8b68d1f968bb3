"""The members' closed form against the whole-part rung over the design box, as it was when
studies/member_regimes.py ran (the CSV's closed columns, 137b3e2) and as it is now (issue 44,
docs/design.md 4.7, "The members' closed form, rebuilt"). No rung solves unless --per-plate.

Per regime (the layers locked in order, in the rung's regime, the layers alone's, and in the
part's, whose members can lock another layer first: those are counted apart, "other order", as
they compare two states; the cover not landed in either form) it prints each
member class's rung / closed form (median, least, most) before and now, the base apart for
layer 1 standing on the slot's walls (its wall heads within 0.3 mm of the slot's edge or on the
wall) and over the slot, and the part's closed / rung - 1 with how many designs are within 5 %.

    PYTHONPATH=. .venv/bin/python studies/member_closed_form.py studies/data/member_regimes.csv --designs 40 --seed 1
    PYTHONPATH=. .venv/bin/python studies/member_closed_form.py --per-plate configs/mohammadi2021.yaml

``--fit-bearing``: the base's rms log error against the rung per regime for each value of its one
fitted constant, model.housing_base.BEARING, on a grid (a few seconds).
``--per-plate``: past each lock of each config's design, the rung with plate 1 alone, plate 2
alone and both in TPU (base and cap rigid) against the closed form's plates now: the plates over
two locked layers (model.past_lock.over_two_locked_mm_per_N). 5 solves a regime, a few minutes.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import tempfile
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.stack import Stack
from studies import member_regimes as mr

ON_WALL_MM = 0.3  # layer 1's wall heads less than this inside the slot's edge: "on the wall"


def spread(values: list[float], form: str = ".2f") -> str:
    return f"{statistics.median(values):{form}} ({min(values):{form}} to {max(values):{form}})" if values else "-"


def ratios(rows: list[dict], designs: dict) -> dict:
    """{(regime, member or "part", "before" or "now"): values} over the CSV's rows (module docstring)."""
    out: dict[tuple, list[float]] = {}
    for name, path in designs.items():
        mine = [r for r in rows if r["name"] == name]
        if not mine:
            continue
        doc, _ = mst.designed(path)
        g, m = doc.geometry(), doc.material
        s = lp.member_scene(g, m)
        theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
        head = lp.layer_supports(s, theta, t, h)[1]
        where = "base, over the slot" if s.half_slot_mm - head[0] > ON_WALL_MM else "base, on the wall"
        laws = layer_laws(g.layers, m, "spring")
        part_locked = list(wp.regime_locked(Stack(tuple(lp.capped_units(laws, lp.members(g, m))))))
        for row, now in zip(mine, mr.closed_rows(g, m, Stack(laws))):
            regime = int(row["regime"])
            landed = min(float(row["cover_lands_N"]), now["cover_lands_N"]) < float(row["regime_to_N"])
            if landed or row["locked"].split() != [str(j) for j in range(regime - 1)]:
                continue
            if tuple(part_locked[regime - 1]) != tuple(range(regime - 1)):
                # the rung's regime is the layers alone's (layers locked in order); the part's
                # members lock another layer first, so its regime here is another state
                out.setdefault((regime, "other order", "now"), []).append(1.0)
                continue
            for k, key in (("base", where), ("plate", "plates"), ("cap", "cap")):
                rung, before = float(row[f"rung_{k}"]), float(row[f"closed_{k}"])
                if before > 0.0 and now[f"closed_{k}"] > 0.0:
                    out.setdefault((regime, key, "before"), []).append(rung / before)
                    out.setdefault((regime, key, "now"), []).append(rung / now[f"closed_{k}"])
            printed = float(row["printed"])
            out.setdefault((regime, "part", "before"), []).append(float(row["closed_part"]) / printed - 1.0)
            out.setdefault((regime, "part", "now"), []).append(now["closed_part"] / printed - 1.0)
    return out


def tables(out: dict) -> None:
    print("| regime | member | rung / closed form, before | now |")
    print("|---|---|---|---|")
    for regime, key in sorted({(r, k) for r, k, _ in out if k not in ("part", "other order")}):
        print(f"| {regime} | {key} | {spread(out[(regime, key, 'before')])} | {spread(out[(regime, key, 'now')])} |")
    print("\n| regime | designs | part: closed / rung - 1, before | within 5 % | now | within 5 % | other order |")
    print("|---|---|---|---|---|---|---|")
    for regime in sorted({r for r, k, _ in out if k == "part"}):
        before, now = out[(regime, "part", "before")], out[(regime, "part", "now")]
        within = [sum(abs(e) <= 0.05 for e in v) for v in (before, now)]
        cells = f"{spread(before, '+.1%')} | {within[0]} | {spread(now, '+.1%')} | {within[1]}"
        print(f"| {regime} | {len(before)} | {cells} | {len(out.get((regime, 'other order', 'now'), []))} |")


def fit_bearing(rows: list[dict], designs: dict) -> None:
    """The base's one fitted constant (model.housing_base.BEARING): the base's rms log error
    against the rung per regime, and their sum, for each c_b on the grid."""
    from mst_cli.model import housing_base as hb

    kept = hb.BEARING
    print("| c_b | rms log, regime 1 | regime 2 | regime 3 | sum |")
    print("|---|---|---|---|---|")
    try:
        for c_b in (0.6, 0.8, 1.0, 1.2, 1.5, 2.0):
            hb.BEARING = c_b
            out = ratios(rows, designs)
            rms = [
                float(np.sqrt(np.mean([np.log(v) ** 2 for (r, k, w), vs in out.items() if r == regime
                                       and k.startswith("base") and w == "now" for v in vs])))
                for regime in (1, 2, 3)
            ]  # fmt: skip
            print(f"| {c_b:g} | {rms[0]:.3f} | {rms[1]:.3f} | {rms[2]:.3f} | {sum(rms):.3f} |", flush=True)
    finally:
        hb.BEARING = kept


def per_plate(configs: list[Path]) -> None:
    """Past each lock of the part, the rung's plates one at a time and together against the
    closed form's plates as the forward model moves them, um/N."""
    print("| design | regime | plate 1 alone | plate 2 alone | both | closed form |")
    print("|---|---|---|---|---|---|")
    for path in configs:
        doc, _ = mst.designed(path)
        g, m = doc.geometry(), doc.material
        stack = Stack(layer_laws(g.layers, m, "spring"))
        closed = mr.closed_rows(g, m, stack)
        part = Stack(tuple(lp.capped_units(stack.layers, lp.members(g, m))))
        for r, locked in enumerate(wp.regime_locked(part)):
            if not locked:
                continue
            opts = {"locked": locked, "member_factor": wp.RIGID_FACTOR}
            rigid = 1e3 * wp.press(g, m, wp.PartOptions(**opts)).drop_mm_per_N
            alone = ((1,), (0,), ())  # plate 1 alone, plate 2 alone, both
            drops = [wp.press(g, m, wp.PartOptions(**opts, scaled=("base", "cap"), rigid_plates=k)) for k in alone]
            cells = " | ".join(f"{1e3 * d.drop_mm_per_N - rigid:.2f}" for d in drops)
            print(f"| {doc.name} | {r + 1} | {cells} | {closed[r]['closed_plate']:.2f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", type=Path, nargs="?", help="a CSV of studies/member_regimes.py")
    ap.add_argument("--designs", type=int, default=0, help="how many designs its run sampled")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--per-plate", type=Path, nargs="*", default=[], help="configs: each plate alone on the rung")
    ap.add_argument("--fit-bearing", action="store_true", help="the base's rms log error for each c_b on the grid")
    args = ap.parse_args()
    if args.per_plate or args.csv is None:
        per_plate(args.per_plate)
        return
    with args.csv.open() as f:
        rows = list(csv.DictReader(f))
    with tempfile.TemporaryDirectory() as tmp:
        designs = {p.stem: p for p in mr.sampled_designs(Path(tmp), args.designs, args.seed)}
        (fit_bearing if args.fit_bearing else lambda r, d: tables(ratios(r, d)))(rows, designs)


if __name__ == "__main__":
    main()
