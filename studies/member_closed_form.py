"""The members' closed form against the whole-part rung over the design box, as it was when
studies/member_regimes.py ran (the CSV's closed columns, 137b3e2) and as it is now (issue 44,
docs/design.md 4.7, "The members' closed form, rebuilt"). No rung solves unless --per-plate.

Per regime (the layers locked in order, the cover not landed in either form) it prints each
member class's rung / closed form (median, least, most) before and now, the base apart for
layer 1 standing on the slot's walls (its wall heads within 0.3 mm of the slot's edge or on the
wall) and over the slot, and the part's closed / rung - 1 with how many designs are within 5 %.

    PYTHONPATH=. .venv/bin/python studies/member_closed_form.py studies/data/member_regimes.csv --designs 40 --seed 1
    PYTHONPATH=. .venv/bin/python studies/member_closed_form.py --per-plate configs/mohammadi2021.yaml

``--fit-bearing``: the base's rms log error against the rung per regime for each value of its one
fitted constant, model.housing_base.BEARING, on a grid (a few seconds).
``--deep-walls``: the tables with the locked cover's walls' part taken on the deep section too
(:func:`deep_walls_locked`, a probe not kept, docs/design.md 4.7); with configs after it, each
config's locked base in both forms, part by part (:func:`locked_base`), and with ``--rung`` the
rung's split of it (4 solves a config, about 30 s).
``--profile CONFIG ...``: the rung's base alone under a locked layer 1, its drop along the cover
and the block (:func:`block_profile`, one solve a config).
``--per-plate``: past each lock of each config's design, the rung with plate 1 alone, plate 2
alone and both in TPU (base and cap rigid) against the closed form's plates now: the plates over
two locked layers (model.past_lock.over_two_locked_mm_per_N). 5 solves a regime, a few minutes.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import functools
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
        for row, now in zip(mine, mr.closed_rows(g, m, Stack(layer_laws(g.layers, m, "spring")))):
            regime = int(row["regime"])
            landed = min(float(row["cover_lands_N"]), now["cover_lands_N"]) < float(row["regime_to_N"])
            if landed or row["locked"].split() != [str(j) for j in range(regime - 1)]:
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
    for regime, key in sorted({(r, k) for r, k, _ in out if k != "part"}):
        print(f"| {regime} | {key} | {spread(out[(regime, key, 'before')])} | {spread(out[(regime, key, 'now')])} |")
    print("\n| regime | designs | part: closed / rung - 1, before | within 5 % | now | within 5 % |")
    print("|---|---|---|---|---|---|")
    for regime in sorted({r for r, k, _ in out if k == "part"}):
        before, now = out[(regime, "part", "before")], out[(regime, "part", "now")]
        within = [sum(abs(e) <= 0.05 for e in v) for v in (before, now)]
        cells = f"{spread(before, '+.1%')} | {within[0]} | {spread(now, '+.1%')} | {within[1]}"
        print(f"| {regime} | {len(before)} | {cells} |")


def fit_bearing(rows: list[dict], designs: dict) -> None:
    """The base's one fitted constant (model.housing_base.BEARING): the base's rms log error
    against the rung per regime, and their sum, for each c_b on the grid."""
    from mst_cli.model import housing_base as hb

    kept = hb.BEARING
    print("| c_b | rms log, regime 1 | regime 2 | regime 3 | sum |")
    print("|---|---|---|---|---|")
    try:
        for c_b in (0.4, 0.5, 0.6, 0.7, 0.8, 1.0, 1.2, 1.5, 2.0):
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


def deep_walls_locked(scene, h_bottom_mm, pad_mm, head_mm, opened: tuple, alone: tuple, stiffer: float = 1.0) -> tuple:
    """model.housing_base._locked_from_open with one change: the cover's end moment, and with it
    the slot walls' turn and the edges' drop, solved on the deep section (cover + h_1 under the
    pad) as its bending is, where the model keeps the open cover's (``opened`` unused); the deep
    section's E'I and kGA times ``stiffer`` (1e4: the block rigid)."""
    from mst_cli.model import housing_base as hb
    from mst_cli.model.beams import section_EI_kGA

    s = scene
    E, G, D = s.E_prime_MPa, s.G_MPa, s.depth_mm
    deep = tuple(stiffer * v for v in section_EI_kGA(D, s.cover_mm + h_bottom_mm, E, G))
    over, walls, _ = hb.housing_mm_per_N(s, head_mm, pad_mm, deep, alone)
    return over, walls + hb.corner_mm_per_N(s, head_mm) + 0.5 / (hb.BEARING * E * D)


@contextlib.contextmanager
def deep_walls(stiffer: float = 1.0):
    """model.housing_base with :func:`deep_walls_locked` in place of its locked cover's form."""
    from mst_cli.model import housing_base as hb

    kept = hb._locked_from_open
    hb._locked_from_open = functools.partial(deep_walls_locked, stiffer=stiffer)
    try:
        yield
    finally:
        hb._locked_from_open = kept


