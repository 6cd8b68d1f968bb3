"""The housing's base under a locked layer 1 (model.housing_base.cover_parts_locked_mm_per_N)
against the whole-part rung, part by part, and the fit of its one constant (issue 44,
docs/design.md 4.7, "The base under a locked layer: rebuilt").

Once layer 1 locks, the rung takes it as a filled block bonded on the cover. With every other
member rigid (the attribution's measure, studies/member_regimes.py) the plate over the block holds
it, and the block and the cover under it go down as one body; the base's compliance is in the
cover's short link from the block's edge to the slot's wall and in the wall. The form before
2026-12-02 bent the block as a free beam (cover + h_1 deep) and kept the open cover's end moment:
:func:`before_locked`, kept here for the record.

    PYTHONPATH=. .venv/bin/python studies/locked_base.py --configs configs/mohammadi2021.yaml \
        configs/fingertip.yaml configs/mohammadi2021-forward.yaml [--rung]
    PYTHONPATH=. .venv/bin/python studies/locked_base.py --box studies/data/member_regimes.csv
    PYTHONPATH=. .venv/bin/python studies/locked_base.py --fit studies/data/member_regimes.csv
    PYTHONPATH=. .venv/bin/python studies/locked_base.py --profile configs/mohammadi2021.yaml

``--configs``: each config's locked base split into the slot walls' squeeze, the cover on rigid
walls and the rest (the walls' turn with the cover), before and now; ``--rung`` adds the rung's
split (the cover rigid: the walls alone; the slot walls rigid: the cover alone; 4 solves a
config, about 15 s each). ``--box``: over the CSV's designs (40 sampled, seed 1) with layer 1
locked in some regime, each part's rung / closed form, before and now (a second, the CSV's rung
columns). ``--fit``: the base's rms log error over those designs for each value of
LINK_INTO_BLOCK on a grid. ``--profile``: the rung's drop along the cover's top and the block's.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import tempfile
from pathlib import Path
from unittest import mock

import numpy as np

import mst_cli as mst
from mst_cli.model import housing_base as hb
from mst_cli.model import load_path as lp
from mst_cli.model.beams import plain_section, section_EI_kGA
from mst_cli.model.mechanics import whole_part as wp
from studies import member_regimes as mr

PARTS = ("slot walls' squeeze", "cover on rigid walls", "rest", "base")


def spread(values: list[float]) -> str:
    return f"{statistics.median(values):.2f} ({min(values):.2f} to {max(values):.2f})" if values else "-"


def layer_1(path: Path) -> tuple:
    """(name, member scene, layer 1's t and h, its pad's and its wall heads' half widths, mm)."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    s = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    pad, head = lp.layer_supports(s, theta, t, h)[:2]
    return doc.name, s, float(t[0]), float(h[0]), float(pad[0]), float(head[0])


def before_locked(s, t_bottom_mm: float, h_bottom_mm: float, pad_mm: float, head_mm: float) -> tuple[float, float]:
    """(the base, the cover on rigid walls) of the locked form before 2026-12-02, mm/N: the open
    cover's (cover + t_1 under the pad) end moment and walls' turn kept, its bending swapped for a
    free deep beam's (cover + h_1 under the pad), the feet's bearing at the edge and the block's."""
    E, G, D = s.E_prime_MPa, s.G_MPa, s.depth_mm
    alone = plain_section(D, s.cover_mm, E, G)
    opened = section_EI_kGA(D, s.cover_mm + t_bottom_mm, E, G)
    deep = section_EI_kGA(D, s.cover_mm + h_bottom_mm, E, G)
    open_over, walls, open_bend = hb.housing_mm_per_N(s, head_mm, pad_mm, opened, alone)
    deep_bend = hb.housing_mm_per_N(s, head_mm, pad_mm, deep, alone)[2]
    bearings = hb.locked_bearings_mm_per_N(s, head_mm)
    return float(open_over - open_bend + deep_bend + walls + bearings), float(deep_bend + bearings)


def now_locked(s, pad_mm: float, head_mm: float) -> tuple[float, float]:
    """(the base, the cover on rigid walls) of the model's locked form, mm/N."""
    bend = hb.locked_link_mm_per_N(s, pad_mm, head_mm)[2]
    bearings = hb.locked_bearings_mm_per_N(s, head_mm)
    return float(sum(hb.cover_parts_locked_mm_per_N(s, pad_mm, head_mm))), float(bend + bearings)


def split(s, t_bottom_mm: float, h_bottom_mm: float, pad_mm: float, head_mm: float) -> dict[str, np.ndarray]:
    """{"before", "now": (squeeze, cover on rigid walls, rest, base), mm/N}."""
    squeeze = float(np.mean([0.5 * s.slot_height_mm / (s.E_prime_MPa * w * s.depth_mm) for w in s.slot_wall_widths_mm]))
    out = {}
    for label, (base, on_rigid) in (
        ("before", before_locked(s, t_bottom_mm, h_bottom_mm, pad_mm, head_mm)),
        ("now", now_locked(s, pad_mm, head_mm)),
    ):
        out[label] = np.array([squeeze, on_rigid, base - squeeze - on_rigid, base])
    return out


def rung_split(path: Path) -> np.ndarray:
    """The rung's base under a locked layer 1, mm/N, split as :func:`split`: the cover rigid (the
    walls alone), the slot walls rigid (the cover alone), the rest, the whole."""
    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    base = {"member_factor": wp.RIGID_FACTOR, "locked": (0,)}
    rigid = wp.press(g, m, wp.PartOptions(**base)).drop_mm_per_N
    tpu = {**base, "scaled": ("plate", "cap")}
    walls, cover, whole = (
        wp.press(g, m, wp.PartOptions(**tpu, rigid_base=part)).drop_mm_per_N - rigid
        for part in ("cover", "slot_walls", "")
    )
    return np.array([walls, cover, whole - walls - cover, whole])


def configs_table(paths: list[Path], rung: bool) -> None:
    print("| design | form | " + " | ".join(PARTS) + " |")
    print("|---|---|" + "---|" * len(PARTS))
    for path in paths:
        name, *layer = layer_1(path)
        rows = [*split(*layer).items(), *((("rung", rung_split(path)),) if rung else ())]
        for label, cells in rows:
            print(f"| {name} | {label} | " + " | ".join(f"{1e3 * v:.2f}" for v in cells) + " |", flush=True)


def box_rows(csv_path: Path, folder: Path) -> list[tuple[Path, np.ndarray]]:
    """(config, the rung's split, mm/N) of the CSV's designs with layer 1 locked in some regime (its
    first such row); the designs drawn again into ``folder`` as studies/member_regimes.py drew them
    (40, seed 1)."""
    with csv_path.open() as f:
        rows = list(csv.DictReader(f))
    out = []
    for path in mr.sampled_designs(folder, 40, 1):
        row = next((r for r in rows if r["name"] == path.stem and "0" in r["locked"].split()), None)
        if row is None:
            continue
        walls, cover, whole = (1e-3 * float(row[k]) for k in ("rung_slot_walls", "rung_cover", "rung_base"))
        out.append((path, np.array([walls, cover, whole - walls - cover, whole])))
    return out


def box_table(csv_path: Path, folder: Path) -> None:
    ratios: dict[str, list[np.ndarray]] = {}
    for path, rung in box_rows(csv_path, folder):
        for label, cells in split(*layer_1(path)[1:]).items():
            ratios.setdefault(label, []).append(rung / cells)
    print("| form | designs | " + " | ".join(PARTS) + " |")
    print("|---|---|" + "---|" * len(PARTS))
    for label, values in ratios.items():
        cells = " | ".join(spread([float(v[k]) for v in values]) for k in range(len(PARTS)))
        print(f"| {label} | {len(values)} | {cells} |")


def fit(csv_path: Path, folder: Path) -> None:
    """The base's rms log error (rung / closed) over the box for each LINK_INTO_BLOCK on a grid."""
    rows = [(layer_1(path)[1:], rung[3]) for path, rung in box_rows(csv_path, folder)]
    print("| LINK_INTO_BLOCK | rms log | median rung / closed |")
    print("|---|---|---|")
    for b in (0.0, 0.1, 0.15, 0.175, 0.2, 0.225, 0.25, 0.3, 0.5):
        with mock.patch.object(hb, "LINK_INTO_BLOCK", b):
            r = np.array([rung / now_locked(s, pad, head)[0] for (s, _, _, pad, head), rung in rows])
        print(f"| {b:g} | {np.sqrt(np.mean(np.log(r) ** 2)):.3f} | {np.median(r):.2f} |")


def profile(path: Path, xs_mm=(0.0, 4.0, 8.0, 10.0, 11.0, 12.0, 12.9, 14.5)) -> None:
    """The rung's base alone in TPU (everything else rigid) under a locked layer 1: the drop per
    newton, um/N, of the cover's top (the block's bottom) and the block's top at ``xs_mm``."""
    from skfem import condense, solve

    doc, _ = mst.designed(path)
    g, m = doc.geometry(), doc.material
    opts = wp.PartOptions(member_factor=wp.RIGID_FACTOR, locked=(0,), scaled=("plate", "cap"))
    mesh, _, element, basis, K, held = wp._system(g, m, opts)
    u = solve(*condense(K, wp._load(g, mesh, element, opts.patch_mm), D=held))
    uz, p = u[basis.nodal_dofs[1]], mesh.p
    _, s, _, h, pad, _ = layer_1(path)
    z0 = g.layer_bottoms_mm[0]
    print(
        f"{doc.name}: the block's pad edge x = {pad:.2f}, the slot's edge {s.half_slot_mm:.2f}, cover {s.cover_mm} mm"
    )
    print("| x, mm | " + " | ".join(f"{x:g}" for x in xs_mm) + " |")
    print("|---|" + "---|" * len(xs_mm))
    for label, z in (("the cover's top", z0), ("the block's top", z0 + h)):
        line = np.flatnonzero(np.abs(p[1] - z) < 1e-6)
        drops = [-1e3 * uz[line[np.argmin(np.abs(p[0, line] - x))]] for x in xs_mm]
        print(f"| {label} | " + " | ".join(f"{d:.2f}" for d in drops) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", type=Path, nargs="+", help="configs: their locked base, part by part")
    ap.add_argument("--rung", action="store_true", help="with --configs: the rung's split too (4 solves a config)")
    ap.add_argument("--box", type=Path, help="studies/member_regimes.py's CSV: each part's rung / closed")
    ap.add_argument("--fit", type=Path, help="the same CSV: LINK_INTO_BLOCK's grid")
    ap.add_argument("--profile", type=Path, nargs="+", help="configs: the rung's drop along the cover and block")
    args = ap.parse_args()
    if args.configs:
        configs_table(args.configs, args.rung)
    elif args.box or args.fit:
        with tempfile.TemporaryDirectory() as tmp:
            (box_table if args.box else fit)(args.box or args.fit, Path(tmp))
    elif args.profile:
        for path in args.profile:
            profile(path)
    else:
        ap.error("give --configs, --box, --fit or --profile")


if __name__ == "__main__":
    main()
