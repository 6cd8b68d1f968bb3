"""Rung L1 ``frame``: geometrically nonlinear (corotational) beam model of one hex layer.

Each inclined wall is a chain of 2D Timoshenko beam elements on its centre line, from the pad
mid-plane (z = t/2) to the chevron tip (z = h/2), the same line and length L that rung L0 uses
(:attr:`HexCell.wall_length_mm`). Boundary conditions are those of one wall of a symmetric
chevron (see :mod:`mst_cli.model.mechanics.spring`): clamped at the pad, which is bonded to the rigid
plate; at the tip, on the mirror plane z = h/2, no rotation and no horizontal force, vertical
motion prescribed (-d/2 for a layer compression d). Two walls in series make a chevron and
the web's two chevrons act in parallel, so the layer force is F = 2 f_wall (f_wall for the
whole web width b = D).

Elements are corotational (Crisfield, "Non-linear Finite Element Analysis of Solids and
Structures", Vol. 1, ch. 7; Battini & Pacoste, Comput. Methods Appl. Mech. Eng. 191 (2002)
1755): the rigid rotation of each element's chord is taken out exactly and the remaining
local deformation (stretch, two end rotations) is small and linear, with the shear-flexible
local stiffness EI/l (4+phi)/(1+phi), EI/l (2-phi)/(1+phi), phi = 12 EI/(kappa G A l^2).
Large rotations of the walls are exact; strains are assumed small. Plane strain: the wall is
a web b = D wide (20 mm against 0.4-3 mm thick) whose sections cannot contract along y, so
EA = E' b t and EI = E' b t^3 / 12 with E' = E / (1 - nu^2), as in rung L0; G is unchanged.

Load: displacement control with adaptive steps, up to the lock. A beam has no faces to pinch
or pads to meet, so the lock stroke is L2's (its stiffness knee, docs/design.md section 4)
through L0's fit of it, at most the rigid pads' stroke h - 2t - a. Where the walls' inner faces
would reach the mirror plane before that, the beam passes through it. After the lock the
layer's stiffness is the walls' last tangent plus L0's contact column.

The layer law (:func:`frame_layer`) multiplies the beam forces by the joint factor of
:mod:`mst_cli.model.mechanics.correction` (fitted against L2, a function of t/L and theta): the
beam's rigid clamps at the pad mid-plane and the tip are what that factor corrects.
:func:`solve_frame` itself returns the pure beam solution. Joint models of L1's own,
rigid end zones from the joint geometry, were measured against L2 on the 150 cells of the
earlier fit, theta 15-60 deg, t/L <= 0.6 (studies/model_choices.py, plane strain): median
|error| in k 23.7 % with none (beam theory), 11.9 % with half the geometric overlaps rigid,
61 % with all of them (L0's fitted factor then: 1.7 %; over the printable box now 1.0 %,
``mst bench``). The near-crack at the cavity's tip
vertex makes the joints softer than rigid and stiffer than absent, which the fit captures and
these do not, so L1 reuses L0's factor.

Also here, shared with rung L2: :class:`TabulatedLockingLayer`, the layer law of a sampled
monotone curve, and :func:`locked_tabulated_law`, which adds the locked branch to a path. The
path itself is followed by :mod:`mst_cli.model.mechanics.path`, L2's driver too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.cell import HexCell
from mst_cli.model.material import Material
from mst_cli.model.mechanics.correction import stiffness_factor
from mst_cli.model.mechanics.law_cache import law_cache
from mst_cli.model.mechanics.path import LAW_CHORD_TOL_REL, PathError, StepControl, follow_to_event
from mst_cli.model.mechanics.spring import (
    SHEAR_COEFFICIENT_RECT,
    contact_stiffness_N_per_mm,
    plane_strain_modulus_MPa,
    spring_layer,
)

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

DEFAULT_N_ELEMENTS = 12


class FrameError(RuntimeError):
    """The frame solve did not converge (reported, never returned as a silent number)."""


# --------------------------------------------------------------------------- tabulated law
def monotone_envelope(d_mm: ArrayLike, F_N: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The force-controlled path of a displacement-controlled curve.

    Under a force (the stack is force-driven) a layer whose F(d) falls after a peak snaps
    through at the peak force to the next point where F is higher again. Returns the samples
    with strictly increasing F and d; a plateau ends at the last sample (contact) with the
    peak force (plus a relative 1e-9 so that d(F) stays a function).
    """
    d = np.asarray(d_mm, dtype=float)
    F = np.asarray(F_N, dtype=float)
    keep_d, keep_F = [d[0]], [F[0]]
    for di, Fi in zip(d[1:], F[1:]):
        if Fi > keep_F[-1] and di > keep_d[-1]:
            keep_d.append(di)
            keep_F.append(Fi)
    if keep_d[-1] < d[-1]:  # snapped: contact reached at the peak force
        keep_d.append(d[-1])
        keep_F.append(keep_F[-1] * (1.0 + 1e-9) + 1e-300)
    return np.array(keep_d), np.array(keep_F)


