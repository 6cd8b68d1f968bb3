"""A starting design built layer by layer: the match decomposed along the physics.

The targets pin one layer each, given the gap:

* R_j is layer j's own lock force: it depends on layer j's cell alone;
* the stack is in series, so in regime i (layers below i locked, i and above still free) the
  compression grows by the sum of the layers' increments over [R_(i-1), R_i]. The targets
  S_i fix |B| at every regime edge, B_i = B0 (1 + sum_(m<=i) S_m (R_m - R_(m-1))); the field
  model, inverted, turns that into the gap at every edge and so into the stack compression
  D_i the regime must add. Of that, the free layers above i take their share (known once
  they are chosen: the loop runs from the top layer down), the locked ones below take
  dF / k_locked (small), and layer i takes the rest.

On the whole part (``model.load_path: part``) the members add to every regime: the cap bends
into the top layer's cavity and each plate into the cavity of the layer under it until it
closes (a layer's lock force and increments are its capped law's), and the cover adds its
compliance x dF. A plate depends on the two layers it joins (the one above is chosen first)
and the cover on layer 1, so each layer's candidates are weighed with the members they make
given the layers already chosen (exact once the passes stop changing).

So each layer is a two-target, three-variable choice from one table of cells evaluated once
(a grid over the unit box of (theta, t, h), the same for every layer): the cell nearest to
(R_i, its increment) in log terms among those that meet every per-layer rule. The gap depends
on the total height, so the pass repeats with the gap of the cells just chosen. The table costs
one kernel call whatever the layer count, and the loop is O(n) small lookups: this replaces a
blind search in 3n dimensions, whose cost grows with the dimension, with n searches in three.

The result is a start, not a design: the knee of the L0 law, the lower layers' locked
compliance and the grid spacing leave a few per cent, which the local solver removes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from mst_cli.design.problem import TINY
from mst_cli.model.housing_base import cover_parts_both_mm_per_N
from mst_cli.model.load_path import cap_mm_per_N, layer_supports, plates_mm_per_N
from mst_cli.model.mechanics.spring import layer_displacement_mm
from mst_cli.model.past_lock import over_two_locked_mm_per_N, plate_overhang_mm_per_N, upper_layer_terms
from mst_cli.model.plate_joint import joint_scene, plates_beside, root_joint_mm_per_N
from mst_cli.model.stack import capped_lock_force_N, contact_drop_mm
from mst_cli.model.wall_thrust import thrust_on_block, top_chain

if TYPE_CHECKING:
    from mst_cli.design.problem import DesignProblem

GRID = (13, 25, 25)  # table points along theta, t, h (normalised, uniform in u)
PASSES = 8  # at most; the passes stop when no layer changes its cell
FIELD_GRID = 512  # gaps on which |B| is tabulated for the inversion


def grid_within(max_cells: float, grid: tuple[int, int, int] = GRID) -> tuple[int, int, int]:
    """``grid`` shrunk evenly along every axis (at least 3 points each) to hold at most
    ``max_cells`` cells: a small evaluation budget gets a coarser table, not none."""
    scale = min(1.0, (max(max_cells, 27.0) / float(np.prod(grid))) ** (1.0 / 3.0))
    a, b, c = (max(3, int(k * scale)) for k in grid)
    return a, b, c


def table_units(grid: tuple[int, int, int] = GRID) -> np.ndarray:
    """Normalised cells (count, 3) of the table, theta slowest."""
    axes = [np.linspace(0.0, 1.0, k) for k in grid]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


class CellTable:
    """The L0 law and per-layer feasibility of every table cell (one kernel call)."""

    def __init__(self, problem: DesignProblem, slack: float, grid: tuple[int, int, int] = GRID):
        u = table_units(grid)
        theta, t, h = problem.cell_to_physical(u)
        ok = np.all(problem.layer_constraints(theta, t, h) + slack <= 0.0, axis=-1)
        k, d_lock, R, k_locked = problem.layer_laws(theta[ok], t[ok], h[ok])
        self.u = u[ok]
        self.theta_deg, self.t_mm, self.h_mm = theta[ok], t[ok], h[ok]
        self.k, self.d_lock, self.R, self.k_locked = k, d_lock, R, k_locked
        self.cells = len(u)
        self.whole_part = problem.whole_part
        self._supports: tuple | None = None  # (t as printed, layer_supports) of the cells, for members_with
        # members_with's members by the cells they rest on (the start's passes repeat them) and
        # the cells' own compression by force: the same arrays, each computed once
        self._members: dict[tuple, np.ndarray] = {}
        self._own: dict[float, np.ndarray] = {}

    def displacement_mm(
        self, force_N: float, cap_mm_per_N: np.ndarray | float = 0.0, capped_lock_N: np.ndarray | None = None
    ) -> np.ndarray:
        """Compression of every table cell at ``force_N``, the plate or cap above it bending into
        its cavity by ``cap_mm_per_N`` (cells,) until it closes there (its capped law);
        ``capped_lock_N``: :meth:`capped_lock_N` of that cap, when the caller has it."""
        own = self._own.get(force_N)
        if own is None:
            own = self._own[force_N] = layer_displacement_mm(force_N, self.k, self.d_lock, self.R, self.k_locked)
        return capped_mm(force_N, self.k, self.d_lock, self.R, self.k_locked, cap_mm_per_N, capped_lock_N, own)

    def capped_lock_N(self, cap_mm_per_N: np.ndarray) -> np.ndarray:
        """Every cell's lock force under a plate or cap bending into its cavity by ``cap_mm_per_N``."""
        return capped_lock_force_N(self.k, self.d_lock, self.R, cap_mm_per_N)

    def increment_mm(self, cell: int, F0: float, F1: float, cap_mm_per_N: float) -> float:
        """One cell's compression from F0 to F1 under its plate or cap (its capped law)."""
        law = (self.k[cell], self.d_lock[cell], self.R[cell], self.k_locked[cell])
        return float(capped_mm(F1, *law, cap_mm_per_N) - capped_mm(F0, *law, cap_mm_per_N))

    def _locked_plate(self, scene, j: int, at, cell, member) -> np.ndarray:
        """The plate over layer j - 1, locked in layer j's regime, under layer j's cells (j > 0),
        model.past_lock: what layer j's cells give it once a run, then only how far their feet
        overhang; over two blocks when layer j - 2 is locked too (the targets rise)."""
        assert self._supports is not None  # members_with computed them
        t, _, head, _, _ = self._supports
        theta_rad, G = np.radians(self.theta_deg), scene.G_MPa
        upper = member(("upper",), lambda: upper_layer_terms(theta_rad, t, self.h_mm, *joint_scene(scene), G))
        if j >= 2:
            return member(
                ("two locked", cell(j - 2), cell(j - 1), cell(j)), lambda: self._over_two(scene, j, at, upper)
            )
        overhang = lambda: plate_overhang_mm_per_N(head - at(head, j - 1), upper)  # noqa: E731
        return member(("locked", cell(j - 1), cell(j)), overhang)

    def _cover_drop(self, problem: DesignProblem, on_bottom: tuple, at, cell, member):
        """The cover's drop (cells,) at a force F under layer 1's cells ``on_bottom`` (t, pad,
        head, theta, h), model.stack.members_drop_mm's: its bending over the slot stopped on the
        board, both rates changing at layer 1's lock, taken at its target (the targets rise)."""
        scene, cells = problem.members, len(self.u)
        both = member(("cover", cell(0)), lambda: cover_parts_both_mm_per_N(scene, *on_bottom))  # one open beam
        (over, walls), (over_l, walls_l) = ((np.broadcast_to(a, (cells,)) for a in pair) for pair in both)
        cover, air, R1 = over + walls, scene.cover_air_mm, problem.R_target[0]
        delta = over_l + walls_l - cover

        def cover_mm(F: float) -> np.ndarray:
            moved = contact_drop_mm(F, R1, over, over_l)
            return cover * F + delta * max(F - R1, 0.0) - np.maximum(moved - air, 0.0)

        return cover_mm

    def _over_two(self, scene, j: int, at, upper: tuple) -> np.ndarray:
        """Plate j - 1 over locked layers j - 2 and j - 1 under layer j's cells (model.past_lock
        .over_two_locked_mm_per_N), ``at`` picking each layer's cells, ``upper`` the table's terms."""
        assert self._supports is not None  # members_with computed them
        t, _, head, _, _ = self._supports
        three = lambda a: np.stack(np.broadcast_arrays(at(a, j - 2), at(a, j - 1), a), axis=-1)  # noqa: E731
        args = (three(t), three(self.h_mm), three(head), *joint_scene(scene), scene.G_MPa, upper)
        return over_two_locked_mm_per_N(*args)

    def members_with(self, problem: DesignProblem, chosen: np.ndarray, j: int) -> tuple:
        """(each layer's cap (cells, n): the plate above it, the cap on the top one; the cover's
        drop (cells,) at a force, its bending over the slot stopped on the board; the plate over
        layer j - 1 while it is locked, model.past_lock (cells,)) of the stacks ``chosen`` with
        every table cell in place of layer ``j``; zeros on the layers alone.

        :meth:`DesignProblem.part_members` of those stacks, bit for bit (elementwise kernels),
        at a fraction of its cost: a member rests on one layer or two, so only the members on
        layer j are computed over the table's cells, the others once, from the table's
        :func:`~mst_cli.model.load_path.layer_supports` (computed on the first call)."""
        cells, n = len(self.u), len(chosen)
        if not self.whole_part:
            return np.zeros((cells, n)), lambda F: np.zeros(cells), np.zeros(cells)
        if self._supports is None:
            t = problem.printed_t_mm(self.t_mm)
            self._supports = (t, *layer_supports(problem.members, np.radians(self.theta_deg), t, self.h_mm))
        t, pad, head, walls, sway = self._supports

        def at(a: np.ndarray, i: int) -> np.ndarray:  # layer i's: every cell at j, the chosen one elsewhere
            return a if i == j else a[chosen[i] : chosen[i] + 1]

        def cell(i: int) -> int:  # the key of layer i's cells: -1 the table's, else the chosen one
            return -1 if i == j else int(chosen[i])

        def member(key: tuple, compute):  # a member depends on the cells it rests on alone
            value = self._members.get(key)
            if value is None:
                value = self._members[key] = compute()
            return value

        scene = problem.members
        theta_rad, top = np.radians(self.theta_deg), n - 1
        on_bottom = tuple(at(a, 0) for a in (t, pad, head, theta_rad, self.h_mm))  # t, pad, head, theta, h
        on_top = tuple(at(a, top) for a in (t, head, walls, theta_rad, self.h_mm))
        cap = member(("cap", cell(top)), lambda: cap_mm_per_N(scene, *on_top))
        plates = [
            member(
                ("plate", cell(i), cell(i + 1)),
                lambda i=i: plates_mm_per_N(
                    scene, at(t, i), at(t, i + 1), at(head, i), at(head, i + 1), at(sway, i), at(sway, i + 1)
                ),
            )
            for i in range(n - 1)
        ]
        # each layer's joints with the plates beside it (model.plate_joint): its own cells alone
        beside = plates_beside(n)
        one = member(("joint",), lambda: root_joint_mm_per_N(theta_rad, t, self.h_mm, *joint_scene(scene)))
        joints = [at(one, i) * beside[i] for i in range(n)]
        caps = np.stack(np.broadcast_arrays(*plates, cap), axis=-1) + np.stack(np.broadcast_arrays(*joints), axis=-1)
        locked = self._locked_plate(scene, j, at, cell, member) if j > 0 else np.zeros(cells)
        if j == top and j > 0:  # the top layer's walls' thrust on that plate (model.wall_thrust)
            chain = member(("top chain",), lambda: top_chain(scene, theta_rad, t, self.h_mm, head))
            thrust = lambda: thrust_on_block(chain, at(head, j - 1))  # noqa: E731
            locked = locked + member(("thrust", cell(j - 1), cell(j)), thrust)
        cover_mm = self._cover_drop(problem, on_bottom, at, cell, member)
        return caps, cover_mm, np.broadcast_to(locked, (cells,))


