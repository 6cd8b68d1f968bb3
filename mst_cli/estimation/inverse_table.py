"""The one-chip readers' tables (``mst read --estimate offset`` and ``--estimate shear``): the
model's field tabulated once per model over the loads the reader supports, and inverted
directly: a start from the field, then a bounded Gauss-Newton on the table.

The field (Bx, By, Bz) is tabulated on a grid of nodes in the normal force (0 to the last lock)
and two more coordinates (u, v), one force path up the forces per (u, v) node; between nodes it
is trilinear. The table's ``kind`` says what (u, v) are:

* ``offset``: where a press without shear was pressed, x0 over the face's width and y0 over its
  depth (mm), each a :func:`~mst_cli.model.general_load.path_fields_T` path (no slides);
* ``shear``: the tangential force's ratios to the normal one, Fx / Fz and Fy / Fz, of a centred
  press (a friction cone: a box in the ratios), each a
  :func:`~mst_cli.model.general_load.path_fields_T` path; an estimate is given as (Fz, Fx, Fy) =
  (F, u F, v F), its Jacobian carried over by the chain rule before the bound is taken.

The table is inverted directly (the same steps as the C header's, batched here over readings):
the start is the node nearest the reading among the force slabs whose |B| range, widened by k
noise sigmas, holds the reading's |B| (:func:`start_nodes`); from it a bounded Gauss-Newton on
the trilinear field that never climbs (:func:`_gauss_newton`); a second start at that end's
mirror through the middle of (u, v) (:func:`mirror_start`), where a field that folds over has
its other root. An end within k sigma of the reading is a root. The flags are the exact
reader's (:mod:`~mst_cli.estimation.offset_reading`): ``no_fit`` without a root, ``ambiguous``
when two roots lie further apart than twice their combined 1-sigma, ``not_identifiable`` when
the best root's offset 1-sigma is over the bound, else ``ok``. Each root's 1-sigma is the
Cramer-Rao bound of the reading there, sqrt(diag((J^T J / sigma^2)^-1)), J the table's field
Jacobian dB/d(F, x0, y0) and sigma the chip's noise and the table's own interpolation error in
that force slab in quadrature (:meth:`InverseTable.slab_error_uT`; the same sigma widens the
start's slab test and judges the misfit): the stated 1-sigma covers what the table adds.

The arithmetic is written so that the C header (:mod:`~mst_cli.firmware.table_header`) can do
the same steps in float: at most STEPS Gauss-Newton steps on a 3 x 3 system solved by Cramer's rule.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from mst_cli.errors import InputError
from mst_cli.estimation.table_file import MAX_TABLE_BYTES, PARSE_ERRORS, TABLE_KEYS, checked_arrays, npz_arrays
from mst_cli.estimation.table_start import middle_uv, start_nodes
from mst_cli.estimation.trilinear import normal_step, to_output, trilinear
from mst_cli.io.files import read_input
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.general_load import loaded_stack, normal_stack, path_fields_T
from mst_cli.model.load_bound import crb_sigma
from mst_cli.model.material import Material
from mst_cli.model.member_pose import MemberPose
from mst_cli.model.stack_pose import tilt_laws
from mst_cli.parallel import fork_map
from mst_cli.sensor.rung_store import model_source_hash

TABLE_FILE = "inverse_table.npz"  # the offset table's file beside the model ...
SHEAR_TABLE_FILE = "shear_table.npz"  # ... and the shear table's
# bumped when the table's file or its builder change meaning: an older file is rebuilt (4: section
# mode's members; 5: the cover in series outside its layer's contact, the base's sway). A change of
# the model itself needs no bump: its source is in every table's hash (source_hash)
TABLE_FORMAT = 5
FIT_SIGMAS = 3.0  # a cell whose best point is further off the reading than this found no root
# the direct inverse (the C header takes the same numbers): from each start, Gauss-Newton steps on
# the table's trilinear field, from the nearest node of the force slabs the reading's |B| allows
# (start_nodes) and from its end's mirror (mirror_start)
STEPS = 10  # steps at most from the first start (most converge in 2 to 5) ...
SECOND_STEPS = 6  # ... and from the second (a root near the mirror; a walk back to the first root is cut)
STEP_CELLS = 2.0  # a step moves each coordinate by at most this many of its cells
CONVERGED = 1e-4  # a start whose step moved less than this share of a cell has converged: it stops ...
MIN_GAIN = 1e-3  # ... as does one whose step lowered the squared misfit by less than this share of it
STOP_SIGMAS = 0.1  # ... and one whose step would change the field by less than this many noise sigmas
STOP_GAIN = 0.1  # ... and lower the squared misfit by less than this share of it (what is left is noise)
HALVINGS = 3  # a step that does not lower the misfit is halved up to this many times
PROBE = 1e-3  # the share of a step that says which cell it enters (its Jacobian is that cell's)
BLOCK = 4096  # readings per estimate (their starts' corners at a time)

# (forces, mm between offsets): the default grid, 1 mm over the face and the range in 32 steps
# (docs/design.md section 4.2 says what it costs in accuracy against the exact solve: the
# offsets' spacing rules it, 97 forces at 2 mm do no better than 49); a microcontroller's header
# takes every other node of it (TableGrid.every_other)
GRID_DEFAULT = (33, 1.0)
KINDS = ("offset", "shear")
# the shear table's friction cone |Fx / Fz|, |Fy / Fz| <= SHEAR_TABLE_RATIO (a reading beyond it is
# no_fit: TPU on TPU or skin slips near 0.5 to 1) and its (forces, ratio step); the start's scan
# grows with the nodes (docs/design.md section 4.5)
SHEAR_TABLE_RATIO = 0.5
SHEAR_GRID_DEFAULT = (33, 0.05)


Edges = Sequence[float] | np.ndarray | None  # regime edges (N), or none


def force_nodes(force_max_N: float, n_force: int, edges_N: Edges = None) -> np.ndarray:
    """The table's force nodes from 0 to ``force_max_N``: without regime edges, ``n_force``
    evenly spaced; with them (0, R_1, ..., the last lock), every edge a node and the same even
    number of intervals in every regime's band (a multiple of 4), at most ``n_force`` nodes in
    all. Each regime is then resolved as finely as the next (a 0.5 N light-touch band gets as
    many cells as a 20 N one, not a part of one), no cell straddles a lock (the layer laws'
    kinks), and every other node (the C header's table), and every other node of that (what
    :meth:`InverseTable.slab_error_uT` compares with), keep the edges."""
    inner = sorted(float(e) for e in (edges_N if edges_N is not None else ()) if 0.0 < e < force_max_N * (1 - 1e-9))
    if not inner and edges_N is None:
        return np.linspace(0.0, force_max_N, n_force)
    edges = [0.0, *inner, float(force_max_N)]
    per = max(4, 4 * ((n_force - 1) // (4 * (len(edges) - 1))))
    bands = [np.linspace(lo, hi, per + 1)[:-1] for lo, hi in zip(edges[:-1], edges[1:])]
    return np.concatenate([*bands, [float(force_max_N)]])


KNOT_MERGE_REL = 1e-3  # a kink this share of the range from an edge is that edge (no sliver of a band)


def kink_edges_N(laws: Sequence[Any], edges_N: Edges, force_max_N: float) -> np.ndarray:
    """The edges the force nodes follow (:func:`force_nodes`): the regime edges ``edges_N`` and
    every other kink of the centred tilt laws ``laws`` below ``force_max_N``: a layer's own
    knots, and on the whole part a member's (the cover's landing on the board,
    :class:`~mst_cli.model.part_laws.SeriesMember`). Between kinks the centred state is linear
    in the force, so no cell then straddles a change of slope, whose secant would be the
    table's Jacobian there."""
    edges = [float(e) for e in (edges_N if edges_N is not None else ())]
    knots = sorted(float(k) for law in laws for k in law.walls.F_knots_N if 0.0 < k < force_max_N)
    for k in knots:
        if all(abs(k - e) > KNOT_MERGE_REL * force_max_N for e in [*edges, 0.0, force_max_N]):
            edges.append(k)
    return np.array(sorted(edges))


