"""Past two locks the cap and the plate under the top layer give more together than alone: a
plane frame of that layer's cell finds why (issue 44, docs/design.md 4.7, "The cap and the plate
together, past two locks").

In regime 3 of a three-layer part (layers 1 and 2 locked, their cavities closed) the whole-part
rung's members add more than their parts: the "rest" (as printed, less every member alone) is a
median 6.7 % of the part over the box (studies/data/member_regimes.csv), and most of it is the
cap with the plates (studies/member_closed_form.py's rows; on three designs 0.9, 2.8 and 6.1 um/N
of 0.9 to 6.1). mst's closed form sums each member alone, so it misses it.

The frame (model.plane_frame) is half the top layer's cell, symmetric about x = 0: the cap from
the centre to the wall heads, the two half-walls of the hexagon (head, side vertex, foot), the
plate from the foot to the locked block's edge (a cantilever when the feet stand beyond it, its
root turning into the block against past_lock's k E'D d^2), the walls' roots turning into cap and
plate (model.plate_joint's springs), the press 1/2 N at the cap's centre. The cap and the plate
are each the closed form's section (the cap with its pocket and insert; the plate with the pad
over it, p + t). What the closed form's members do not have is **where the walls meet them**: a
wall's end is at the underside of the cap (the cap's mid-plane cap_above/2 above it) and on the
top of the plate (its mid-plane p/2 below). The hexagon's walls thrust along the cap and the
plate; off their mid-planes the thrust bends them, and how much thrust there is depends on how
freely the wall's other end turns. So a soft cap and a soft plate feed each other. With the
offsets set to 0 (``--no-offsets``, the control) the frame's interaction nearly vanishes.

Per design: the rung with the plates alone in TPU, the cap alone, both (the base rigid), against
the frame's same three (each less its rigid case). 3 rung solves a design more than the rigid
one, kept in mst's cache (a second run reads them back).

    PYTHONPATH=. .venv/bin/python studies/cap_plate_thrust.py --configs configs/mohammadi2021-forward.yaml
    PYTHONPATH=. .venv/bin/python studies/cap_plate_thrust.py --box 40 [--no-offsets]
    PYTHONPATH=. .venv/bin/python studies/cap_plate_thrust.py --part studies/data/member_regimes.csv

model.wall_thrust.chain_drop_mm_per_N is the same frame by another method, vectorised over
stacks as the design loop's members are: the flexibility of the chain from the block to the cap's
centre (no stiff links, so exact where the stiffness method loses about 1e-4 to them); its four
rigid cases' signed sum is the thrust term the closed form now carries (``--cost``: its time).

``--decompose``: where the closed form's regime 3 falls short of the rung over the box, member by
member and the rest, % of the part (and the walls' two roots solved together); ``--cost``: the
chain's time. Both without rung solves.

``--part``: the closed form's regime 3 over the box (the CSV's rung) without the thrust term and
with it, as the model has it (no rung solves, seconds).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.cell import wall_centreline_length_mm
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.past_lock import LOCKED_FITTED
from mst_cli.model.plane_frame import Frame
from mst_cli.model.plate_joint import root_spring_Nmm_per_rad
from mst_cli.model.stack import Stack
from mst_cli.model.wall_thrust import chain_drop_mm_per_N as chain_drop_mm_per_N
from mst_cli.model.wall_thrust import chain_members, scene_thrust_mm_per_N, thrust_extra_mm_per_N

RIGID = 1e4  # the rigid members' modulus factor, as the rung's control
TIE_N_PER_MM = 1e9  # a spring's two nodes tied in position
STIFF = 1e12  # the short offsets from a wall's end to a member's mid-plane: rigid


def offset_node(f: Frame, node: int, x_mm: float, z_mm: float) -> int:
    """A node at (x, z) held rigidly to ``node`` (``node`` itself where they coincide)."""
    if np.hypot(x_mm - f.nodes[node][0], z_mm - f.nodes[node][1]) < 1e-12:
        return node
    other = f.node(x_mm, z_mm)
    f.beam(node, other, STIFF, STIFF, np.inf)
    return other


def frame_drop_um_per_N(g, m, cap_rigid: bool, plate_rigid: bool, offsets: bool = True) -> float:
    """The cap centre's drop, um/N, of the top layer's half cell (module docstring) over the
    locked layer below it; ``cap_rigid``, ``plate_rigid``: that member (and the root springs
    into it) RIGID times stiffer."""
    s = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    head = lp.layer_supports(s, theta, t, h)[1]
    factors = (RIGID if rigid else 1.0 for rigid in (cap_rigid, plate_rigid))
    return cell_frame_drop_um_per_N(s, theta[-1], t[-1], h[-1], head[-1], head[-2], *factors, offsets)


def cell_frame_drop_um_per_N(
    s, th: float, tt: float, hh: float, x_head: float, x_block: float, cap_f: float, plate_f: float,
    offsets: bool = True,
) -> float:  # fmt: skip
    """:func:`frame_drop_um_per_N` of a top layer (theta in rad; t, h, its wall heads' x and the
    closed layer's below, mm) in the scene ``s`` (a model.load_path.MemberScene), the cap's and the
    plate's stiffness (and their roots') times ``cap_f`` and ``plate_f`` (:data:`RIGID`: rigid)."""
    m = chain_members(s, th, tt, hh, offsets)  # the members the chain takes (model.wall_thrust)
    L, root = float(m.L_mm), float(m.root_Nmm_per_rad)
    (EI_c, kGA_c), (EI_p, kGA_p), wall = m.cap, m.plate, m.wall
    # the wall's centre line: foot at t/2, side vertex at h/2, head at h - t/2 (the plate's top z = 0)
    z_foot, z_head, e_cap, e_plate = float(m.z_foot_mm), float(m.z_head_mm), m.e_cap_mm, m.e_plate_mm
    f = Frame(TIE_N_PER_MM)
    centre, cap_end = f.node(0.0, z_head + e_cap), f.node(x_head, z_head + e_cap)
    f.beam(centre, cap_end, STIFF, EI_c * cap_f, kGA_c * cap_f)
    f.hold(centre, (0, 2))  # the symmetry plane
    head_node, head_wall = offset_node(f, cap_end, x_head, z_head), f.node(x_head, z_head)
    f.spring(head_node, head_wall, root * cap_f)
    vertex = f.node(x_head + L * np.cos(th), 0.5 * hh)
    foot_wall, foot = f.node(x_head, z_foot), f.node(x_head, z_foot)
    f.beam(head_wall, vertex, *wall)
    f.beam(vertex, foot_wall, *wall)
    f.spring(foot_wall, foot, root * plate_f)
    plate_end = offset_node(f, foot, x_head, z_foot - e_plate)
    block_root = m.block_root_Nmm_per_rad * plate_f
    if x_head > x_block:  # the feet beyond the block's edge: the plate hangs from it
        edge = f.node(x_block, z_foot - e_plate)
        f.beam(plate_end, edge, STIFF, EI_p * plate_f, kGA_p * plate_f)
    else:
        edge = plate_end
    ground = f.node(*f.nodes[edge])
    f.hold(ground)
    f.hold(edge, (0, 1))
    f.spring(edge, ground, block_root)
    return -1e3 * float(f.solve({3 * centre + 1: -0.5})[3 * centre + 1])


def rung_um_per_N(g, m) -> tuple[float, float, float]:
    """The rung's plates alone, cap alone and both (the base rigid), each less every member
    rigid, um/N, layers 1 and 2 locked."""
    opts = {"locked": (0, 1), "member_factor": wp.RIGID_FACTOR}
    rigid = wp.kept_press(g, m, wp.PartOptions(**opts)).drop_mm_per_N
    out = []
    for stiff in (("base", "cap"), ("base", "plate"), ("base",)):
        out.append(1e3 * (wp.kept_press(g, m, wp.PartOptions(**opts, scaled=stiff)).drop_mm_per_N - rigid))
    return out[0], out[1], out[2]


def frame_um_per_N(g, m, offsets: bool) -> tuple[float, float, float]:
    both = frame_drop_um_per_N(g, m, True, True, offsets)
    plate = frame_drop_um_per_N(g, m, True, False, offsets) - both
    cap = frame_drop_um_per_N(g, m, False, True, offsets) - both
    return plate, cap, frame_drop_um_per_N(g, m, False, False, offsets) - both


def bottom_first(g, m) -> bool:
    """Whether the part's layers lock bottom first (the frame's case: layers 1 and 2 locked)."""
    stack = Stack(layer_laws(g.layers, m, "spring"))
    part = Stack(tuple(lp.capped_units(stack.layers, lp.members(g, m))))
    locked = wp.regime_locked(part)
    return len(g.layers) == 3 and len(locked) > 2 and tuple(locked[2]) == (0, 1)


def rows(paths: list[Path], offsets: bool) -> list[dict]:
    out = []
    for path in paths:
        doc, _ = mst.designed(path)
        g, m = doc.geometry(), doc.material
        if not bottom_first(g, m):
            continue
        rung, frame = rung_um_per_N(g, m), frame_um_per_N(g, m, offsets)
        row = {"design": doc.name, "rung": rung, "frame": frame}
        row["rung_extra"] = rung[2] - rung[0] - rung[1]
        row["frame_extra"] = frame[2] - frame[0] - frame[1]
        out.append(row)
        r, f = rung, frame
        print(
            f"| {doc.name} | {r[0]:.2f} / {f[0]:.2f} | {r[1]:.2f} / {f[1]:.2f} | {r[2]:.2f} / {f[2]:.2f} | "
            f"**{row['rung_extra']:+.2f} / {row['frame_extra']:+.2f}** |",
            flush=True,
        )
    return out


def counted_regime3(csv_path: Path, paths: list[Path]):
    """(name, geometry, material, the CSV's regime-3 row, the closed form's now) of each design
    studies/member_closed_form.py counts: layers 1 and 2 locked in the rung and in the closed
    form, the cover landed in neither."""
    import csv

    from studies import member_regimes as mr

    with csv_path.open() as f:
        kept = [r for r in csv.DictReader(f) if r["regime"] == "3" and r["locked"].split() == ["0", "1"]]
    for path in paths:
        doc, _ = mst.designed(path)
        mine = [r for r in kept if r["name"] == doc.name]
        if not mine:
            continue
        g, m = doc.geometry(), doc.material
        now = mr.closed_rows(g, m, Stack(layer_laws(g.layers, m, "spring")))[2]
        if min(float(mine[0]["cover_lands_N"]), now["cover_lands_N"]) < float(mine[0]["regime_to_N"]):
            continue
        yield doc.name, g, m, mine[0], now


def part_with_frame(csv_path: Path, paths: list[Path]) -> None:
    """The closed form's part / the rung's - 1 in regime 3 (:func:`counted_regime3`) without the
    walls' thrust (model.wall_thrust, in the closed form since it went in) and with it, and how
    many are within 5 %."""
    errors: dict[str, list[float]] = {"without the thrust": [], "with it (the model)": []}
    for _, g, m, row, now in counted_regime3(csv_path, paths):
        thrust, printed = 1e3 * model_thrust_mm_per_N(g, m), float(row["printed"])
        errors["without the thrust"].append((now["closed_part"] - thrust) / printed - 1.0)
        errors["with it (the model)"].append(now["closed_part"] / printed - 1.0)
    print("\n| regime 3, closed / rung - 1 | designs | median (least to most) | within 5 % |")
    print("|---|---|---|---|")
    for name, e in errors.items():
        within = sum(abs(v) <= 0.05 for v in e)
        print(f"| {name} | {len(e)} | {statistics.median(e):+.1%} ({min(e):+.1%} to {max(e):+.1%}) | {within} |")


def model_thrust_mm_per_N(g, m) -> float:
    """The walls' thrust the closed form adds past the lock under the top layer, mm/N
    (model.wall_thrust, on the plate under it)."""
    s = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    return float(scene_thrust_mm_per_N(s, theta, t, h, lp.layer_supports(s, theta, t, h)[1])[-1])


def two_roots_um_per_N(g, m) -> float:
    """What the top layer's walls give, um/N, with both roots' springs (model.plate_joint) solved
    together beyond each root alone: the clamped-guided wall with springs k1 at its foot (the
    plate over the closed layer, k / (1 + a) for past_lock's unbalanced root) and k at its head,
    M1 = V (L/k2 + L^2/(2 E'I)) / (L/E'I + 1/k1 + 1/k2), two walls in parallel."""
    s = lp.member_scene(g, m)
    theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
    th, tt, hh = theta[-1], t[-1], h[-1]
    L = float(wall_centreline_length_mm(th, tt, hh))
    EI = s.E_prime_MPa * s.depth_mm * tt**3 / 12.0
    k = float(root_spring_Nmm_per_rad(th, tt, L, s.depth_mm, s.E_prime_MPa))
    k1 = k / (1.0 + LOCKED_FITTED[0])

    def extra(k_foot: float, k_head: float) -> float:  # over both roots rigid, per unit shear
        moment = (L / k_head + L * L / (2.0 * EI)) / (L / EI + 1.0 / k_foot + 1.0 / k_head)
        return moment * L / k_foot + (moment * L * L / 2.0 - L**3 / 6.0) / EI - L**3 / (12.0 * EI)

    alone = extra(k1, np.inf) + extra(np.inf, k)
    return 1e3 * 0.5 * np.cos(th) ** 2 * (extra(k1, k) - alone)


def decompose(csv_path: Path, paths: list[Path]) -> None:
    """Regime 3 over the box: where the closed form's part falls short of the rung, % of the part
    as printed (the layers: L0 less the rung with every member rigid; each member: the closed form
    less the rung with that member alone in TPU; the rest: what the rung's members give together
    beyond each alone, with its sign turned), and the walls' two roots solved together."""
    keys = ("layers", "base", "plates", "cap", "rest", "part", "two roots")
    shares: dict[str, list[float]] = {k: [] for k in keys}
    print("| design | rest, um/N | " + " | ".join(f"{k}, %" for k in keys) + " |")
    print("|---|---|" + "---|" * len(keys))
    for name, g, m, row, now in counted_regime3(csv_path, paths):
        printed = float(row["printed"])
        members = now["closed_base"] + now["closed_plate"] + now["closed_cap"]
        gap = {
            "layers": now["closed_part"] - members - float(row["rigid"]),
            "base": now["closed_base"] - float(row["rung_base"]),
            "plates": now["closed_plate"] - float(row["rung_plate"]),
            "cap": now["closed_cap"] - float(row["rung_cap"]),
            "rest": -float(row["rest"]),
            "part": now["closed_part"] - printed,
            "two roots": two_roots_um_per_N(g, m),
        }
        for k in keys:
            shares[k].append(100.0 * gap[k] / printed)
        print(f"| {name} | {float(row['rest']):.2f} | " + " | ".join(f"{shares[k][-1]:+.1f}" for k in keys) + " |")
    print("| median | | " + " | ".join(f"{statistics.median(shares[k]):+.1f}" for k in keys) + " |")


def chain_cost_s(stacks: int = 1000, repeats: int = 5) -> float:
    """The least time, s, of the chain's four rigid cases over ``stacks`` random top layers in the
    forward design's scene."""
    import time

    doc, _ = mst.designed(Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml")
    s = lp.member_scene(doc.geometry(), doc.material)
    rng = np.random.default_rng(0)
    theta, t = np.radians(rng.uniform(15.0, 60.0, stacks)), rng.uniform(0.4, 1.4, stacks)
    h, head, below = 2.0 * t + rng.uniform(0.5, 2.0, stacks), rng.uniform(10, 13, stacks), rng.uniform(10, 13, stacks)
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        thrust_extra_mm_per_N(s, theta, t, h, head, below)  # the four cases in one call, as the model runs it
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", type=Path, nargs="*", default=[])
    ap.add_argument("--box", type=int, default=0, help="this many of studies/member_regimes.py's sampled designs")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--no-offsets", action="store_true", help="the control: walls meet cap and plate at mid-plane")
    ap.add_argument(
        "--part", type=Path, help="studies/data/member_regimes.csv: the box's regime 3 without the thrust and with"
    )
    ap.add_argument("--decompose", type=Path, help="studies/data/member_regimes.csv: where regime 3 falls short")
    ap.add_argument(
        "--cost", action="store_true", help="the thrust term (the chain's four rigid cases) of 1000 stacks, s"
    )
    args = ap.parse_args()
    if args.cost:
        for n in (1000, 20):
            print(f"the thrust term (four rigid chains), {n} stacks: {1e3 * chain_cost_s(n):.2f} ms (least of 5)")
        return
    if args.part is not None or args.decompose is not None:
        from studies import member_regimes as mr

        with tempfile.TemporaryDirectory() as tmp:
            paths = mr.sampled_designs(Path(tmp), args.box or 40, args.seed)
            (part_with_frame if args.part is not None else decompose)(args.part or args.decompose, paths)
        return
    print("past two locks, um/N, rung / frame:\n")
    print("| design | plates alone | cap alone | both | together less alone |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        paths = list(args.configs)
        if args.box:
            from studies import member_regimes as mr

            paths += mr.sampled_designs(Path(tmp), args.box, args.seed)
        done = rows(paths, not args.no_offsets)
    if len(done) > 1:
        summary(done, "all")
        summary([r for r in done if abs(r["frame"][0] / r["rung"][0] - 1.0) <= 0.2], "plates alone within 20 %")


def summary(done: list[dict], label: str) -> None:
    """The frame's extra over the rung's, median (least to most), of ``done``'s rows."""
    ratio = [r["frame_extra"] / r["rung_extra"] for r in done if r["rung_extra"] > 0.05]
    if ratio:
        print(f"{label}: {len(done)} designs; frame / rung of the extra: median {statistics.median(ratio):.2f} "
              f"({min(ratio):.2f} to {max(ratio):.2f}, of {len(ratio)} with a rung extra over 0.05 um/N)")  # fmt: skip


if __name__ == "__main__":
    main()