def capped_mm(force_N, k, d_lock, R, k_locked, cap_mm_per_N, Rc=None, own=None) -> np.ndarray:
    """L0 layers' compression at ``force_N`` with the plate or cap above each bending into its
    cavity by ``cap_mm_per_N`` until it closes there (the layers' own law where C = 0); ``Rc``
    (their capped lock forces) and ``own`` (their own law's compression), when the caller has them."""
    own = layer_displacement_mm(force_N, k, d_lock, R, k_locked) if own is None else own
    C = np.asarray(cap_mm_per_N, dtype=float)
    Rc = capped_lock_force_N(k, d_lock, R, C) if Rc is None else Rc
    return np.where(C > 0, np.where(force_N <= Rc, own + C * force_N, d_lock + (force_N - Rc) / k_locked), own)


def _edge_gaps_mm(problem: DesignProblem, gap0_mm: float) -> np.ndarray | None:
    """Gap at F = 0, R*_1, ..., R*_n that makes |B| follow the S targets (None: out of reach)."""
    R = np.concatenate([[0.0], problem.R_target])
    rise = np.concatenate([[0.0], np.cumsum(problem.S_target * np.diff(R))])
    gaps = np.linspace(gap0_mm, 1e-3 * gap0_mm, FIELD_GRID)  # closing: |B| should rise
    B = problem.field_T(gaps)
    rising = np.concatenate([[True], np.diff(B) > 0.0])
    stop = int(np.argmin(rising)) if not rising.all() else len(B)
    B, gaps = B[:stop], gaps[:stop]
    want = B[0] * (1.0 + rise)
    if stop < 2 or want[-1] > B[-1]:
        return None
    return np.interp(want, B, gaps)