@dataclass(frozen=True)
class TableGrid:
    """Nodes of the table: the normal force N and the coordinates u, v, each ascending (``kind``
    offset: the press's x0 and y0, mm; shear: the ratios Fx / Fz and Fy / Fz)."""

    force_N: np.ndarray
    u: np.ndarray
    v: np.ndarray
    kind: str = "offset"

    @classmethod
    def over(
        cls, geometry: SensorGeometry, force_max_N: float, n_force: int, step_mm: float, edges_N: Edges = None
    ) -> TableGrid:
        """An offset grid: about ``n_force`` forces from 0 to ``force_max_N`` (:func:`force_nodes`);
        x0 and y0 over the whole face, about ``step_mm`` apart (the face's edges are nodes)."""
        hw, hd = 0.5 * geometry.width_mm, 0.5 * geometry.depth_mm
        nx = max(2, int(math.ceil(2 * hw / step_mm)) + 1)
        ny = max(2, int(math.ceil(2 * hd / step_mm)) + 1)
        F = force_nodes(force_max_N, n_force, edges_N)
        return cls(F, np.linspace(-hw, hw, nx), np.linspace(-hd, hd, ny))

    @classmethod
    def cone(cls, force_max_N: float, n_force: int, ratio_max: float, step: float, edges_N: Edges = None) -> TableGrid:
        """A shear grid: about ``n_force`` forces from 0 to ``force_max_N`` (:func:`force_nodes`);
        each ratio from -``ratio_max`` to ``ratio_max``, about ``step`` apart (0 a node)."""
        half = max(1, int(math.ceil(ratio_max / step)))
        ratios = np.linspace(-ratio_max, ratio_max, 2 * half + 1)
        return cls(force_nodes(force_max_N, n_force, edges_N), ratios, ratios.copy(), "shear")

    @property
    def shape(self) -> tuple[int, int, int]:
        return len(self.force_N), len(self.u), len(self.v)

    def every_other(self) -> TableGrid:
        """Every second node on each axis (the ends kept where a count is odd): the C header's
        grid of the default one."""
        return TableGrid(self.force_N[::2], self.u[::2], self.v[::2], self.kind)