@dataclass(frozen=True)
class TabulatedLockingLayer:
    """Layer law from a sampled curve: linear between samples up to the lock, then locked.

    Implements the layer-law protocol of :mod:`mst_cli.model.mechanics`. ``d_samples_mm`` and
    ``F_samples_N`` start at (0, 0), increase strictly, and end at contact onset.
    """

    d_samples_mm: tuple[float, ...]
    F_samples_N: tuple[float, ...]
    k_N_per_mm: float  # small-load stiffness (the linear solve)
    k_locked_N_per_mm: float
    snap_through: bool = False  # F(d) had a falling branch before contact
    # L2 only: the smallest principal stretch anywhere in the wall at the lock (None: not
    # computed); below material.CREASE_ONSET_STRETCH the wall's outer root creases (docs/design.md §4)
    min_stretch_at_lock: float | None = None

    @classmethod
    def from_curve(
        cls,
        d_mm: ArrayLike,
        F_N: ArrayLike,
        k_linear_N_per_mm: float,
        k_locked_N_per_mm: float,
        snap_through: bool | None = None,
        min_stretch_at_lock: float | None = None,
    ) -> TabulatedLockingLayer:
        d = np.asarray(d_mm, dtype=float)
        F = np.asarray(F_N, dtype=float)
        if not (np.all(np.diff(d) > 0) and np.all(np.diff(F) > 0) and d[0] == 0 and F[0] == 0):
            raise ValueError("a tabulated layer law needs a strictly increasing curve from (0, 0)")
        snap = bool(snap_through) if snap_through is not None else False
        stretch = None if min_stretch_at_lock is None else float(min_stretch_at_lock)
        k, k_locked = float(k_linear_N_per_mm), float(k_locked_N_per_mm)
        return cls(tuple(map(float, d)), tuple(map(float, F)), k, k_locked, snap, stretch)

    @property
    def d_lock_mm(self) -> float:
        return self.d_samples_mm[-1]

    @property
    def lock_force_N(self) -> float:
        return self.F_samples_N[-1]

    @property
    def knots_N(self) -> tuple[float, ...]:
        return self.F_samples_N[1:]

    def displacement_mm(self, force_N: ArrayLike) -> np.ndarray:
        F = np.asarray(force_N, dtype=float)
        inside = np.interp(F, self.F_samples_N, self.d_samples_mm)
        beyond = self.d_lock_mm + (F - self.lock_force_N) / self.k_locked_N_per_mm
        return np.where(F <= self.lock_force_N, inside, beyond)


