"""The first start of the one-chip tables' direct inverse (:mod:`~mst_cli.estimation.inverse_table`,
and the C header's, the same steps): the node nearest the reading among the force slabs its |B|
allows, the distances in integers (an int16 copy of the field in the header), and the middle of
(u, v) where the second start is mirrored. Batched over readings; no I/O."""

from __future__ import annotations

from typing import Protocol

import numpy as np


class GridLike(Protocol):
    """The nodes of a table (:class:`~mst_cli.estimation.inverse_table.TableGrid`)."""

    @property
    def force_N(self) -> np.ndarray: ...

    @property
    def u(self) -> np.ndarray: ...

    @property
    def v(self) -> np.ndarray: ...


class TableLike(Protocol):
    """A table's nodes and field in T (:class:`~mst_cli.estimation.inverse_table.InverseTable`,
    which imports this module)."""

    @property
    def grid(self) -> GridLike: ...

    @property
    def B_T(self) -> np.ndarray: ...


def slab_babs_uT(table: TableLike) -> tuple[np.ndarray, np.ndarray]:
    """Each force slab's |B| range over its nodes (both force ends, every (u, v)): (lo, hi), each
    (n_F - 1,) uT. A trilinear field's size is at most its corners' largest."""
    babs = np.linalg.norm(1e6 * table.B_T, axis=3).reshape(len(table.grid.force_N), -1)
    lo, hi = babs.min(axis=1), babs.max(axis=1)
    return np.minimum(lo[:-1], lo[1:]), np.maximum(hi[:-1], hi[1:])


START_LEVELS = 16383  # the start's integer field: |value| <= this, so that a difference fits 15 bits
# and a squared distance (three squares) 32 unsigned bits: the C header's search is integer, cheap
# on a Cortex-M0+ without an FPU, and Python's is the same integers (the same node, ties too)
START_HEADROOM = 1.25  # the integer field spans this times the table's largest field component


def start_quantum_uT(table: TableLike) -> float:
    """The start search's field unit (uT, a float32 value as the C header holds it): the table's
    largest field component, with START_HEADROOM, over START_LEVELS."""
    return float(np.float32(START_HEADROOM * 1e6 * np.max(np.abs(table.B_T)) / START_LEVELS))


def start_field(B_uT: np.ndarray, quantum_uT: float) -> np.ndarray:
    """Fields (..., 3) uT as the start search's integers (rounded half up, clamped to
    +-START_LEVELS), in float64: exact, as every distance between them is."""
    return np.clip(np.floor(B_uT / quantum_uT + 0.5), -START_LEVELS, START_LEVELS)


def start_index(table: TableLike) -> tuple[int, np.ndarray]:
    """The C header's index of the same search (its result is :func:`start_nodes`', exactly): the
    axis whose integer field spreads the most, and the nodes (flat, C order) sorted by their
    integer field on it (ties in C order). The header scans outward from the reading's place in
    that order and stops on each side once the axis alone is further than the nearest node so
    far: a few hundred nodes instead of every node of the allowed slabs."""
    field = start_field(1e6 * table.B_T, start_quantum_uT(table)).reshape(-1, 3)
    axis = int(np.argmax(np.std(field, axis=0)))
    return axis, np.argsort(field[:, axis], kind="stable")


def start_nodes(table: TableLike, B_uT: np.ndarray, margin_uT: np.ndarray) -> np.ndarray:
    """The first start of each reading (n, 3) uT: the node nearest it (least squared distance in
    the integer units of :func:`start_field`, the first in C order on a tie) among the nodes of
    every force slab whose |B| range, widened by ``margin_uT`` (n_F - 1,: the root test's
    FIT_SIGMAS of the slab's noise), holds the reading's |B| (a field within that of the reading lies in no other
    slab: | |b| - |B| | <= |b - B|); NaN where no slab holds it; on the no-load face, where every
    (u, v) gives the same field, the middle of (u, v). Force node by force node, each against the
    readings it may hold (the distances by a matrix product of integers held in float64: exact)."""
    g = table.grid
    lo, hi = slab_babs_uT(table)
    babs = np.linalg.norm(B_uT, axis=1)[:, None]
    slab = (babs >= lo - margin_uT) & (babs <= hi + margin_uT)
    take = np.zeros((len(B_uT), len(g.force_N)), dtype=bool)
    take[:, :-1] |= slab
    take[:, 1:] |= slab
    quantum = start_quantum_uT(table)
    field = start_field(1e6 * table.B_T, quantum).reshape(len(g.force_N), -1, 3)
    reading = start_field(B_uT, quantum)
    size2 = np.sum(field * field, axis=2)
    best = np.full(len(B_uT), np.inf)
    node = np.full(len(B_uT), -1)
    for k in range(len(g.force_N)):
        rows = np.flatnonzero(take[:, k])
        if not len(rows):
            continue
        b = reading[rows]
        d2 = size2[k][None, :] - 2.0 * (b @ field[k].T)  # the squared distance less |b|^2 (a product)
        j = np.argmin(d2, axis=1)
        near = d2[np.arange(len(rows)), j] + np.sum(b * b, axis=1)
        better = near < best[rows]
        best[rows[better]], node[rows[better]] = near[better], k * field.shape[1] + j[better]
    nodes = np.stack(np.meshgrid(g.force_N, g.u, g.v, indexing="ij"), axis=-1).reshape(-1, 3)
    out = np.where((node >= 0)[:, None], nodes[np.maximum(node, 0)], np.nan)
    out[out[:, 0] == g.force_N[0], 1:] = middle_uv(g)[0]  # no load: every (u, v) has its field
    return out


def middle_uv(grid: GridLike) -> tuple[np.ndarray, np.ndarray]:
    """The middle of the table's (u, v) box (the first start's) and its mean node spacing."""
    mid = np.array([0.5 * (grid.u[0] + grid.u[-1]), 0.5 * (grid.v[0] + grid.v[-1])])
    return mid, np.array([(grid.u[-1] - grid.u[0]) / (len(grid.u) - 1), (grid.v[-1] - grid.v[0]) / (len(grid.v) - 1)])
