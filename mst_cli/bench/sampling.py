"""The seeded sample of valid cells every ladder measurement draws from (``mst bench``, the L0
fits, the tilt rung's check)."""

from __future__ import annotations

import numpy as np

from mst_cli.model.cell import HexCell
from mst_cli.model.mechanics.correction import VERIFIED_BOX

BOUNDS = VERIFIED_BOX


def sample_cells(
    n: int, seed: int = 0, max_t_over_L: float = np.inf, bounds: dict | None = None, min_t_over_L: float = 0.0
) -> list[HexCell]:
    """n valid cells drawn uniformly in (theta, t, h) inside ``bounds`` (default BOUNDS) by
    rejection sampling: HexCell.violations() empty -- the only filter by default. The t/L
    window [min_t_over_L, max_t_over_L] (default: none) and narrower ``bounds`` are for
    experiments and for topping up sparse corners of the box in the L0 fit."""
    bounds = {**BOUNDS, **(bounds or {})}
    rng = np.random.default_rng(seed)
    out: list[HexCell] = []
    while len(out) < n:
        th, t, h = (rng.uniform(*bounds[k]) for k in ("theta_deg", "t_mm", "h_mm"))
        c = HexCell(round(float(th), 3), round(float(t), 3), round(float(h), 3))
        if not c.violations() and min_t_over_L <= c.t_mm / c.wall_length_mm <= max_t_over_L:
            out.append(c)
    return out