# --------------------------------------------------------------------------- corotational beam
def _element_forces(X, U, l0, beta0, EA, EI, phi, need_K=True):
    """Internal forces (and tangents) of corotational Timoshenko elements, vectorised.

    X: (n+1, 2) node coordinates; U: (n+1, 3) nodal (u_x, u_z, rotation); per element l0, beta0.
    Returns f_e (n, 6), K_e (n, 6, 6).
    """
    x1 = X[:-1] + U[:-1, :2]
    x2 = X[1:] + U[1:, :2]
    dx = x2 - x1
    ln = np.hypot(dx[:, 0], dx[:, 1])
    c, s = dx[:, 0] / ln, dx[:, 1] / ln
    # rigid chord rotation beta - beta0, wrapped to (-pi, pi]
    c0, s0 = np.cos(beta0), np.sin(beta0)
    alpha = np.arctan2(s * c0 - c * s0, c * c0 + s * s0)
    ubar = ln - l0
    th1 = U[:-1, 2] - alpha
    th2 = U[1:, 2] - alpha
    k11 = EI / l0 * (4.0 + phi) / (1.0 + phi)
    k12 = EI / l0 * (2.0 - phi) / (1.0 + phi)
    N = EA / l0 * ubar
    M1 = k11 * th1 + k12 * th2
    M2 = k12 * th1 + k11 * th2
    zero = np.zeros_like(c)
    r = np.stack([-c, -s, zero, c, s, zero], axis=1)
    z = np.stack([s, -c, zero, -s, c, zero], axis=1)
    e3 = np.zeros((len(c), 6))
    e3[:, 2] = 1.0
    e6 = np.zeros((len(c), 6))
    e6[:, 5] = 1.0
    B = np.stack([r, -z / ln[:, None] + e3, -z / ln[:, None] + e6], axis=1)  # (n, 3, 6)
    fl = np.stack([N, M1, M2], axis=1)
    f = np.einsum("nij,ni->nj", B, fl)
    if not need_K:
        return f, None
    Kl = np.zeros((len(c), 3, 3))
    Kl[:, 0, 0] = EA / l0
    Kl[:, 1, 1] = Kl[:, 2, 2] = k11
    Kl[:, 1, 2] = Kl[:, 2, 1] = k12
    K = np.einsum("nki,nkl,nlj->nij", B, Kl, B)
    K += (N / ln)[:, None, None] * np.einsum("ni,nj->nij", z, z)
    K += ((M1 + M2) / ln**2)[:, None, None] * (np.einsum("ni,nj->nij", r, z) + np.einsum("ni,nj->nij", z, r))
    return f, K


@dataclass(frozen=True)
class FrameResult:
    """Force-displacement of one layer from the frame solve, up to contact onset."""

    displacement_mm: np.ndarray
    force_N: np.ndarray
    k_linear_N_per_mm: float
    d_contact_mm: float
    contact_at: str  # "pad" or "wall"
    newton_iterations: int
    snap_through: bool


class _Wall:
    def __init__(self, cell: HexCell, material, n_el: int):
        th = cell.theta_rad
        t, b = cell.t_mm, cell.b_mm
        outer, inner = cell.outer_profile_xz(), cell.inner_profile_xz()
        tip = 0.5 * (np.asarray(outer[1]) + np.asarray(inner[1]))  # centre of the tip section
        L = cell.wall_length_mm
        self.u_dir = np.array([math.cos(th), math.sin(th)])
        self.n0 = np.array([-math.sin(th), math.cos(th)])  # towards the cavity
        s = np.linspace(0.0, L, n_el + 1)
        self.X = tip[None, :] - (L - s)[:, None] * self.u_dir[None, :]
        self.l0 = np.full(n_el, L / n_el)
        self.beta0 = np.full(n_el, th)
        E, nu = material.youngs_modulus_MPa, material.poisson_ratio
        G = E / (2.0 * (1.0 + nu))
        E_ps = plane_strain_modulus_MPa(E, nu)  # a web b = D wide: plane strain
        self.EA, self.EI = E_ps * b * t, E_ps * b * t**3 / 12.0
        self.phi = 12.0 * self.EI / (SHEAR_COEFFICIENT_RECT * G * b * t * self.l0**2)
        self.n_nodes = n_el + 1
        ndof = 3 * self.n_nodes
        self.tip_w = ndof - 2
        fixed = [0, 1, 2, ndof - 2, ndof - 1]
        self.free = np.setdiff1d(np.arange(ndof), fixed)
        self.dofs = 3 * np.arange(n_el)[:, None] + np.arange(6)[None, :]  # (n, 6)
        self.half_t = 0.5 * t
        self.h2 = 0.5 * cell.h_mm
        self.ndof = ndof

    def assemble(self, u, need_K=True):
        U = u.reshape(-1, 3)
        fe, Ke = _element_forces(self.X, U, self.l0, self.beta0, self.EA, self.EI, self.phi, need_K)
        f = np.zeros(self.ndof)
        np.add.at(f, self.dofs, fe)
        if not need_K:
            return f, None
        K = np.zeros((self.ndof, self.ndof))
        np.add.at(K, (self.dofs[:, :, None], self.dofs[:, None, :]), Ke)
        return f, K

    def solve_step(self, u, d, max_iter=30, rtol=1e-10):
        u = u.copy()
        f, K = self.assemble(u)
        du_pres = -0.5 * d - u[self.tip_w]
        free = self.free
        u[free] += np.linalg.solve(K[np.ix_(free, free)], -f[free] - K[free, self.tip_w] * du_pres)
        u[self.tip_w] += du_pres
        scale = None
        for it in range(1, max_iter + 1):
            f, K = self.assemble(u)
            reaction = abs(f[self.tip_w])
            scale = max(reaction, 1e-14 * self.EA) if scale is None else max(scale, reaction)
            if np.linalg.norm(f[free]) <= rtol * scale + 1e-13 * self.EA:
                return u, it
            du = np.linalg.solve(K[np.ix_(free, free)], -f[free])
            if not np.all(np.isfinite(du)):
                raise FloatingPointError("singular tangent")
            u[free] += du
        raise FloatingPointError("Newton did not converge")


