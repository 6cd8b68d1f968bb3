"""One layer's L2 law: :func:`solve_continuum` (the fine mesh's k, the path to the lock on the
path's mesh) and the cached law :func:`continuum_layer`; :class:`StudyOptions`, the studies' hook."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from mst_cli.model.mechanics.continuum.lock_path import (
    LOCK_STIFFNESS_FACTOR,
    ContinuumError,
    ContinuumResult,
    continuum_result,
    follow_to_lock,
    linear_k,
)
from mst_cli.model.mechanics.continuum.mesh import CORNERS, PRODUCTION_MESH, REFINE_RADIUS_IN_T, MeshOptions
from mst_cli.model.mechanics.continuum.problem import ContactProblem
from mst_cli.model.mechanics.frame import TabulatedLockingLayer, locked_tabulated_law
from mst_cli.model.mechanics.law_cache import law_cache
from mst_cli.model.mechanics.path import PathError, StepControl

if TYPE_CHECKING:
    from mst_cli.model.cell import HexCell
    from mst_cli.model.material import Material


@dataclass(frozen=True)
class StudyOptions:
    """How a study's :func:`solve_continuum` departs from production; the defaults are production.

    ``mesh``: the fine mesh, whose linear k is the law's (:class:`MeshOptions`: elements across
    and along the wall, corner refinement, the root fillet). The path's mesh is the same with
    ``path_levels`` rounds of corner refinement (default 0; its forces are scaled by the linear
    stiffness ratio to the fine mesh). A convergence study knob: studies/sweep_lock.py and
    docs/design.md section 4 give what it changes; ``path_corners`` and ``path_radius_in_t`` say
    where it refines (studies/steep_lock.py refines at the inner wall root alone, where a steep
    wall's contact front runs).
    ``plate_penalty_per_mm``: the outer face's contact with the plate as a penalty of that
    stiffness (pressure per mm of overlap, in units of the shear modulus; :class:`PlatePenalty`)
    instead of the active set: a study knob for root-graded path meshes.
    ``first_step_frac``, ``max_steps``: the path's first step (a fraction of the rigid-pad
    stroke) and its step budget (:class:`~mst_cli.model.mechanics.path.StepControl`).
    ``lock_stiffness_factor``: the lock's test (LOCK_STIFFNESS_FACTOR; studies/sweep_lock.py varies it).
    """

    mesh: MeshOptions = PRODUCTION_MESH
    path_levels: int = 0
    path_corners: tuple[str, ...] = CORNERS
    path_radius_in_t: float = REFINE_RADIUS_IN_T
    plate_penalty_per_mm: float | None = None
    first_step_frac: float = 0.125
    max_steps: int = 200
    lock_stiffness_factor: float = LOCK_STIFFNESS_FACTOR

    @property
    def path_mesh(self) -> MeshOptions:
        """The path's mesh: the fine mesh's elements, refined ``path_levels`` rounds."""
        return replace(self.mesh, levels=self.path_levels, corners=self.path_corners, radius_in_t=self.path_radius_in_t)


PRODUCTION = StudyOptions()


def solve_continuum(cell: HexCell, material: Material, study: StudyOptions = PRODUCTION) -> ContinuumResult:
    """Nonlinear force-displacement of one layer through closure, up to its lock.

    Displacement control with adaptive steps: a step that fails to converge is halved, a step
    that converges in few Newton iterations lets the next grow. The lock, where the tangent
    stiffness jumps, is bracketed between two converged steps and bisected
    (:func:`follow_to_lock`; the driver is L1's too: :mod:`mst_cli.model.mechanics.path`).

    Production calls ``solve_continuum(cell, material)``; ``study`` is the studies' hook
    (:class:`StudyOptions`).

    Raises
    ------
    ValueError          for a cell whose profile cannot be meshed (broken validity rule)
    ContinuumError      when the path cannot be followed (steps stalled below 1e-7 of the
                        stroke, no contact up to D_MAX_OVER_NOMINAL times it)
    """
    _require_meshable(cell)
    fine = ContactProblem(cell, material, study.mesh)
    k_lin = linear_k(fine)
    # The nonlinear path runs on the mesh without corner refinement: on the refined one the
    # elements at the cavity's near-crack tip invert long before contact. Its forces are
    # scaled by k_fine / k_coarse, the ratio of the two meshes' linear stiffnesses (the
    # corner singularity's mesh error; the benchmark's convergence study records it).
    own_path_mesh = study.path_mesh != study.mesh or study.plate_penalty_per_mm is not None
    prob = ContactProblem(cell, material, study.path_mesh, study.plate_penalty_per_mm) if own_path_mesh else fine
    k_path = linear_k(prob) if own_path_mesh else k_lin
    mesh_scale = k_lin / k_path
    steps = StepControl(first_step_rel=study.first_step_frac, max_steps=study.max_steps)
    try:
        path, ratio_after = follow_to_lock(prob, k_path, steps, lock_factor=study.lock_stiffness_factor)
    except PathError as exc:
        raise ContinuumError(f"continuum solve: {exc} for {cell}") from None
    return continuum_result(prob, path, k_lin, mesh_scale, ratio_after, int(fine.basis.N))


def _require_meshable(cell: HexCell) -> None:
    """Raise ValueError for a cell whose quarter profile cannot be meshed."""
    bad = [v for v in cell.violations() if v.rule in ("pad_width", "lock_stroke")]
    if bad:
        raise ValueError(f"continuum model needs a meshable cell: {bad[0].message}")
    if not (cell.p_mm > 0 and cell.h_mm > 2 * cell.t_mm):
        raise ValueError("continuum model needs a meshable cell: h <= 2t or p <= 0")


@law_cache(maxsize=256)
def continuum_layer(cell: HexCell, material: Material) -> TabulatedLockingLayer:
    """The L2 law of one cell: the FE curve up to its lock, then the locked branch (walls + contact column)."""
    res = solve_continuum(cell, material)
    return locked_tabulated_law(
        cell, material, res.displacement_mm, res.force_N, res.k_linear_N_per_mm, False, res.min_stretch_at_lock
    )