@dataclass
class TableEstimates:
    """Per reading: the estimate p (n, 3) (offset: force N, x0 mm, y0 mm; shear: Fz, Fx, Fy N;
    NaN unless ``ok``), its Cramer-Rao 1-sigma (n, 3), the flag (ok, not_identifiable, ambiguous,
    no_fit) and how many distinct roots the direct inverse found (0 to 2: two ends within each
    other's combined 2-sigma count once)."""

    p: np.ndarray
    sigma: np.ndarray
    flag: np.ndarray
    roots: np.ndarray
    best: np.ndarray  # (n, 3) the best root as p (NaN without one), whatever the flag: where a polish starts

    # the offset table's names of p's and sigma's columns (views: writing one writes p)
    @property
    def force_N(self) -> np.ndarray:
        return self.p[:, 0]

    @property
    def x_mm(self) -> np.ndarray:
        return self.p[:, 1]

    @property
    def y_mm(self) -> np.ndarray:
        return self.p[:, 2]

    @property
    def sigma_force_N(self) -> np.ndarray:
        return self.sigma[:, 0]

    @property
    def sigma_x_mm(self) -> np.ndarray:
        return self.sigma[:, 1]

    @property
    def sigma_y_mm(self) -> np.ndarray:
        return self.sigma[:, 2]


