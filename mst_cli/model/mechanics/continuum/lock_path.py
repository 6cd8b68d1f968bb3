"""Following a contact problem's load path to its lock, the layer's small-strain stiffness, and
the result of a solve (:class:`ContinuumResult`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy.sparse.linalg import splu

from mst_cli.model.mechanics.continuum.assembly import smallest_stretch
from mst_cli.model.mechanics.continuum.mesh import PRODUCTION_MESH, MeshOptions
from mst_cli.model.mechanics.continuum.problem import ContactProblem
from mst_cli.model.mechanics.path import LAW_CHORD_TOL_REL, PathTolerances, StepControl, follow_to_event
from mst_cli.parallel import one_blas_thread

if TYPE_CHECKING:
    from mst_cli.model.cell import HexCell
    from mst_cli.model.material import Material

# Contact is searched up to this multiple of the rigid-pad stroke h - 2t - allowance (the
# elastic pads under stiff walls meet up to ~5 % late; beyond this the solve is an error).
D_MAX_OVER_NOMINAL = 1.5
# The lock (docs/design.md section 4): the first compression at which the layer's tangent
# stiffness reaches this multiple of its small-load stiffness k. Where a wall is pinched
# between the plate and its mirror, or the pads meet, the tangent jumps 20-80 fold within a
# few micrometres, so the lock force hardly depends on the factor; the gradual stiffening of
# faces zipping shut before that (up to ~2.5 k) stays part of the pre-lock curve.
LOCK_STIFFNESS_FACTOR = 5.0
# the tangent jumps at the lock, so the event is bisected, to 1e-5 of the stroke
LOCK_TOLERANCES = PathTolerances(event_gap_rel=0.0, event_width_rel=1e-5, max_event_iterations=40, bisect=True)


class ContinuumError(RuntimeError):
    """The FE solve did not converge (reported, never returned as a silent number)."""


@dataclass(frozen=True)
class ContinuumResult:
    """Force-displacement of one layer from the FE solve, up to its lock."""

    displacement_mm: np.ndarray  # layer compression d at every converged step
    force_N: np.ndarray  # layer force F at those steps
    k_linear_N_per_mm: float  # small-strain (linear) stiffness, by-product
    d_contact_mm: float  # the lock: where the tangent reaches LOCK_STIFFNESS_FACTOR x k (last sample)
    contact_at: str  # what closed there: "pad" (the pads meet) or "wall" (a wall pinched)
    newton_iterations: int
    n_dofs: int
    reaction_balance: float  # |force across the mirror plane - support reaction| / force
    mesh_scale: float  # k on the refined mesh / k on the path's mesh
    lock_stiffness_ratio: float = math.nan  # tangent / k just past the lock (>= LOCK_STIFFNESS_FACTOR)
    contact_points: np.ndarray | None = None  # surface points in contact at each sample
    min_stretch_at_lock: float = math.nan  # smallest principal stretch on the path's mesh at the lock


def continuum_result(prob, path, k_lin: float, mesh_scale: float, ratio_after: float, n_dofs: int) -> ContinuumResult:
    """The path's samples on ``prob``'s mesh as a ContinuumResult, forces scaled to the refined mesh."""
    return ContinuumResult(
        np.array([0.0] + path.d_mm),
        np.array([0.0] + [F * mesh_scale for F, _, _ in path.observations]),
        k_lin,
        float(path.d_mm[-1]),
        path.event_at,
        path.iterations,
        n_dofs,
        float(path.observations[-1][1]),
        float(mesh_scale),
        float(ratio_after),
        np.array([0] + [n for _, _, n in path.observations]),
        smallest_stretch(prob, path.state.u),
    )


@dataclass(frozen=True)
class _PathPoint:
    """A converged point of the load path: what a solve restarts from, and what the lock test,
    the next step's predictor and the chord's error estimate read."""

    u: np.ndarray  # displacements (N,), mm
    active: np.ndarray | None  # contact points held on their obstacles
    residual: np.ndarray | None  # at u (None at rest)
    d_mm: float
    du_dd: np.ndarray  # the path's tangent
    k_t_N_per_mm: float  # dF/dd
    force: tuple[float, float]  # (F in N, equilibrium imbalance)


class _LockPath:
    """The callbacks :func:`~mst_cli.model.mechanics.path.follow_to_event` drives for one problem."""

    def __init__(self, prob, k_ref_N_per_mm: float, lock_factor: float):
        self.prob, self.k_ref, self.lock_factor = prob, k_ref_N_per_mm, lock_factor

    def point(self, u, active, r, d) -> _PathPoint:
        v, k_t = self.prob.rate(u, active, d)
        return _PathPoint(u, active, r, d, v, k_t, self.prob.force(u, active, r) if r is not None else (0.0, 0.0))

    def solve(self, at: _PathPoint, d: float, depth: int = 0) -> tuple[_PathPoint, int]:
        prob = self.prob
        try:
            try:  # from the path's tangent: first order in the step, Newton starts close
                u, it, active, r = prob._newton(at.u + (d - at.d_mm) * at.du_dd, d, at.active, pads=True)
            except FloatingPointError:  # that start inverts an element or does not converge
                u, it, active, r = prob._newton(at.u, d, at.active, pads=True)
        except FloatingPointError:
            # sub-step from the given point (the event search starts each trial from the
            # bracket's near end, which can be a long step away where a wall is pinched)
            if depth >= 3 or at.residual is None:
                raise
            mid, it0 = self.solve(at, 0.5 * (at.d_mm + d), depth + 1)
            end, it1 = self.solve(mid, d, depth + 1)
            return end, it0 + it1
        return self.point(u, active, r, d), it

    def margin(self, at: _PathPoint, d: float) -> tuple[float, str]:
        # a face pinched between the plate and its mirror, or the pads meeting
        return self.lock_factor - at.k_t_N_per_mm / self.k_ref, _lock_label(self.prob, at.active)

    def guess(self, at: _PathPoint, d_lo: float, d_hi: float) -> float | None:
        """Where in (d_lo, d_hi) the next contact point is expected to touch: each idle point's
        gap over its closing rate along the path's tangent, the earliest (None: none closes
        there). The lock is a contact engaging, so this is where its tangent jumps."""
        prob = self.prob
        idle = ~at.active if at.active is not None else np.ones(prob.contact_dofs.size, bool)
        dofs, sign = prob.contact_dofs[idle], prob.contact_sign[idle]
        penetration = sign * (at.u[dofs] - prob.obstacle(at.d_mm)[idle])  # < 0: a gap
        closing = sign * (at.du_dd[dofs] - prob.obstacle_rate[idle])  # d(penetration)/dd
        ok = closing > 0.0
        touch = at.d_mm - penetration[ok] / closing[ok]
        touch = touch[(touch > d_lo) & (touch < d_hi)]
        return float(touch.min()) if touch.size else None

    @staticmethod
    def chord(at: _PathPoint, d: float, new: _PathPoint, d_new: float) -> float:
        # a quadratic between the two points bows off their chord by (d_new - d) |k_new - k| / 8
        return (d_new - d) * abs(new.k_t_N_per_mm - at.k_t_N_per_mm) / 8.0 / max(abs(new.force[0]), 1e-300)

    @staticmethod
    def observe(at: _PathPoint, d: float) -> tuple[float, float, int]:
        return at.force[0], at.force[1], int(at.active.sum()) if at.active is not None else 0


def follow_to_lock(
    prob: ContactProblem,
    k_ref_N_per_mm: float,
    steps: StepControl | None = None,
    d_max_over_nominal: float = D_MAX_OVER_NOMINAL,
    lock_factor: float = LOCK_STIFFNESS_FACTOR,
) -> tuple:
    """Follow a built problem's load path from rest to its lock (the tangent stiffness reaching
    ``lock_factor`` x ``k_ref_N_per_mm``; LOCK_STIFFNESS_FACTOR but in the studies that vary it),
    then one short step on into the locked branch.

    Works on any problem with L2's interface (``_newton``, ``rate``, ``force``; the 3D check in
    tools/continuum_3d.py reuses it). Steps are kept only while the chord between two points stays within
    ``steps.chord_tol_rel`` (LAW_CHORD_TOL_REL unless given) of the curve. Returns (the
    :class:`~mst_cli.model.mechanics.path.PathResult`, whose observations are (F in N,
    equilibrium imbalance, contact points in contact) and whose state is the lock's
    :class:`_PathPoint`, and the tangent / k just past the lock (nan when that step does not
    converge)). Raises PathError.
    """
    cell = prob.cell
    d_nom = cell.h_mm - 2 * cell.t_mm - cell.contact_allowance_mm  # pads meet here if rigid
    steps = steps or StepControl()
    if steps.chord_tol_rel is None:
        steps = replace(steps, chord_tol_rel=LAW_CHORD_TOL_REL)
    lp = _LockPath(prob, k_ref_N_per_mm, lock_factor)
    # the path's linear algebra is a few hundred banded solves of 500-1200 unknowns (half-band
    # ~43), where OpenBLAS's threads cost more than they give: one thread makes an in-process
    # law about an eighth faster on two cores (benchmarks/l2_cost.py, parts 1 and 2), and
    # makes it the law fork_map's one-thread workers solve
    with one_blas_thread():
        return _follow_path(prob, lp, d_nom, steps, d_max_over_nominal)


def _follow_path(prob, lp: _LockPath, d_nom: float, steps: StepControl, d_max_over_nominal: float) -> tuple:
    """:func:`follow_to_lock`'s path, its callbacks ``lp``, ``d_nom`` the rigid-pad stroke."""
    rest = lp.point(np.zeros(prob.basis.N), None, None, 0.0)
    path = follow_to_event(
        lp.solve,
        lp.margin,
        lp.observe,
        rest,
        d_nom,
        d_max_over_nominal * d_nom,
        steps,
        LOCK_TOLERANCES,
        chord=lp.chord,
        guess=lp.guess,
    )
    d_after = path.d_mm[-1] + LOCK_TOLERANCES.event_width_rel * d_nom * 10
    try:
        after, _ = lp.solve(path.state, d_after)
        ratio_after = after.k_t_N_per_mm / lp.k_ref
    except FloatingPointError:
        ratio_after = math.nan
    return path, ratio_after


