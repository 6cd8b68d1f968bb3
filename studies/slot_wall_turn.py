"""What the cover and the slot's walls give together, against the closed form's turn of the walls
(issue 44, docs/design.md 4.7, "The closed form over the design box"). A diagnosis on a CSV of
studies/member_regimes.py; no rung solves.

On the rung, the base in TPU gives more than its cover alone (the walls rigid) and its walls
alone (the cover rigid) by what the two do together: the walls turn under the cover's end. The
closed form's ``load_path.housing_mm_per_N`` turns a wall as a column free to sway (k = E'I/H),
loaded at its inner edge. This fits, over the regime-1 rows whose layer 1 stands over the slot,
a variant with three constants: the column's turn stiffness c_k E'I/H (4: held from swaying by
the cover, which ties the two walls), the load's lever on its top a w/2 (1/3: a triangle of
pressure), and the cover's end turning into the wall's top, a spring c_r E'D c^2 (c the cover's
thickness: an end built into a body of the same modulus) in series with the column.

    PYTHONPATH=. .venv/bin/python studies/slot_wall_turn.py studies/data/member_regimes.csv --designs 40 --seed 1 \
        --check studies/data/member_regimes_bundled.csv

Beside each design it prints the cover alone on the rung (the walls rigid) against the closed
form's cover clamped at the slot's edges and layer 1's roots turning into the cover, which the
closed form lacks (taken as model.plate_joint takes them on a plate).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.beams import plain_section, section_EI_kGA
from mst_cli.model.plate_joint import root_joint_mm_per_N
from studies import member_regimes as mr

C_K = (1.0, 2.0, 4.0, 8.0, 16.0)  # the grid searched
LEVER = tuple(np.linspace(0.0, 1.0, 11))
C_R = (0.0, 0.2, 0.4, 0.8, 1.6)  # 0: no spring at the cover's end


def together_um_per_N(scene, head_mm: float, pad_mm: float, t_bottom_mm: float, c_k: float, lever: float, c_r: float):
    """The variant's extra drop of the walls' turn, um/N: load_path.housing_mm_per_N's virtual
    work over the cover's half span (the same C_j and B), the walls' turn with the constants,
    less the cover clamped on rigid walls (module docstring)."""
    s, P = scene, 0.5
    E, G, D, H, L2 = s.E_prime_MPa, s.G_MPa, s.depth_mm, s.slot_height_mm, s.half_slot_mm
    EI_in, _ = section_EI_kGA(D, s.cover_mm + t_bottom_mm, E, G)
    EI_out, _ = plain_section(D, s.cover_mm, E, G)
    e, x_pad = max(L2 - head_mm, 0.0), min(max(L2 - pad_mm, 0.0), L2)

    def over_half_span(j: int) -> float:
        at_pad = min(x_pad, e) ** (j + 1) / (j + 1) + e**j * max(x_pad - e, 0.0)
        return at_pad / EI_out + (min(L2, e) ** (j + 1) / (j + 1) + e**j * max(L2 - e, 0.0) - at_pad) / EI_in

    B, C1, C2 = (over_half_span(j) for j in range(3))
    drops = []
    for w in s.slot_wall_widths_mm:
        k = c_k * E * D * w**3 / 12.0 / H
        if c_r > 0.0:
            k = 1.0 / (1.0 / k + 1.0 / (c_r * E * D * s.cover_mm**2))
        arm = lever * 0.5 * w
        M = (P * C1 - P * arm / k) / (B + 1.0 / k)
        drops.append(P * C2 - M * C1 + 0.5 * w * (P * arm + M) / k)
    return 1e3 * (float(np.mean(drops)) - (P * C2 - P * C1 * C1 / B))


def over_slot_rows(path: Path, designs: int, seed: int) -> list[tuple]:
    """(name, cover mm, scene, layer 1's wall heads, outer pad and t, the rung's together, the
    rung's cover alone, the closed form's cover clamped on rigid walls, layer 1's roots turning
    into the cover as model.plate_joint takes them on a plate; um/N) of the CSV's regime-1 rows
    whose layer 1 stands over the slot (sampled designs rebuilt from the seed, others from
    configs/<name>.yaml)."""
    with path.open() as f:
        rows = {r["name"]: r for r in csv.DictReader(f) if r["regime"] == "1"}
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        sampled = {p.stem: p for p in mr.sampled_designs(Path(tmp), designs, seed)}
        for name, r in rows.items():
            doc, _ = mst.designed(sampled.get(name, mr.ROOT / "configs" / f"{name}.yaml"))
            g, m = doc.geometry(), doc.material
            s = lp.member_scene(g, m)
            theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
            pad, head, _, _ = lp.layer_supports(s, theta, t, h)
            together = float(r["rung_base"]) - float(r["rung_cover"]) - float(r["rung_slot_walls"])
            if s.half_slot_mm > head[0] and together > 0.0:
                clamped = sum(lp.cover_parts_mm_per_N(replace(s, slot_height_mm=0.0), t[0], pad[0], head[0]))
                roots = root_joint_mm_per_N(theta[0], t[0], h[0], s.cover_mm, s.depth_mm, s.E_prime_MPa)
                cover = (float(r["rung_cover"]), 1e3 * float(clamped), 1e3 * float(roots))
                out.append((name, s.cover_mm, s, float(head[0]), float(pad[0]), float(t[0]), together, *cover))
    return out


def errors(data: list[tuple], c: tuple) -> list[float]:
    """log(variant / rung) of the walls' turn with the constants ``c`` per row of ``data``."""
    return [math.log(max(together_um_per_N(d[2], d[3], d[4], d[5], *c), 1e-9) / d[6]) for d in data]


def table(data: list[tuple], variants: tuple) -> None:
    """Per design: the rung's together and each variant's error; the cover alone on the rung
    against the closed form's clamped cover and the roots it lacks."""
    print(
        "| design | cover, mm | rung, um/N | "
        + " | ".join(label for label, _ in variants)
        + " | cover alone: rung / beam + roots |"
    )
    print("|---" * (4 + len(variants)) + "|")
    for d in data:
        cells = " | ".join(f"{math.expm1(errors([d], c)[0]):+.0%}" for _, c in variants)
        print(f"| {d[0]} | {d[1]:g} | {d[6]:.2f} | {cells} | {d[7]:.2f} / {d[8]:.2f} + {d[9]:.2f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", type=Path, help="a CSV of studies/member_regimes.py")
    ap.add_argument("--designs", type=int, default=0, help="how many designs its run sampled")
    ap.add_argument("--seed", type=int, default=1, help="and its seed")
    ap.add_argument("--check", type=Path, help="another such CSV (e.g. the bundled designs'): the same constants on it")
    args = ap.parse_args()
    data = over_slot_rows(args.csv, args.designs, args.seed)

    def rms(c: tuple) -> float:
        return math.sqrt(float(np.mean(np.square(errors(data, c)))))

    today, derived = (1.0, 1.0, 0.0), (4.0, 1.0 / 3.0, 0.0)
    best = min(itertools.product(C_K, LEVER, C_R), key=rms)
    print(f"{len(data)} designs with layer 1 over the slot; rms of log(variant / rung):")
    variants = (("today", today), ("held, triangle", derived), ("best", best))
    for label, c in variants:
        print(f"  {label} (c_k {c[0]:g}, lever {c[1]:.2f}, c_r {c[2]:g}): {rms(c):.3f}")
    table(data, variants)
    if args.check is not None:
        print(f"\n{args.check}, the same constants:")
        table(over_slot_rows(args.check, 0, args.seed), variants)


if __name__ == "__main__":
    main()