@dataclass
class InverseTable:
    """The tabulated field of one model (T, shape (n_F, n_x, n_y, 3)) and what it was built from
    (``source_hash``: the model file, its calibration.json, the mechanics and the grid)."""

    grid: TableGrid
    B_T: np.ndarray
    source_hash: str
    _corners: np.ndarray | None = field(default=None, repr=False, compare=False)
    _slab_error: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def file_name(self) -> str:
        return SHEAR_TABLE_FILE if self.grid.kind == "shear" else TABLE_FILE

    @property
    def size_bytes_float32(self) -> int:
        """The field and the nodes as 4-byte floats (what the C header holds)."""
        return 4 * (self.B_T.size + sum(self.grid.shape))

    def corners_uT(self) -> np.ndarray:
        """Every cell's eight corners (n_cells, 2, 2, 2, 3) in uT, cells in C order of their lowest
        corner (computed once)."""
        if self._corners is None:
            B = self.B_T * 1e6
            nF, nx, ny = (n - 1 for n in self.grid.shape)
            C = np.empty((nF, nx, ny, 2, 2, 2, 3))
            for a in (0, 1):
                for b in (0, 1):
                    for c in (0, 1):
                        C[:, :, :, a, b, c] = B[a : nF + a, b : nx + b, c : ny + c]
            self._corners = C.reshape(-1, 2, 2, 2, 3)
        return self._corners

    def slab_error_uT(self) -> np.ndarray:
        """The table's own interpolation error per force slab (n_F - 1,), uT per axis
        (:func:`_miss_per_slab`). A table of every other node of another knows it: what it
        misses at the other's nodes. Any other table estimates it: trilinear interpolation errs
        as the square of the node spacing, so a quarter of what its table of every other node
        misses at its nodes. The direct inverse takes it as field noise of that slab, in quadrature with
        the chip's: a root within it counts, and the stated 1-sigma covers it (docs/design.md
        section 4.5). 0 where an axis has fewer than 3 nodes."""
        if self._slab_error is None:
            g = self.grid
            if min(g.shape) < 3:
                self._slab_error = np.zeros(len(g.force_N) - 1)
            else:
                half = self.every_other()
                own = np.searchsorted(half.grid.force_N, g.force_N[:-1], side="right") - 1
                self._slab_error = 0.25 * half.slab_error_uT()[np.minimum(own, len(half.grid.force_N) - 2)]
        return self._slab_error

    def every_other(self) -> InverseTable:
        """Every second node on each axis (the ends kept where a count is odd: the default grid's
        nodes give the coarse grid's)."""
        half = InverseTable(self.grid.every_other(), np.ascontiguousarray(self.B_T[::2, ::2, ::2]), self.source_hash)
        half._slab_error = _miss_per_slab(half, self)
        return half

    def save(self, path: Path) -> None:
        with open(path, "wb") as fh:
            self.dump(fh)

    def dump(self, fh: BinaryIO) -> None:
        """The table's npz bytes into the open file ``fh``."""
        np.savez(fh, **self.arrays())

    def arrays(self) -> dict[str, Any]:
        g = self.grid
        return {
            "format": np.array(TABLE_FORMAT),
            "kind": np.array(g.kind),
            "source_hash": np.array(self.source_hash),
            "force_N": g.force_N,
            "u": g.u,
            "v": g.v,
            "B_T": self.B_T,
        }

    @classmethod
    def load(cls, path: Path) -> InverseTable | None:
        """The table in ``path``; None when it is missing or not a good table (:meth:`read`)."""
        return cls.read(path)[0]

    @classmethod
    def read(cls, path: Path) -> tuple[InverseTable | None, str]:
        """(the table in ``path``, "") or (None, why it is not a good table): read as every input
        file is (:func:`~mst_cli.io.files.read_input`: a regular file, at most MAX_TABLE_BYTES),
        parsed without pickles, every array of its kind, shape and finite values checked."""
        try:
            data = read_input(path, MAX_TABLE_BYTES, field=str(path), what="table")
        except InputError as exc:  # "file not found", "is a FIFO (named pipe), not a table: give ..."
            return None, exc.allowed.removeprefix("is ").split(": give")[0]
        try:
            arrays = npz_arrays(data, TABLE_KEYS)
        except PARSE_ERRORS as exc:
            return None, f"not a table ({type(exc).__name__}: {' '.join(str(exc).split())[:80]})"
        try:
            force_N, u, v, kind, B, source = checked_arrays(arrays, TABLE_FORMAT, KINDS)
        except ValueError as exc:
            return None, str(exc)
        return cls(TableGrid(force_N, u, v, kind), B, source), ""

    def estimate(self, B_T: np.ndarray, sigma_T: float, max_sigma_mm: float) -> TableEstimates:
        """Every reading (n, 3) in T, with the chip's noise ``sigma_T`` per axis, BLOCK readings
        at a time (a reading has up to a few hundred candidate cells)."""
        B = np.asarray(B_T, dtype=float).reshape(-1, 3)
        if not len(B):  # every reading flagged before the estimate
            return TableEstimates(
                np.empty((0, 3)), np.empty((0, 3)), np.empty(0, dtype=object), np.empty(0, int), np.empty((0, 3))
            )
        parts = [estimate_many(self, B[i : i + BLOCK], sigma_T, max_sigma_mm) for i in range(0, len(B), BLOCK)]
        if len(parts) == 1:
            return parts[0]
        return TableEstimates(*(np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(TableEstimates)))