def solve_frame(
    cell: HexCell,
    material: Material,
    n_elements: int = DEFAULT_N_ELEMENTS,
    first_step_frac: float = 0.125,
    max_steps: int = 400,
) -> FrameResult:
    """Nonlinear force-displacement of one layer up to contact onset (see module docstring).

    The path is followed by :func:`mst_cli.model.mechanics.path.follow_to_event` (its default
    tolerances) up to the rigid pads' stroke, where contact is certain.

    Raises
    ------
    ValueError     for a cell without a cavity stroke (h - 2t <= allowance) or with p <= 0
    FrameError     when the path cannot be followed (steps stalled, a failed solve near contact)
    """
    _require_stroke(cell)
    wall = _Wall(cell, material, n_elements)
    factor = 2.0  # two chevrons in parallel
    allowance = cell.contact_allowance_mm
    u = np.zeros(wall.ndof)
    k_lin = _small_load_stiffness(wall) * factor
    d_lock, closes = _lock_stroke(cell, material)

    def margin(u, d):
        return d_lock - d, closes

    def force(u, d):
        f, _ = wall.assemble(u, need_K=False)
        return -f[wall.tip_w] * factor

    d_nom = cell.cavity_height_mm - allowance
    # the rigid pads meet at d_nom: a cap just past it ends every path in contact
    d_cap = d_nom * (1.0 + 1e-9) + 1e-12
    try:
        path = follow_to_event(
            wall.solve_step,
            margin,
            force,
            u,
            d_nom,
            d_cap,
            StepControl(first_step_rel=first_step_frac, max_steps=max_steps, chord_tol_rel=LAW_CHORD_TOL_REL),
            chord=_chord_estimate(wall, factor),
        )
    except PathError as exc:
        raise FrameError(f"frame solve: {exc} for {cell}") from None
    F = np.array([0.0] + path.observations)
    snap = bool(np.any(np.diff(F) <= 0))
    return FrameResult(
        np.array([0.0] + path.d_mm), F, k_lin, float(path.d_mm[-1]), path.event_at, path.iterations, snap
    )


def _chord_estimate(wall: _Wall, factor: float):
    """The path driver's ``chord`` callback (as L2's): a quadratic between two converged points
    bows off their chord by (d1 - d0) |k1 - k0| / 8, relative to the force at d1."""
    last: list = [None, 0.0]  # the last point measured to, and its tangent (the next step's start)

    def chord(u0, d0, u1, d1):
        k0 = last[1] if u0 is last[0] else _tangent_stiffness(wall, u0)
        k1 = _tangent_stiffness(wall, u1)
        last[:] = [u1, k1]
        f, _ = wall.assemble(u1, need_K=False)
        return (d1 - d0) * abs(k1 - k0) / 8.0 / max(abs(f[wall.tip_w]), 1e-300)

    return chord


