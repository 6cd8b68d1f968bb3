"""Every layer's tilt-rung state (d, phi_y, phi_x) tabulated over the normal force and where it
is pressed, (F, |ox|, |oy|), and read trilinearly with its gradient: the fast two-chip reader's
guess of the states (:mod:`mst_cli.estimation.two_chip_table`, whose docstring says how far the
guess is from the exact states and how they are made exact).

The cell is mirror symmetric in x and y: d is even in both offsets, phi_y odd in ox, phi_x odd in
oy, so a quadrant of nodes holds it all.

Read in a compiled loop (numba), a load at a time: the fit reads every layer's table at every load
it tries, and numpy's array calls cost several times the arithmetic on these shapes (issue 45).

Pure: no I/O.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

import numpy as np
from numba import njit

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
        F = np.ascontiguousarray(force_N, dtype=float).ravel()
        ox = np.ascontiguousarray(ox_mm, dtype=float).ravel()
        oy = np.ascontiguousarray(oy_mm, dtype=float).ravel()
        out, grad = np.empty((len(F), 3)), np.empty((len(F), 3, 3))
        _read_rows(self.force_N, self.x_mm, self.y_mm, self.state, F, ox, oy, out, grad)
        return out, (grad if gradient else None)


@njit(cache=True, nogil=True)
def _cell(nodes, v):  # pragma: no cover - compiled
    """(the index of the cell holding v, the share of the way across it, its width), end cells
    taking what lies past the nodes (linear extrapolation)."""
    lo, hi = 0, len(nodes)
    while lo < hi:  # searchsorted, side right
        mid = (lo + hi) // 2
        if nodes[mid] <= v:
            lo = mid + 1
        else:
            hi = mid
    i = min(max(lo - 1, 0), len(nodes) - 2)
    width = nodes[i + 1] - nodes[i]
    return i, (v - nodes[i]) / width, width


@njit(cache=True, nogil=True)
def _read_rows(force_N, x_mm, y_mm, state, F, ox, oy, out, grad):  # pragma: no cover - compiled
    """out (m, 3), grad (m, 3, 3): the trilinear state and its gradient in (F, ox, oy) of every
    load, the tilts' signs from the offsets' (phi_y odd in ox, phi_x odd in oy, d even in both)."""
    sign = np.empty(3)
    for r in range(len(F)):
        i, u, hu = _cell(force_N, F[r])
        j, v, hv = _cell(x_mm, abs(ox[r]))
        k, w, hw = _cell(y_mm, abs(oy[r]))
        sign[0], sign[1], sign[2] = 1.0, (-1.0 if ox[r] < 0.0 else 1.0), (-1.0 if oy[r] < 0.0 else 1.0)
        for c in range(3):
            c000, c001 = state[i, j, k, c], state[i, j, k + 1, c]
            c010, c011 = state[i, j + 1, k, c], state[i, j + 1, k + 1, c]
            c100, c101 = state[i + 1, j, k, c], state[i + 1, j, k + 1, c]
            c110, c111 = state[i + 1, j + 1, k, c], state[i + 1, j + 1, k + 1, c]
            # along w, then v, then u; each derivative the difference of the faces' bilinear values
            c00, c01 = c000 + (c001 - c000) * w, c010 + (c011 - c010) * w
            c10, c11 = c100 + (c101 - c100) * w, c110 + (c111 - c110) * w
            c0, c1 = c00 + (c01 - c00) * v, c10 + (c11 - c10) * v
            value = c0 + (c1 - c0) * u
            d_u = c1 - c0
            d_v = (c01 - c00) + ((c11 - c10) - (c01 - c00)) * u
            lo_w = (c000 + (c010 - c000) * v) + ((c100 + (c110 - c100) * v) - (c000 + (c010 - c000) * v)) * u
            hi_w = (c001 + (c011 - c001) * v) + ((c101 + (c111 - c101) * v) - (c001 + (c011 - c001) * v)) * u
            d_w = hi_w - lo_w
            out[r, c] = value * sign[c]
            grad[r, c, 0] = d_u / hu * sign[c]
            grad[r, c, 1] = d_v / hv * sign[c] * sign[1]
            grad[r, c, 2] = d_w / hw * sign[c] * sign[2]


TABLES_FORMAT = 2  # bump when the tables' build or file form changes: every kept file turns stale


def tables_key(stack: LoadedStack, force_max_N: float, ratio_max: float, n_force: int, step_mm: float) -> str:
    """The hash of everything :func:`layer_tables` reads: each layer's tilt law (its walls' knots
    and slopes, lever, depth and pads), the stack's levers, the face, and the nodes asked for. A
    kept file with another key is stale."""
    h = hashlib.sha256(f"layer-tables {TABLES_FORMAT} {n_force} {step_mm!r} {ratio_max!r}".encode())
    numbers = [force_max_N, stack.geometry.width_mm, stack.geometry.depth_mm, *np.ravel(stack.lever_mm)]
    for law in stack.tilt:
        w = law.walls
        numbers += [w.k_tension_N_per_mm, w.k_after_N_per_mm, law.lever_mm, law.depth_mm]
        numbers += [law.pad_half_width_mm, law.pad_gap_mm, law.pad_stiffness_N_per_mm, len(w.d_knots_mm)]
        numbers += [*w.d_knots_mm, *w.F_knots_N]
        if law.member is not None:  # the cover in series (model.mechanics.tilt.MemberInSeries)
            member = law.member
            numbers += [len(member.F_knots_N), *member.F_knots_N, *member.drop_mm, member.rate_after_mm_per_N]
            numbers += [*member.moment_gain_after]
    h.update(np.asarray(numbers, dtype=float).tobytes())
    return h.hexdigest()


def _nodes(half_mm: float, step_mm: float) -> np.ndarray:
    """From 0 to ``half_mm``, about ``step_mm`` apart, both ends nodes."""
    return np.linspace(0.0, half_mm, max(2, int(math.ceil(half_mm / step_mm)) + 1))


def _force_nodes(law: LayerTiltLaw, force_max_N: float, n_force: int) -> np.ndarray:
    """``n_force`` forces from 0 to ``force_max_N`` and the layer law's knots among them (its
    member's too): the centred state is piecewise linear in the force, its kinks at the knots."""
    knots = law.walls.F_knots_N if law.member is None else np.concatenate([law.walls.F_knots_N, law.member.F_knots_N])
    knots = knots[(knots > 0.0) & (knots < force_max_N)]
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
