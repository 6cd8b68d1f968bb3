"""Seeded random sensors inside the design bounds, shared by the CAD and check sweeps."""

import numpy as np

from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.board_slots import slot_violations
from mst_cli.model.cell import HexCell
from mst_cli.model.components import BOARDS


def random_valid_geometries(n, seed, max_offset_mm):
    """n buildable sensors of 1-3 valid layers, random depth (whole 0.2 mm layers), board and
    chip offset (|x|, |y| <= max)."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        depth = 0.2 * int(rng.integers(80, 151))  # 16-30 mm
        cells = tuple(
            HexCell(
                float(rng.uniform(15, 60)), float(rng.uniform(0.4, 2.0)), float(rng.uniform(1.2, 6.0)), depth_mm=depth
            )
            for _ in range(int(rng.integers(1, 4)))
        )
        if any(c.violations() for c in cells):
            continue
        board = BOARDS[sorted(BOARDS)[int(rng.integers(len(BOARDS)))]]
        offset = tuple(float(v) for v in rng.uniform(-max_offset_mm, max_offset_mm, size=2))
        g = SensorGeometry(cells, board=board, chip_offset_mm=offset)
        if g.housing_violations() or slot_violations(g):  # buildable: its board slot inside the face
            continue
        out.append(g)
    return out