def _require_stroke(cell: HexCell) -> None:
    """ValueError for a cell the frame cannot follow: no pad (p <= 0) or no stroke."""
    if not (cell.p_mm > 0 and cell.cavity_height_mm > cell.contact_allowance_mm):
        raise ValueError(
            f"frame model needs a cell with p > 0 and h - 2t > the contact allowance "
            f"(theta={cell.theta_deg:g} deg, t={cell.t_mm:g} mm, h={cell.h_mm:g} mm)"
        )


def _small_load_stiffness(wall: _Wall) -> float:
    """One wall's small-load stiffness (N/mm of layer compression): the tangent at u = 0."""
    return _tangent_stiffness(wall, np.zeros(wall.ndof))


def _tangent_stiffness(wall: _Wall, u: np.ndarray) -> float:
    """One wall's tangent stiffness dF/dd (N/mm of layer compression) at the converged state u:
    the tip moved by -1/2 per unit layer compression."""
    f0, K0 = wall.assemble(u)
    free = wall.free
    ul = np.zeros_like(u)
    ul[wall.tip_w] = -0.5
    ul[free] = np.linalg.solve(K0[np.ix_(free, free)], -K0[free, wall.tip_w] * ul[wall.tip_w])
    return float(-(K0 @ ul)[wall.tip_w])


def _lock_stroke(cell: HexCell, material: Material) -> tuple[float, str]:
    """(d_lock mm, what closes): L2's lock stroke (its stiffness knee, where a wall is pinched or
    the pads meet), through L0's fit of it (module docstring); "pad" when that is the rigid
    pads' stroke."""
    d_pads = cell.cavity_height_mm - cell.contact_allowance_mm
    d_lock = min(spring_layer(cell, material).d_lock_mm, d_pads)
    return d_lock, "pad" if d_lock >= d_pads else "wall"


def locked_tabulated_law(
    cell: HexCell,
    material: Material,
    d_mm: ArrayLike,
    F_N: ArrayLike,
    k_linear_N_per_mm: float,
    snap_through: bool = False,
    min_stretch_at_lock: float | None = None,
) -> TabulatedLockingLayer:
    """The law of a path sampled up to contact (rungs L1 and L2): its force-controlled envelope,
    then the locked branch, the walls' last tangent in parallel with the closed cavity's
    contact column (L0's :func:`~mst_cli.model.mechanics.spring.contact_stiffness_N_per_mm`);
    ``min_stretch_at_lock``: L2's crease marker (:class:`TabulatedLockingLayer`)."""
    d, F = monotone_envelope(d_mm, F_N)
    k_walls = max((F[-1] - F[-2]) / (d[-1] - d[-2]), 0.0)
    k_locked = k_walls + float(
        contact_stiffness_N_per_mm(
            cell.theta_rad, cell.t_mm, cell.width_mm, cell.b_mm, material.youngs_modulus_MPa, material.poisson_ratio
        )
    )
    return TabulatedLockingLayer.from_curve(d, F, k_linear_N_per_mm, k_locked, snap_through, min_stretch_at_lock)


@law_cache(maxsize=4096)
def frame_layer(cell: HexCell, material: Material) -> TabulatedLockingLayer:
    """The L1 law of one cell: the frame curve up to contact, then the locked branch (walls + contact column)."""
    res = solve_frame(cell, material)
    # the beam clamps the wall at the pad mid-plane and the tip; the finite joints' effect is
    # the same fitted factor as L0's (a function of t/L and theta only), applied to the forces
    joint = float(stiffness_factor(cell.t_mm / cell.wall_length_mm, cell.theta_rad))
    return locked_tabulated_law(
        cell, material, res.displacement_mm, res.force_N * joint, res.k_linear_N_per_mm * joint, res.snap_through
    )