def source_hash(model_text: str, calibration_text: str | None, mechanics: str, grid: TableGrid) -> str:
    """What a table depends on, hashed: a table whose hash differs is stale. The physics modules'
    source is part of it (:func:`~mst_cli.sensor.rung_store.model_source_hash`), so a table made
    by another version of the model is never read as current."""
    h = hashlib.sha256()
    for part in (str(TABLE_FORMAT), model_source_hash(), model_text, calibration_text or "", mechanics):
        h.update(part.encode("utf-8"))
        h.update(b"\0")
    h.update(grid.kind.encode("utf-8"))
    for nodes in (grid.force_N, grid.u, grid.v):
        h.update(np.ascontiguousarray(nodes, dtype=float).tobytes())
    return h.hexdigest()


def build_table(
    geometry: SensorGeometry,
    material: Material,
    mechanics: str,
    grid: TableGrid,
    lever_factor: float = 1.0,
    source: str = "",
    whole_part: bool = True,
    members: MemberPose | None = None,
) -> InverseTable:
    """The model's field at every node: one force path per (u, v) node (in worker processes
    where the platform forks; the same numbers either way). ``offset``: the tilt rung's; ``shear``:
    the general load's, pressed at the centre; the part's members with the layers unless
    ``whole_part`` is False (model.load_path: layers), and what the whole-part rung adds to them
    (``members``, model.load_path: section)."""
    nodes = [(float(u), float(v)) for u in grid.u for v in grid.v]
    if grid.kind == "shear":
        stack = loaded_stack(geometry, material, mechanics, lever_factor, whole_part, members)

        def path(node: tuple[float, float]) -> np.ndarray:  # node: (Fx / Fz, Fy / Fz)
            return path_fields_T(stack, grid.force_N, (0.0, 0.0), node)

    else:
        laws = tilt_laws(geometry, material, mechanics, lever_factor, whole_part)
        pressed = normal_stack(geometry, laws, mechanics, members)

        def path(node: tuple[float, float]) -> np.ndarray:  # node: (x0, y0) mm
            return path_fields_T(pressed, grid.force_N, node)

    paths = fork_map(path, nodes)
    if paths is None:
        paths = [path(o) for o in nodes]
    nF, nu, nv = grid.shape
    B = np.stack(paths).reshape(nu, nv, nF, 3).transpose(2, 0, 1, 3)
    return InverseTable(grid, np.ascontiguousarray(B), source)