def locked_split(path: Path) -> tuple[str, dict]:
    """(the design's name, {form: (the slot walls' squeeze, the cover on rigid walls (its deep
    bending, the feet's and the block's bearing), the rest (the walls' turn with the cover), the
    base)}) of the design at ``path`` once layer 1 is locked, mm/N, in the model's form ("model")
    and in :func:`deep_walls_locked`'s ("deep walls")."""
    from mst_cli.model import housing_base as hb
    from mst_cli.model.beams import plain_section, section_EI_kGA

    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    s = lp.member_scene(g, m)
    E, G, D = s.E_prime_MPa, s.G_MPa, s.depth_mm
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    pad, head = lp.layer_supports(s, theta, t, h)[:2]
    squeeze = float(np.mean([0.5 * s.slot_height_mm / (E * w * D) for w in s.slot_wall_widths_mm]))
    deep = section_EI_kGA(D, s.cover_mm + h[0], E, G)
    bend = hb.cover_bending_mm_per_N(s, head[0], pad[0], deep, plain_section(D, s.cover_mm, E, G))
    on_rigid = float(bend + hb.corner_mm_per_N(s, head[0]) + 0.5 / (hb.BEARING * E * D))
    out = {}
    for label, form in (("model", contextlib.nullcontext()), ("deep walls", deep_walls())):
        with form:
            total = float(sum(hb.cover_parts_locked_mm_per_N(s, t[0], h[0], pad[0], head[0])))
        out[label] = (squeeze, on_rigid, total - squeeze - on_rigid, total)
    return doc.name, out


