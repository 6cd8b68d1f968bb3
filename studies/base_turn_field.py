"""Where the plane frame's base turns the stack back less than the whole-part rung's, under a
tangential pull before the first lock (issue 44; docs/design.md 4.7, "The base's turn under a
pull, field by field").

Prints, for each design (regime 1, the layers in TPU, the plates and the cap rigid):

1. the magnet's turn per tangential newton on the rung with the base as printed, its cover rigid,
   its slot walls rigid and every member rigid (the base's share is each less the last);
2. the rung's cover and wall tops, fitted as rigid pieces through the cover's thickness in
   windows 0.22 mm wide across x: turn (mrad/N, counter-clockwise from x to z), rise and slide
   (um/N), near the slot's edges and
   at the centre;
3. the frame's nodes on the cover's mid-plane and the slot walls' tops (model.plate_sway, the base
   alone in TPU): the same three.

    PYTHONPATH=. .venv/bin/python studies/base_turn_field.py configs/mohammadi2021-forward.yaml [more.yaml]

About 30 s a design (four rung solves, kept in mst's cache after the first run).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model import plate_sway as ps
from mst_cli.model.mechanics import whole_part as wp
from mst_cli.model.plane_frame import Frame

CASES = (("base as printed", ""), ("its cover rigid", "cover"), ("its slot walls rigid", "slot_walls"))


def rung_pull(g, m, rigid_base: str | None):
    """(mesh points (n, 2), their displacement (n, 2), the magnet's turn) per newton of the pull."""
    from skfem import condense, solve

    if rigid_base is None:
        opts = wp.PartOptions(member_factor=wp.RIGID_FACTOR)
    else:
        opts = wp.PartOptions(member_factor=wp.RIGID_FACTOR, scaled=("plate", "cap"), rigid_base=rigid_base)
    mesh, tag, element, basis, K, held = wp._system(g, m, opts)
    f = wp._load(g, mesh, element, opts.patch_mm, tangential=True)
    is_z = np.zeros(basis.N, dtype=bool)
    is_z[basis.nodal_dofs[1]] = True
    is_z[basis.facet_dofs[1]] = True
    u = solve(*condense(K, f / (g.depth_mm * f[~is_z].sum()), D=held))
    points = np.stack([u[basis.nodal_dofs[0]], u[basis.nodal_dofs[1]]], axis=1)
    return mesh.p.T, points, wp._motion(g, basis, tag, u, opts, 0.0).turn_rad_per_N


def stations_mm(half_slot_mm: float) -> np.ndarray:
    edge = np.arange(half_slot_mm - 1.5, half_slot_mm + 1.71, 0.2)
    return np.concatenate([-edge[::-1], [0.0], edge])


def rung_profile(xz, u, stations, z_top_mm: float, cover_mm: float) -> list:
    rows = []
    for x0 in stations:
        sel = (np.abs(xz[:, 0] - x0) < 0.11) & (xz[:, 1] > z_top_mm - cover_mm - 1e-6) & (xz[:, 1] < z_top_mm + 1e-6)
        rows.append(wp.rigid_fit(xz[sel], u[sel]) if sel.sum() >= 3 else None)
    return rows


def frame_nodes(sec) -> list[str]:
    """The frame's nodes at or under the cover's mid-plane, the base alone in TPU (the pull)."""
    got: dict = {}
    solve_cases = Frame.solve_cases

    def keep(self, cases):
        u = solve_cases(self, cases)
        got["u"], got["nodes"] = u[0], np.array(self.nodes)
        return u

    Frame.solve_cases = keep  # type: ignore[method-assign]
    try:
        ps.frame_response(sec, (), -1, ps.wall_factors(sec))
    finally:
        Frame.solve_cases = solve_cases  # type: ignore[method-assign]
    u, nodes = got["u"], got["nodes"]
    z_cover = ps._beam_z_mm(sec)[0]
    lines = []
    for i, (x, z) in enumerate(nodes):
        if z <= z_cover + 1e-9 and z > 0.5 * z_cover and (abs(x) > sec.half_slot_mm - 1.0 or abs(x) < 1e-9):
            turn, rise, slide = 1e3 * u[3 * i + 2], 1e3 * u[3 * i + 1], 1e3 * u[3 * i]
            lines.append(f"| {x:+.3f} | {z:.2f} | {turn:+.2f} | {rise:+.1f} | {slide:+.1f} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("configs", nargs="+", type=Path)
    args = ap.parse_args()
    for path in args.configs:
        doc, _ = mst.designed(path)
        g, m = doc.geometry(), doc.material
        s = lp.member_scene(g, m)
        walls = ", ".join(f"{w:.2f}" for w in s.slot_wall_widths_mm)
        print(f"\n## {doc.name}: slot edge at |x| = {s.half_slot_mm:.2f} mm, walls {walls} mm, cover {s.cover_mm} mm")
        _, _, rigid_turn = rung_pull(g, m, None)
        stations = stations_mm(s.half_slot_mm)
        profiles = {}
        print("\n| rung | magnet's turn per tangential N, mrad/N | less all rigid |\n|---|---|---|")
        for label, rigid_base in CASES:
            xz, u, turn = rung_pull(g, m, rigid_base)
            profiles[label] = rung_profile(xz, u, stations, g.z_base_top_mm, s.cover_mm)
            print(f"| {label} | {1e3 * turn:+.3f} | {1e3 * (turn - rigid_turn):+.3f} |")
        print("\n| x, mm | " + " | ".join(f"{label}: turn, up, slide" for label, _ in CASES) + " |")
        print("|---|" + "---|" * len(CASES))
        for k, x0 in enumerate(stations):
            cells = []
            for label, _ in CASES:
                fit = profiles[label][k]
                cells.append("" if fit is None else f"{1e3 * fit[2]:+.1f}, {1e3 * fit[1]:+.1f}, {1e3 * fit[0]:+.1f}")
            print(f"| {x0:+.1f} | " + " | ".join(cells) + " |")
        print("\n| frame node x, mm | z, mm | turn, mrad/N | up, um/N | slide, um/N |\n|---|---|---|---|---|")
        print("\n".join(frame_nodes(ps.stack_section(g, m))))


if __name__ == "__main__":
    main()
