"""L2 under tilted plates: the check of the tilt rung (:mod:`mst_cli.model.mechanics.tilt`).

When the plates of a layer tilt by phi about y as well as close by d, the two chevrons stay
independent (the plates are rigid and the bonded pad between them is unstressed a few t from
the walls), so the full-width, unsymmetric problem is two quarter problems: the right chevron
with +phi and the left one with -phi. Each is the quarter profile of
:mod:`mst_cli.model.mechanics.continuum` with its bonded face turned: in the symmetric split of
the relative motion the mirror plane still moves by -d/2, and the bottom plate turns by phi/2
about the axis's foot, u_z = phi x / 2, u_x = -phi z / 2 (the pad's cut turns with it), and so
does the plate the wall's outer face lies down on. The tilt rung says this chevron is the
untilted one at the compression d + phi x_c; :func:`solve_tilted_chevron` gives what L2 says.

Two small-strain solves of the same problem give x_c itself (:func:`linear_tilt_lever_mm`).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse.linalg import spsolve

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics.continuum import (
    D_MAX_OVER_NOMINAL,
    DEFAULT_LEVELS,
    DEFAULT_N_LENGTH,
    DEFAULT_N_THICK,
    ContactProblem,
    ContinuumError,
    ContinuumResult,
    MeshOptions,
    continuum_result,
    follow_to_lock,
)
from mst_cli.model.mechanics.path import PathError, StepControl


def _dof_sets(prob: ContactProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(is_x (N,), on the bonded bottom face (N,), on the pad's cut above it (N,), dof x, z):
    the problem's own masks."""
    return prob.is_x, prob.on_bottom, prob.on_cut & ~prob.on_bottom, prob.basis.doflocs


class _TiltedProblem(ContactProblem):
    """The quarter problem with its bonded face and plate turned by phi/2 = tilt d / 2."""

    def __init__(self, cell, material, tilt_rad_per_mm: float, n_thick: int, n_length: int, levels: int = 0):
        super().__init__(cell, material, MeshOptions(n_thick, n_length, levels))
        if self.x_cut <= 0.0:
            raise ValueError("tilted L2 needs a pad longer than PAD_LENGTH_IN_T t (its cut away from the axis)")
        is_x, bottom, cut, xy = _dof_sets(self)
        self.tilt = float(tilt_rad_per_mm)
        self._held_rate = np.zeros(self.basis.N)
        self._held_rate[bottom & ~is_x] = 0.5 * self.tilt * xy[0, bottom & ~is_x]
        self._held_rate[cut & is_x] = -0.5 * self.tilt * xy[1, cut & is_x]
        self.obstacle_rate = self.obstacle_rate.copy()
        outer = self.contact_dofs[self.n_inner :]
        self.obstacle_rate[self.n_inner :] = 0.5 * self.tilt * xy[0, outer]

    def pinned_rate(self) -> np.ndarray:
        return super().pinned_rate() + self._held_rate

    def _newton(self, u, d, active=None, max_iter=60, rtol=1e-8, pads=False):
        u = u.copy()
        held = self._held_rate != 0.0
        u[held] = self._held_rate[held] * d
        return super()._newton(u, d, active, max_iter, rtol, pads)


def solve_tilted_chevron(
    cell: HexCell,
    material: Material,
    tilt_rad_per_mm: float,
    n_thick: int = DEFAULT_N_THICK,
    n_length: int = DEFAULT_N_LENGTH,
) -> ContinuumResult:
    """One chevron's F(d) through its lock with the plates tilting by phi = tilt d as they close
    (d the compression at the axis; forces as a whole web of such chevrons, plane strain, on the
    path's own mesh: compare with ``solve_continuum(...).force_N / mesh_scale``)."""
    prob = _TiltedProblem(cell, material, tilt_rad_per_mm, n_thick, n_length)
    k0 = prob.rate(np.zeros(prob.basis.N), None, 0.0)[1]
    # the side that closes less reaches its stroke later: at most where its pads' least-closed
    # point (the cut, or the pad's end) has closed by the untilted stroke
    least = min(1.0 + tilt_rad_per_mm * prob.x_cut, 1.0 + tilt_rad_per_mm * cell.p_mm)
    try:
        path, ratio_after = follow_to_lock(prob, k0, StepControl(), D_MAX_OVER_NOMINAL / max(least, 0.05))
    except PathError as exc:
        raise ContinuumError(f"tilted continuum solve: {exc} for {cell}") from None
    return continuum_result(prob, path, k0, 1.0, ratio_after, int(prob.basis.N))


def linear_tilt_lever_mm(
    cell: HexCell,
    material: Material,
    n_thick: int = DEFAULT_N_THICK,
    n_length: int = DEFAULT_N_LENGTH,
    levels: int = DEFAULT_LEVELS,
) -> float:
    """Where a chevron's force sits when the plates tilt (mm from the axis), at small strain.

    Two linear solves of the quarter profile with the mirror plane held (u_z = 0 on the tip
    face): the bonded bottom face lifted uniformly by 1/2 (a compression d = 1 mm), then
    turned about its own line by phi/2 with phi = 1 rad (u_z = x/2), the symmetric half of a
    relative tilt phi of the plates. The pad's cut turns with the pad (u_x = -z/2) when it lies
    away from the axis; a cut on the axis (a pad shorter than PAD_LENGTH_IN_T t) is the plane
    of antisymmetry of a tilt, u_z = 0 there, u_x free. If the chevron answers only to the
    compression at one line x_c, the second force is x_c times the first: the ratio is the
    lever the tilt rung (:mod:`mst_cli.model.mechanics.tilt`) uses.
    """
    prob = ContactProblem(cell, material, MeshOptions(n_thick, n_length, levels))
    _, K0 = prob.assemble(np.zeros(prob.basis.N))
    is_x, bottom, cut, xy = _dof_sets(prob)
    u_comp = np.zeros(prob.basis.N)
    u_comp[bottom & ~is_x] = 0.5
    u_tilt = np.zeros(prob.basis.N)
    u_tilt[bottom & ~is_x] = 0.5 * xy[0, bottom & ~is_x]
    pinned_comp = bottom | (cut & is_x)
    if prob.x_cut > 0.0:
        u_tilt[cut & is_x] = -0.5 * xy[1, cut & is_x]
        pinned_tilt = pinned_comp
    else:
        pinned_tilt = bottom | (cut & ~is_x)
    forces = []
    for u, pinned in ((u_comp, pinned_comp), (u_tilt, pinned_tilt)):
        pinned = pinned.copy()
        pinned[prob.tip_z] = True
        free = np.flatnonzero(~pinned)
        u[free] = spsolve(K0[free][:, free].tocsc(), -(K0 @ u)[free])
        forces.append(-(K0 @ u)[prob.tip_z].sum())
    return float(forces[1] / forces[0])