def _lock_label(prob, active) -> str:
    """What closed at the lock: "pad" when the pads touch, else "wall" (a wall pinched)."""
    return "pad" if active is not None and active[: prob.pad_z.size].any() else "wall"


def linear_stiffness_N_per_mm(cell: HexCell, material: Material, options: MeshOptions = PRODUCTION_MESH) -> float:
    """Small-strain layer stiffness k (N/mm) of the L2 model alone (one linear solve); ``options``
    the mesh (the production mesh unless a convergence study, ``mst bench``'s, asks for another)."""
    return linear_k(ContactProblem(cell, material, options))


def linear_k(problem: ContactProblem) -> float:
    """Small-strain stiffness of a built problem: one linear solve with the tangent at u = 0."""

    _, K0 = problem.assemble(np.zeros(problem.basis.N))
    ul = np.zeros(problem.basis.N)
    ul[problem.tip_z] = -0.5
    # cut directly: a one-off solve needs no cached banded block (free_block is the path's)
    f = problem.free
    K_ff = K0[f][:, f].tocsc()
    # at rest K_ff is linear elasticity held on the bonded face: symmetric positive definite,
    # so SuperLU's symmetric mode (an A + A^T ordering, no pivoting) is safe, and on the fine
    # meshes up to 2x faster than the general LU
    lu = splu(K_ff, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    ul[f] = lu.solve(-(K0 @ ul)[f])
    if not np.all(np.isfinite(ul)):
        raise ContinuumError("singular small-strain tangent")
    return float(-(K0 @ ul)[problem.tip_z].sum() * problem.depth_factor)
