"""The base under a closed layer 1, in closed form: tried, not built (docs/design.md 4.7, "Member
by member with the closed form of today").

Once layer 1 is closed the whole-part rung's base (the cover over the board's slot and the slot
walls) is 1.7-1.9 times stiffer than the closed form, which keeps its open-layer figure. The trial:
``load_path.housing_mm_per_N`` with the cover's section under layer 1's pad deepened by the closed
layer (cover + h_1 instead of cover + t_1), loaded at layer 1's wall heads as before. Prints the
closed form's base now and with the trial, um/N, against which the rung's figures in the docs stand
(``benchmarks/bench_whole_part.py --attribute``: 24.8, 24.1, 15.3 on the three designs).

    PYTHONPATH=. .venv/bin/python studies/base_past_lock.py   (a few seconds)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import mst_cli as mst
from mst_cli.model import load_path as lp
from mst_cli.model.beams import plain_section, section_EI_kGA

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ("mohammadi2021.yaml", "fingertip.yaml", "mohammadi2021-forward.yaml")


def main() -> None:
    print("| design | base now, um/N | base, layer 1 closed (cover + h_1), um/N |")
    print("|---|---|---|")
    for name in CONFIGS:
        doc, _ = mst.api.designed(ROOT / "configs" / name)
        g, m = doc.geometry(), doc.material
        s = lp.member_scene(g, m)
        theta, t, h = (np.array([getattr(c, k) for c in g.layers]) for k in lp.CELL_KEYS)
        pad, head, _, _ = lp.layer_supports(s, theta, t, h)
        now = sum(lp.cover_parts_mm_per_N(s, t[0], pad[0], head[0]))
        deep = section_EI_kGA(s.depth_mm, s.cover_mm + h[0], s.E_prime_MPa, s.G_MPa)
        closed = sum(
            lp.housing_mm_per_N(s, head[0], pad[0], deep, plain_section(s.depth_mm, s.cover_mm, s.E_prime_MPa, s.G_MPa))
        )
        print(f"| {doc.name} | {1e3 * now:.2f} | {1e3 * closed:.2f} |")


if __name__ == "__main__":
    main()