def _miss_per_slab(coarse: InverseTable, fine: InverseTable) -> np.ndarray:
    """What ``coarse`` misses at ``fine``'s nodes (uT), per coarse force slab: the worst axis at
    each node, RMS over each force's (u, v) nodes, the worst force of the slab (its ends included).
    Tested to cover as a 1-sigma claims (tests/test_light_touch.py: about 70 % of the normal
    force's errors within it, 93 % within two)."""
    g, h = fine.grid, coarse.grid
    pts = np.stack(np.meshgrid(g.force_N, g.u, g.v, indexing="ij"), axis=-1)
    miss = np.max(np.abs(_interpolate(coarse, pts) - 1e6 * fine.B_T), axis=3)  # the worst axis
    per_node = np.sqrt(np.mean(miss**2, axis=(1, 2)))
    k = np.arange(len(h.force_N) - 1)
    within = (g.force_N[None, :] >= h.force_N[k, None]) & (g.force_N[None, :] <= h.force_N[k + 1, None])
    return np.max(within * per_node, axis=1)


def _locate(
    table: InverseTable, p: np.ndarray, toward: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The cell of points p (P, 3) (its flat index, clipped to the table; of the points ``toward``
    when given: the cell a step from p enters), p's coordinates t (P, 3) in it, the cell's widths
    (P, 3) and its force slab (P,)."""
    g = table.grid
    nodes = (g.force_N, g.u, g.v)
    at = p if toward is None else toward
    idx = [np.clip(np.searchsorted(nodes[a], at[:, a], side="right") - 1, 0, len(nodes[a]) - 2) for a in range(3)]
    w = np.stack([nodes[a][idx[a] + 1] - nodes[a][idx[a]] for a in range(3)], axis=1)
    t = np.stack([(p[:, a] - nodes[a][idx[a]]) for a in range(3)], axis=1) / w
    cell = np.ravel_multi_index(tuple(idx), tuple(n - 1 for n in g.shape))
    return cell, t, w, idx[0]


def _interpolate(table: InverseTable, pts: np.ndarray) -> np.ndarray:
    """The table's trilinear field (uT) at points (..., 3) of (F, u, v) inside its grid."""
    flat = pts.reshape(-1, 3)
    cell, t, _, _ = _locate(table, flat)
    return trilinear(table.corners_uT()[cell], t)[0].reshape(*pts.shape[:-1], 3)


def _field(
    table: InverseTable, b: np.ndarray, p: np.ndarray, toward: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """At points p (P, 3), in their cells (:func:`_locate`): the residual b - field (P, 3) uT, its
    square sum (P,), the field's Jacobian in cell coordinates (P, 3, 3), the cells' widths (P, 3)
    and the cells (P,)."""
    cell, t, w, _ = _locate(table, p, toward)
    val, J = trilinear(table.corners_uT()[cell], t)
    r = b - val
    return r, np.sum(r * r, axis=1), J, w, cell


def _held_step(J: np.ndarray, r: np.ndarray, q: np.ndarray, box: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The Gauss-Newton step (cell coordinates) from q (P, 3), a coordinate on the box's face
    whose step would leave it held, at most STEP_CELLS cells per coordinate."""
    dt = normal_step(J, r, np.zeros_like(q, dtype=bool))
    held = ((q <= box[0]) & (dt < 0.0)) | ((q >= box[1]) & (dt > 0.0))
    some = held.any(axis=1)
    if some.any():
        dt[some] = normal_step(J[some], r[some], held[some])
    return np.clip(dt, -STEP_CELLS, STEP_CELLS)


def _worth_trying(J: np.ndarray, dt: np.ndarray, m2: np.ndarray, noise_uT: np.ndarray) -> np.ndarray:
    """Whether steps dt (P, 3) (cell coordinates) are tried: not when the field they would change
    (J dt, uT) is under STOP_SIGMAS of the noise and its square, about the squared misfit they
    would take off, under STOP_GAIN of the misfit m2 (P,) (what is left is noise)."""
    change = np.einsum("pij,pj->pi", J, dt)
    size = np.sum(change * change, axis=1)
    return (size >= (STOP_SIGMAS * noise_uT) ** 2) | (size >= STOP_GAIN * m2)


def _gauss_newton(
    table: InverseTable,
    b: np.ndarray,
    p: np.ndarray,
    noise_uT: np.ndarray,
    joins: np.ndarray | None = None,
    steps: int = STEPS,
) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``steps`` ridged Gauss-Newton steps on the table's trilinear field from starts p (P, 3)
    to readings b (P, 3) uT (:func:`_held_step`), each taken with the Jacobian of the cell it
    enters (from a node or a face, the one whose side it goes to), clamped to the table's box and
    halved up to HALVINGS times until the misfit falls; a start stops when no step lowers it,
    once its step would change the field by less than STOP_SIGMAS of the noise ``noise_uT`` of
    its force slab (n_F - 1,) and lower the squared misfit by less than STOP_GAIN of it (then it
    is not tried: the misfit left is noise, and the step would move each coordinate by less than
    STOP_SIGMAS of its 1-sigma, by Cauchy-Schwarz), once it moves less than CONVERGED of a cell,
    or once it lowers the squared misfit by less than MIN_GAIN of it. With ``joins`` (P, 3), another descent's
    ends: a start stops once it lies within a cell of its end on every axis (it has joined that
    root: it would only walk on to it). The ends (P, 3) and whether each joined."""
    g = table.grid
    box = (np.array([g.force_N[0], g.u[0], g.v[0]]), np.array([g.force_N[-1], g.u[-1], g.v[-1]]))
    r, m2, J, w, cell = _field(table, b, p)
    cells_per_slab = (g.shape[1] - 1) * (g.shape[2] - 1)
    joined = np.zeros(len(p), dtype=bool)
    live = np.arange(len(p))
    for _ in range(steps):
        if not len(live):
            break
        q = p[live]
        dt = _held_step(J[live], r[live], q, box)
        _, _, Jp, wp, cp = _field(table, b[live], q, np.clip(q + PROBE * dt * w[live], *box))
        turn = np.flatnonzero(cp != cell[live])
        if len(turn):
            J[live[turn]], w[live[turn]], cell[live[turn]] = Jp[turn], wp[turn], cp[turn]
            dt[turn] = _held_step(Jp[turn], r[live[turn]], q[turn], box)
        dp = dt * w[live]
        pending = np.flatnonzero(_worth_trying(J[live], dt, m2[live], noise_uT[cell[live] // cells_per_slab]))
        go, took = np.zeros(len(live), dtype=bool), np.zeros(len(live), dtype=bool)
        for h in range(HALVINGS + 1):
            if not len(pending):
                break
            rows = live[pending]
            new = np.clip(q[pending] + 0.5**h * dp[pending], *box)
            rn, m2n, Jn, wn, cn = _field(table, b[rows], new)
            better = m2n < m2[rows]
            done = rows[better]
            gain = m2n[better] < (1.0 - MIN_GAIN) * m2[done]
            moved = np.max(np.abs(new[better] - q[pending[better]]) / w[done], axis=1)
            p[done], r[done], m2[done], J[done], w[done] = new[better], rn[better], m2n[better], Jn[better], wn[better]
            cell[done] = cn[better]
            go[pending[better]] = (moved >= CONVERGED) & gain
            took[pending[better]] = True
            pending = pending[~better]
        if joins is not None:
            near = took & np.all(np.abs(p[live, 1:] - joins[live, 1:]) <= w[live, 1:], axis=1)
            joined[live[near]] = True
            go &= ~near
        live = live[go]
    return p, joined


def mirror_start(grid: TableGrid, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The second start of each end p (P, 3): its (u, v) mirrored through the middle of the table
    (a field symmetric about it, or folding over, has its other root there), and whether it is
    taken (the end lies more than one mean node spacing from the middle)."""
    mid, step = middle_uv(grid)
    far = np.any(np.abs(p[:, 1:] - mid) > step, axis=1)
    return np.column_stack([p[:, 0], 2.0 * mid - p[:, 1:]]), far


def solve_starts(
    table: InverseTable, B_uT: np.ndarray, noise_uT: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The direct inverse of readings (n, 3) uT from both starts: the nearest node
    (:func:`start_nodes`, slot 0) and its end's mirror (:func:`mirror_start`, slot 1, where
    taken): (p (n, 2, 3) in the table's coordinates, NaN for an empty slot; misfit (n, 2) uT, inf
    there; the field Jacobian dB/dp (n, 2, 3, 3) in uT per unit of p; the force slab of each end
    (n, 2))."""
    n = len(B_uT)
    P = np.full((n, 2, 3), np.nan)
    P[:, 0] = start_nodes(table, B_uT, FIT_SIGMAS * noise_uT)
    first = np.flatnonzero(np.isfinite(P[:, 0, 0]))
    P[first, 0] = ends = _gauss_newton(table, B_uT[first], P[first, 0].copy(), noise_uT)[0]
    start, far = mirror_start(table.grid, ends)
    second = first[far]
    P[second, 1], joined = _gauss_newton(table, B_uT[second], start[far], noise_uT, ends[far], SECOND_STEPS)
    P[second[joined], 1] = np.nan  # it joined the first root: no second
    flat = P.reshape(-1, 3)
    rows = np.flatnonzero(np.isfinite(flat[:, 0]))
    cell, t, w, slab = _locate(table, flat[rows])
    val, Jt = trilinear(table.corners_uT()[cell], t)
    misfit = np.full(2 * n, np.inf)
    J = np.zeros((2 * n, 3, 3))
    slabs = np.zeros(2 * n, dtype=int)
    misfit[rows] = np.linalg.norm(np.repeat(B_uT, 2, axis=0)[rows] - val, axis=1)
    J[rows], slabs[rows] = Jt / w[:, None, :], slab
    return P, misfit.reshape(n, 2), J.reshape(n, 2, 3, 3), slabs.reshape(n, 2)


def estimate_many(table: InverseTable, B_T: np.ndarray, sigma_T: float, max_sigma_mm: float) -> TableEstimates:
    """The direct inverse and its flags for readings B_T (n, 3) in T (see the module's
    docstring); the offset's bound ``max_sigma_mm`` on x0 and y0 (the shear table has none: its
    sigmas say)."""
    n, S = len(B_T), 2
    slab_noise = np.hypot(1e6 * sigma_T, table.slab_error_uT())
    p, misfit, J, slab = solve_starts(table, 1e6 * B_T, slab_noise)
    noise = slab_noise[slab]
    root = misfit <= FIT_SIGMAS * noise
    q, Jq = to_output(table.grid.kind, np.nan_to_num(p.reshape(-1, 3)), J.reshape(-1, 3, 3))
    q, sig = q.reshape(n, S, 3), crb_sigma(Jq, noise.ravel()).reshape(n, S, 3)
    # pairs of roots: far when they lie further apart than twice their combined 1-sigma on an axis
    with np.errstate(invalid="ignore"):
        far = np.any(np.abs(q[:, :, None] - q[:, None, :]) > 2.0 * np.hypot(sig[:, :, None], sig[:, None, :]), axis=3)
    pair = root[:, :, None] & root[:, None, :]
    ambiguous = np.any(far & pair, axis=(1, 2))
    earlier = np.tril(np.ones((S, S), dtype=bool), -1)  # [s, r]: r before s
    roots = np.sum(root & ~np.any(pair & ~far & earlier, axis=2), axis=1)
    best = np.argmin(np.where(root, misfit, np.inf), axis=1)
    has = root.any(axis=1)
    i = np.arange(n)
    pb = np.where(has[:, None], q[i, best], np.nan)
    sb = np.where(has[:, None], sig[i, best], np.nan)
    flag = np.full(n, "no_fit", dtype=object)
    flag[has] = "ok"
    if table.grid.kind == "offset":
        flag[has & (np.fmax(sb[:, 1], sb[:, 2]) > max_sigma_mm)] = "not_identifiable"
    flag[ambiguous] = "ambiguous"
    ok = flag == "ok"
    return TableEstimates(np.where(ok[:, None], pb, np.nan), np.where(ok[:, None], sb, np.nan), flag, roots, pb)