def _layer_choice(
    problem: DesignProblem,
    table: CellTable,
    chosen: np.ndarray,
    j: int,
    F: np.ndarray,
    increment_mm: float,
    terms: dict,
) -> int:
    """The table cell for layer j nearest (R_j, the compression its regime must add, of which the
    layers above, the locked ones below and the members take their share), the layers above it
    chosen; ``terms`` keeps what depends on the plate or cap above layer j alone (over the table)."""
    n, dF = problem.n, F[j + 1] - F[j]
    caps, cover, locked = table.members_with(problem, chosen, j)  # the layers above j: already chosen
    key = (j, int(chosen[j + 1]) if j < n - 1 else -1)  # the cells the plate or cap above j rests on
    if key not in terms:
        R_capped = table.capped_lock_N(caps[:, j])
        own = table.displacement_mm(F[j + 1], caps[:, j], R_capped) - table.displacement_mm(F[j], caps[:, j], R_capped)
        lock = np.log(np.maximum(R_capped, TINY))
        terms[key] = (lock - np.log(problem.R_target[j])) ** 2, np.log(np.maximum(own, TINY))
    lock_miss, log_own = terms[key]
    above = sum(table.increment_mm(chosen[m], F[j], F[j + 1], caps[0, m]) for m in range(j + 1, n))
    below = sum(dF / table.k_locked[chosen[m]] for m in range(j))
    members = cover(F[j + 1]) - cover(F[j]) + locked * dF
    need = np.maximum(increment_mm - above - below - members, 1e-3 * increment_mm)
    return int(np.argmin(lock_miss + (log_own - np.log(need)) ** 2))


