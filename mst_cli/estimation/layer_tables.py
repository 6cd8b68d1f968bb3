"""Every layer's tilt-rung state (d, phi_y, phi_x) tabulated over the normal force and where it
is pressed, (F, |ox|, |oy|), and read trilinearly with its gradient: the fast two-chip reader's
guess of the states (:mod:`mst_cli.estimation.two_chip_table`, whose docstring says how far the
guess is from the exact states and how they are made exact).

The cell is mirror symmetric in x and y: d is even in both offsets, phi_y odd in ox, phi_x odd in
oy, so a quadrant of nodes holds it all.

Pure: no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mst_cli.estimation.trilinear import trilinear
from mst_cli.model.general_load import LoadedStack
from mst_cli.model.mechanics.tilt import LayerTiltLaw
from mst_cli.model.stack_pose import stack_path
from mst_cli.parallel import fork_map


@dataclass(frozen=True)
class LayerTable:
    """One layer's state (d mm, phi_y rad, phi_x rad) on nodes (force N, |ox| mm, |oy| mm), all
    ascending from 0; (n_F, n_x, n_y, 3)."""

    force_N: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    state: np.ndarray

    def at(self, force_N: np.ndarray, ox_mm: np.ndarray, oy_mm: np.ndarray) -> np.ndarray:
        """(m, 3) the state by trilinear interpolation (linear extrapolation past the nodes),
        the tilts' signs from the offsets' (the mirror symmetries)."""
        return self.read(force_N, ox_mm, oy_mm, gradient=False)[0]

    def read(
        self, force_N: np.ndarray, ox_mm: np.ndarray, oy_mm: np.ndarray, gradient: bool = True
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """((m, 3) the state as :meth:`at`, (m, 3, 3) its exact gradient in (force, ox, oy)
        inside each cell (the forward side on a face; None without ``gradient``))."""
        (i, u, hu), (j, v, hv), (k, w, hw) = [
            _cell(nodes, val)
            for nodes, val in ((self.force_N, force_N), (self.x_mm, np.abs(ox_mm)), (self.y_mm, np.abs(oy_mm)))
        ]
        _, nx, ny, _ = self.state.shape
        corners = np.array([(a * nx + b) * ny + c for a in (0, 1) for b in (0, 1) for c in (0, 1)])
        C = self.state.reshape(-1, 3)[((i * nx + j) * ny + k)[:, None] + corners].reshape(-1, 2, 2, 2, 3)
        out, grad = trilinear(C, np.column_stack([u, v, w]))
        sx, sy = np.where(ox_mm < 0.0, -1.0, 1.0), np.where(oy_mm < 0.0, -1.0, 1.0)
        sign = np.column_stack([np.ones_like(sx), sx, sy])  # the state's and the offsets' mirror signs
        out *= sign
        if not gradient:
            return out, None
        return out, grad / np.column_stack([hu, hv, hw])[:, None, :] * sign[:, :, None] * sign[:, None, :]


def _cell(nodes: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(the index of the cell holding each v, the share of the way across it, its width), end
    cells taking what lies past the nodes."""
    i = np.clip(np.searchsorted(nodes, v, side="right") - 1, 0, len(nodes) - 2)
    width = nodes[i + 1] - nodes[i]
    return i, (v - nodes[i]) / width, width


def _nodes(half_mm: float, step_mm: float) -> np.ndarray:
    """From 0 to ``half_mm``, about ``step_mm`` apart, both ends nodes."""
    return np.linspace(0.0, half_mm, max(2, int(math.ceil(half_mm / step_mm)) + 1))


def _force_nodes(law: LayerTiltLaw, force_max_N: float, n_force: int) -> np.ndarray:
    """``n_force`` forces from 0 to ``force_max_N`` and the layer law's knots among them: the
    centred state is piecewise linear in the force, its kinks at the knots."""
    knots = law.walls.F_knots_N[(law.walls.F_knots_N > 0.0) & (law.walls.F_knots_N < force_max_N)]
    return np.unique(np.concatenate([np.linspace(0.0, force_max_N, n_force), knots]))


def _path_task(task: tuple[LayerTiltLaw, np.ndarray, float, float]) -> np.ndarray:
    """(n_F, 3) one layer's state up the forces at one offset."""
    law, F, ox, oy = task
    d, tilt = stack_path([law], F, (ox, oy))
    return np.column_stack([d[:, 0], tilt[:, 0, :]])


def layer_tables(
    stack: LoadedStack, force_max_N: float, ratio_max: float, n_force: int, step_mm: float
) -> list[LayerTable]:
    """Every layer's table, its offsets over the face widened by its lever x ``ratio_max`` (one
    force path per offset node, in forked workers where the platform allows)."""
    g = stack.geometry
    grids = []
    tasks = []
    for law, lever in zip(stack.tilt, stack.lever_mm):
        F = _force_nodes(law, force_max_N, n_force)
        xs = _nodes(0.5 * g.width_mm + lever * ratio_max, step_mm)
        ys = _nodes(0.5 * g.depth_mm + lever * ratio_max, step_mm)
        grids.append((F, xs, ys))
        tasks += [(law, F, float(x), float(y)) for x in xs for y in ys]
    paths = fork_map(_path_task, tasks)
    if paths is None:
        paths = [_path_task(t) for t in tasks]
    out, at = [], 0
    for F, xs, ys in grids:
        block = np.stack(paths[at : at + len(xs) * len(ys)]).reshape(len(xs), len(ys), len(F), 3)
        out.append(LayerTable(F, xs, ys, np.ascontiguousarray(block.transpose(2, 0, 1, 3))))
        at += len(xs) * len(ys)
    return out