def rung_split(path: Path) -> tuple[float, float, float, float]:
    """The rung's base once layer 1 is locked, mm/N, split as :func:`locked_split`'s: the cover
    rigid (the walls alone), the slot walls rigid (the cover alone), the rest, the whole."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    base = {"member_factor": wp.RIGID_FACTOR, "locked": (0,)}
    rigid = wp.press(g, m, wp.PartOptions(**base)).drop_mm_per_N
    tpu = {**base, "scaled": ("plate", "cap")}
    walls, cover, whole = (
        wp.press(g, m, wp.PartOptions(**tpu, rigid_base=part)).drop_mm_per_N - rigid
        for part in ("cover", "slot_walls", "")
    )
    return walls, cover, whole - walls - cover, whole


def locked_base(configs: list[Path], rung: bool = False) -> None:
    """Each config's :func:`locked_split`, um/N; ``rung``: the rung's (:func:`rung_split`)."""
    print("| design | form | slot walls' squeeze | cover on rigid walls | rest | base |")
    print("|---|---|---|---|---|---|")
    for path in configs:
        name, forms = locked_split(path)
        rows = [*forms.items(), *((("rung", rung_split(path)),) if rung else ())]
        for label, cells in rows:
            print(f"| {name} | {label} | " + " | ".join(f"{1e3 * v:.2f}" for v in cells) + " |", flush=True)


def locked_split_over_box(rows: list[dict], designs: dict) -> None:
    """Over the CSV's designs with layer 1 locked in some regime (its first such row; the rung's
    base, cover and slot walls columns): each part's rung / closed form, median (least to most),
    in both forms of :func:`locked_split`."""
    ratios_by_form: dict[str, list[list[float]]] = {}
    for name, path in designs.items():
        row = next((r for r in rows if r["name"] == name and "0" in r["locked"].split()), None)
        if row is None:
            continue
        walls, cover = float(row["rung_slot_walls"]), float(row["rung_cover"])
        whole = float(row["rung_base"])
        rung = (walls, cover, whole - walls - cover, whole)
        for form, cells in locked_split(path)[1].items():
            ratios_by_form.setdefault(form, []).append([r / (1e3 * c) for r, c in zip(rung, cells)])
    print("| form | designs | slot walls' squeeze | cover on rigid walls | rest | base |")
    print("|---|---|---|---|---|---|")
    for form, values in ratios_by_form.items():
        columns = [spread([v[k] for v in values]) for k in range(4)]
        print(f"| {form} | {len(values)} | " + " | ".join(columns) + " |")


def block_profile(path: Path, xs_mm=(0.0, 4.0, 8.0, 10.0, 11.0, 12.0, 12.9, 14.5)) -> None:
    """The rung's base alone in TPU (everything else rigid) under a locked layer 1: the drop per
    newton, um/N, of the cover's top (the block's bottom) and the block's top at ``xs_mm``; and the
    model's locked cover split at the slot's edge, the block rigid (what the attribution's rigid
    plate over it makes it): the cover's link from the block's edge to the wall (bending, shear)
    and the slot wall's inner edge (squeeze and turn), for one wall, P = 1/2."""
    from skfem import condense, solve

    from mst_cli.model import housing_base as hb
    from mst_cli.model.beams import plain_section, section_EI_kGA

    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    opts = wp.PartOptions(member_factor=wp.RIGID_FACTOR, locked=(0,), scaled=("plate", "cap"))
    mesh, _, element, basis, K, held = wp._system(g, m, opts)
    u = solve(*condense(K, wp._load(g, mesh, element, opts.patch_mm), D=held))
    uz, p = u[basis.nodal_dofs[1]], mesh.p
    s = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    pad, head = lp.layer_supports(s, theta, t, h)[:2]
    z0 = g.layer_bottoms_mm[0]
    print(f"{doc.name}: block's pad edge x = {pad[0]:.2f}, slot's edge {s.half_slot_mm:.2f}, cover {s.cover_mm} mm")
    print("| x, mm | " + " | ".join(f"{x:g}" for x in xs_mm) + " |")
    print("|---|" + "---|" * len(xs_mm))
    for label, z in (("the cover's top", z0), ("the block's top", z0 + h[0])):
        line = np.flatnonzero(np.abs(p[1] - z) < 1e-6)
        drops = [-1e3 * uz[line[np.argmin(np.abs(p[0, line] - x))]] for x in xs_mm]
        print(f"| {label} | " + " | ".join(f"{d:.2f}" for d in drops) + " |")
    E, G, D, P, w = s.E_prime_MPa, s.G_MPa, s.depth_mm, 0.5, s.slot_wall_widths_mm[0]
    rigid_block = tuple(wp.RIGID_FACTOR * v for v in section_EI_kGA(D, s.cover_mm + h[0], E, G))
    e, B, C1, C2, shear = hb._cover_integrals(
        s, np.asarray(head[0]), pad[0], rigid_block, plain_section(D, s.cover_mm, E, G)
    )
    k_wall, k_end = hb.wall_turn_Nmm_per_rad(s, w), hb.END_BUILT_IN * E * D * s.cover_mm**2
    M = (P * C1 - P * hb.WALL_LEVER * w / k_wall) / (B + 1.0 / (1.0 / (1.0 / k_wall + 1.0 / k_end)))
    turn = (P * hb.WALL_LEVER * w + M) / k_wall
    squeeze, edge_turn = P * s.slot_height_mm / (E * w * D), 0.5 * w * turn
    print(
        f"model, the block rigid: the link {1e3 * (P * C2 - M * C1):.2f} (bending) + {1e3 * shear:.2f} (shear), ",
        end="",
    )
    print(f"the wall's inner edge {1e3 * squeeze:.2f} (squeeze) + {1e3 * edge_turn:.2f} (turn) um/N")


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
    ap.add_argument("--deep-walls", type=Path, nargs="*", default=None, help="the locked cover's probe (docstring)")
    ap.add_argument("--rung", action="store_true", help="with --deep-walls CONFIGS: the rung's split too")
    ap.add_argument("--split", action="store_true", help="with the CSV: the locked base's parts, rung / closed")
    ap.add_argument("--profile", type=Path, nargs="*", default=[], help="configs: the locked block's drop profile")
    ap.add_argument("--fit-bearing", action="store_true", help="the base's rms log error for each c_b on the grid")
    args = ap.parse_args()
    if args.profile:
        for path in args.profile:
            block_profile(path)
        return
    if args.deep_walls:
        locked_base(args.deep_walls, args.rung)
        return
    if args.per_plate or args.csv is None:
        per_plate(args.per_plate)
        return
    with args.csv.open() as f:
        rows = list(csv.DictReader(f))
    with tempfile.TemporaryDirectory() as tmp:
        designs = {p.stem: p for p in mr.sampled_designs(Path(tmp), args.designs, args.seed)}
        if args.split:
            locked_split_over_box(rows, designs)
            return
        with deep_walls() if args.deep_walls is not None else contextlib.nullcontext():
            (fit_bearing if args.fit_bearing else lambda r, d: tables(ratios(r, d)))(rows, designs)


if __name__ == "__main__":
    main()