def seed_start(problem: DesignProblem, slack: float, table: CellTable | None = None) -> tuple[np.ndarray | None, int]:
    """(normalised start (3n,) built layer by layer, candidate stacks evaluated for it; the
    table's cells not counted). The start is None when the targets give the decomposition
    nothing to work with: lock targets not increasing, a field rise the magnet cannot give, no
    cell meeting the per-layer rules."""
    R_target = problem.R_target
    if np.any(np.diff(R_target) <= 0.0) or np.any(problem.S_target <= 0.0):
        return None, 0
    table = table if table is not None else CellTable(problem, slack)
    if len(table.u) == 0:
        return None, 0
    n = problem.n
    F = np.concatenate([[0.0], R_target])
    log_R = np.log(np.maximum(table.R, TINY))
    # first guess: each layer's lock force alone; the passes then add the field's demands
    chosen = np.argmin(np.abs(log_R[None, :] - np.log(R_target)[:, None]), axis=1)
    for j in range(n - 1, -1, -1):  # then each layer's capped lock force, the layers above it chosen
        C = table.members_with(problem, chosen, j)[0][:, j]
        R_capped = capped_lock_force_N(table.k, table.d_lock, table.R, C)
        chosen[j] = int(np.argmin(np.abs(np.log(np.maximum(R_capped, TINY)) - np.log(R_target[j]))))
    # the passes may end in a cycle (a layer swapping between two cells): a pass from a start
    # made before gives the same choices, and a layer's terms under the same plate or cap the same
    candidates: list[np.ndarray] = []
    passes: dict[bytes, np.ndarray] = {}
    terms: dict[tuple, tuple] = {}
    for _ in range(PASSES):
        before = chosen.copy()
        if before.tobytes() in passes:
            chosen = passes[before.tobytes()].copy()
        else:
            gaps = _edge_gaps_mm(problem, float(problem.gap0_mm(table.h_mm[chosen].sum())))
            if gaps is None:
                break
            stack_increment = -np.diff(gaps)  # D_i - D_(i-1), i = 1..n
            for j in range(n - 1, -1, -1):
                chosen[j] = _layer_choice(problem, table, chosen, j, F, stack_increment[j], terms)
            passes[before.tobytes()] = chosen.copy()
        candidates.append(table.u[chosen].reshape(-1))
        if np.array_equal(chosen, before):
            break
    if not candidates:
        return None, 0
    U = np.array(candidates)
    return U[int(np.argmin(problem.evaluate(U).merit(slack)))], len(U)
