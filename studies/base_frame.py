"""The housing's base as a plane frame under a tangential force: how far the cover slides and how
far its middle turns, with layer 1 open, locked or rigid above it (issue 44, docs/design.md 4.7,
"The base's sway: built").

The frame: the slot's two walls as Timoshenko columns (plane strain, shear factor 5/6) from the
floor's top to the cover's underside, their roots built into the floor (pi/8 E'D w^2, the tilted
flat punch on a half-plane, Johnson 1985, chapter 2) or held; a rigid offset from each column's
top to the cover's end at the wall's inner edge, on the cover's mid-plane; the cover's end built
into it (pi/8 E'D c^2); the cover a beam of two sections, cover + layer 1's pad (open), cover +
h_1 (locked) or rigid (everything above rigid) under |x| < pad, the cover alone beyond. A force
T = 1 N along +x enters at layer 1's wall heads, half at each, with its moment about the cover's
mid-plane (T times the top face's height over it) as a couple at the heads. Printed per design:
the cover's slide at the heads (the mean of the two), its middle's turn (the heads' relative
drop over their distance; counter-clockwise, against the couple, positive), each from the force
alone and with its moment, and mst's column form (model.housing_base.base_sway_mm_per_N). With
--rung, the whole-part rung's base alone with everything above rigid, as printed
(benchmarks/bench_whole_part.py --base-sway).

    python studies/base_frame.py [--rung] [--configs ...]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import housing_base as hb
from mst_cli.model import load_path as lp
from mst_cli.model.plane_frame import element_stiffness

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ("mohammadi2021-forward", "mohammadi2021", "fingertip")
STIFF = 1e6  # a rigid link's factor on E'D
SEGMENTS = 6  # beam elements between stations


def frame_response(scene, pad_mm, head_mm, pad_section_mm, lever_mm, root="joint") -> dict:
    """(slide and turn under the force alone, under its moment alone, together) of the cover at
    layer 1's heads, per newton along +x at the top face ``lever_mm`` over the cover's mid-plane."""
    s = scene
    E, G, D, c, L2, H = s.E_prime_MPa, s.G_MPa, s.depth_mm, s.cover_mm, s.half_slot_mm, s.slot_height_mm
    nodes, elements, joints, held = [], [], [], []

    def node(x, z):
        nodes.append((x, z))
        return len(nodes) - 1

    ends = []
    for sign, w in zip((-1.0, 1.0), s.slot_wall_widths_mm):
        root_node, top = node(sign * (L2 + 0.5 * w), 0.0), node(sign * (L2 + 0.5 * w), H)
        elements.append((root_node, top, E * w * D, E * D * w**3 / 12.0, 5.0 / 6.0 * G * w * D))
        edge = node(sign * L2, H + 0.5 * c)
        elements.append((top, edge, STIFF * E * D, STIFF * E * D, math.inf))
        held += [3 * root_node, 3 * root_node + 1]
        if root == "held":
            held.append(3 * root_node + 2)
        else:
            joints.append((root_node, None, hb.END_BUILT_IN * E * D * w * w))
        ends.append(edge)
    stations = sorted({-L2, L2, 0.0, *(v for v in (-pad_mm, pad_mm, -head_mm, head_mm) if abs(v) < L2)})
    xs = [x for a, b in zip(stations[:-1], stations[1:]) for x in np.linspace(a, b, SEGMENTS + 1)[:-1]]
    beam = [node(x, H + 0.5 * c) for x in [*xs, stations[-1]]]
    for a, b in zip(beam[:-1], beam[1:]):
        thick = c + pad_section_mm if abs(0.5 * (nodes[a][0] + nodes[b][0])) < pad_mm else c
        elements.append((a, b, E * thick * D, E * D * thick**3 / 12.0, 5.0 / 6.0 * G * thick * D))
    for edge, end in zip(ends, (beam[0], beam[-1])):
        joints.append((edge, end, hb.END_BUILT_IN * E * D * c * c))
    K = np.zeros((3 * len(nodes), 3 * len(nodes)))
    for a, b, EA, EI, kGA in elements:
        dofs = [3 * a, 3 * a + 1, 3 * a + 2, 3 * b, 3 * b + 1, 3 * b + 2]
        K[np.ix_(dofs, dofs)] += element_stiffness(nodes[a], nodes[b], EA, EI, kGA)
    for a, b, k_turn in joints:  # the ends' positions tied, their turns through the spring
        for d, k in ((0, STIFF * E * D), (1, STIFF * E * D), (2, k_turn)):
            if b is None:
                K[3 * a + d, 3 * a + d] += k if d == 2 else 0.0
                continue
            i, j = 3 * a + d, 3 * b + d
            K[np.ix_([i, j], [i, j])] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    free = np.setdiff1d(np.arange(3 * len(nodes)), held)
    heads = [beam[int(np.argmin([abs(nodes[b][0] - x) for b in beam]))] for x in (-head_mm, head_mm)]
    span = nodes[heads[1]][0] - nodes[heads[0]][0]

    def solve(load) -> tuple[float, float]:
        u = np.zeros(3 * len(nodes))
        u[free] = np.linalg.solve(K[np.ix_(free, free)], load[free])
        return 0.5 * (u[3 * heads[0]] + u[3 * heads[1]]), (u[3 * heads[1] + 1] - u[3 * heads[0] + 1]) / span

    force, couple = np.zeros(3 * len(nodes)), np.zeros(3 * len(nodes))
    force[[3 * h for h in heads]] = 0.5
    couple[3 * heads[1] + 1], couple[3 * heads[0] + 1] = 1.0 / span, -1.0 / span  # 1 N mm counter-clockwise
    (u_f, t_f), (u_m, t_m) = solve(force), solve(couple)
    # the force along +x at the top face: its moment about the cover is clockwise
    return {"slide": (u_f, -lever_mm * u_m, u_f - lever_mm * u_m), "turn": (t_f, -lever_mm * t_m, t_f - lever_mm * t_m)}


def rung_slide_mm_per_N(geometry, material) -> float:
    """The whole-part rung's cover slide, the base alone as printed, everything above it rigid."""
    import mst_cli.model.mechanics.whole_part as wp  # deferred: scikit-fem's rung

    rigid_above = ("layer", "plate", "cap", "insert", "magnet")
    x = wp.press_general(geometry, material, wp.PartOptions(member_factor=wp.RIGID_FACTOR, scaled=rigid_above))
    z_magnet = geometry.z_magnet_bottom_mm + 0.5 * geometry.magnet.thickness_mm
    return x.pull.side_mm_per_N + x.pull.turn_rad_per_N * (z_magnet - geometry.z_base_top_mm)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--configs", nargs="*", default=[str(ROOT / "configs" / f"{n}.yaml") for n in CONFIGS])
    ap.add_argument("--rung", action="store_true", help="also the whole-part rung's base, everything above rigid")
    args = ap.parse_args()
    print("per newton along +x at the top face: the cover's slide at layer 1's heads, mm/N (force alone, its moment")
    print("alone, both) and its middle's turn, mrad/N (counter-clockwise, against the force's moment, positive)")
    print("| design | above the cover | roots | slide | turn | mst's columns | rung, above rigid |")
    print("|---|---|---|---|---|---|---|")
    for path in args.configs:
        doc, _ = mst.designed(path)
        g, m = doc.geometry(), doc.material
        s = lp.member_scene(g, m)
        first = g.layers[0]
        pad, head, _, _ = lp.layer_supports(s, math.radians(first.theta_deg), first.t_mm, first.h_mm)
        lever = g.total_height_mm - (g.z_cover_bottom_mm + 0.5 * s.cover_mm)
        rung = f"{rung_slide_mm_per_N(g, m):.4f}" if args.rung else "-"
        columns = hb.base_sway_mm_per_N(s)
        for label, section in (("layer 1 open", first.t_mm), ("layer 1 locked", first.h_mm), ("rigid", 1e3)):
            for root in ("joint", "held"):
                r = frame_response(s, float(pad), float(head), section, lever, root)
                slide = " / ".join(f"{v:.4f}" for v in r["slide"])
                turn = " / ".join(f"{1e3 * v:+.2f}" for v in r["turn"])
                rung_cell = rung if label == "rigid" and root == "joint" else ""
                print(
                    f"| {doc.name} | {label} | {root} | {slide} | {turn} | {columns:.4f} | {rung_cell} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
