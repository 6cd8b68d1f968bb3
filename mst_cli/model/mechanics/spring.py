"""Rung L0 ``spring``: closed-form reduced beam model of one hex layer.

The layer's profile is one continuous web through the whole depth D (the part prints on its
side; :class:`~mst_cli.model.cell.HexCell`, b = D, default 20 mm). Its walls are 0.4-3 mm thick
and 1-8 mm long, so they bend in plane strain: a section cannot contract along y, and bending
and stretching see E' = E / (1 - nu^2) (1.25 E at nu = 0.45) instead of E; shear sees G.

Each inclined wall is a clamped-guided beam: the pad end is clamped (the pads are bonded to
rigid plates and, by left-right symmetry, do not rotate) and the chevron tip is guided (by
the mirror symmetry about z = h/2 it does not rotate) and free to move sideways (nothing
pushes on it horizontally). A vertical tip force F, split into a transverse part F cos(theta)
and an axial part F sin(theta), moves the tip vertically by

    delta / F = cos^2(theta) * (L^3 / (12 E' I) + L / (kappa G A)) + sin^2(theta) * L / (E' A)

with A = b t, I = b t^3 / 12 (bending and Timoshenko shear of a clamped-guided beam, plus
axial shortening; e.g. Roark's Formulas for Stress and Strain, 8th ed., Table 8.1 case 1e,
and Timoshenko & Gere; E' for the plate-like web as in cylindrical bending of plates). Two
walls in series make a chevron and the web's two chevrons act in parallel:

    k = 1 / c_wall    [N/mm]

After the cavity closes, the top and bottom pads (2t of solid TPU, bonded to the plates) press
on each other over the inner width 2c = W - 2t/sin(theta) and the web width b; that contact
column (the modulus of a bonded, laterally confined layer: :func:`contact_stiffness_N_per_mm`)
acts in parallel with the walls, which go on bending. The sum is the finite locked stiffness
past the lock.

The corrected law (the default) also carries the fitted lock point of rung L2
(:mod:`mst_cli.model.mechanics.correction`): the walls soften as they rotate, so the cavity closes at
R < k d_lock. Before the lock the law is then two straight pieces: slope k up to the knee
F = KNEE_FRACTION * R, then straight to (d_lock, R). The textbook law is bilinear (R = k d_lock).

The kernels are pure numpy, vectorised over any broadcastable arrays, and return finite
numbers for every input with positive t, h, b, 0 <= nu < 0.5 and theta in (0, 90) deg --
including cells that the validity checks reject (the geometry kernels floor the lengths).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.cell import HexCell, inner_tip_half_width_mm, lock_stroke_mm, wall_centreline_length_mm
from mst_cli.model.mechanics import correction

if TYPE_CHECKING:
    from collections.abc import Sequence

    from numpy.typing import ArrayLike

    from mst_cli.model.arrays import Floats
    from mst_cli.model.material import Material

SHEAR_COEFFICIENT_RECT = 5.0 / 6.0  # Timoshenko shear coefficient of a rectangular section
# Where the softened pre-lock curve bends, as a fraction of the lock force. Chosen against the
# L2 curves of 12 bench cells (seed 0, studies/model_choices.py, plane strain): the largest
# displacement error of the two-piece curve, in units of d_lock, has median 4.9 % at 0.4
# (6.7 % at 0.3, 5.5 % at 0.5, 10.8 % at 0.7).
KNEE_FRACTION = 0.4


def plane_strain_modulus_MPa(E_MPa: Floats, nu: Floats) -> Floats:
    """E' = E / (1 - nu^2): the bending and axial modulus of a web much wider than thick.

    The web runs the whole depth D (20 mm) while its walls are 0.4-3 mm thick, so a wall's
    cross-sections cannot contract along y (anticlastic curvature and the Poisson contraction
    are suppressed except within about a wall thickness of the free faces y = +-D/2):
    eps_yy = 0, sigma_yy = nu (sigma_xx + sigma_zz), and a fibre along the wall has the
    modulus E' (Timoshenko & Goodier, plate/cylindrical bending: D = E t^3 / 12 (1 - nu^2)).
    Shear is unaffected: G = E / 2 (1 + nu).
    """
    return E_MPa / (1.0 - nu * nu)


def wall_compliance_mm_per_N(
    theta_rad: Floats,
    t_mm: Floats,
    h_mm: Floats,
    b_mm: Floats,
    E_MPa: Floats,
    nu: Floats,
    bending: bool = True,
    shear: bool = True,
    axial: bool = True,
) -> np.ndarray:
    """Vertical compliance of one clamped-guided inclined wall (a web b wide), mm/N.

    Plane strain: bending and axial terms with E' = E / (1 - nu^2), shear with G.
    The switches drop terms for the textbook-limit tests (slender wall: bending only;
    theta -> 90 deg: axial only).
    """
    L = wall_centreline_length_mm(theta_rad, t_mm, h_mm)
    area = b_mm * t_mm
    inertia = b_mm * t_mm**3 / 12.0
    E_ps = plane_strain_modulus_MPa(E_MPa, nu)
    G = E_MPa / (2.0 * (1.0 + nu))
    cos2 = np.cos(theta_rad) ** 2
    sin2 = np.sin(theta_rad) ** 2
    c = np.zeros(np.broadcast(theta_rad, t_mm, h_mm, b_mm, E_MPa, nu).shape)
    if bending:
        c = c + cos2 * L**3 / (12.0 * E_ps * inertia)
    if shear:
        c = c + cos2 * L / (SHEAR_COEFFICIENT_RECT * G * area)
    if axial:
        c = c + sin2 * L / (E_ps * area)
    return c


def layer_stiffness_N_per_mm(
    theta_rad: Floats, t_mm: Floats, h_mm: Floats, b_mm: Floats, E_MPa: Floats, nu: Floats
) -> np.ndarray:
    """Small-load stiffness k of a whole layer (a web of width b: 2 chevrons of 2 walls each)."""
    c_wall = wall_compliance_mm_per_N(theta_rad, t_mm, h_mm, b_mm, E_MPa, nu)
    # chevron = 2 walls in series (2 c); the layer = 2 chevrons in parallel
    return 2.0 / (2.0 * c_wall)


def pad_compression_modulus_MPa(E_MPa: Floats, nu: Floats, half_width_mm: Floats, thickness_mm: Floats) -> np.ndarray:
    """Apparent compression modulus of a layer bonded to rigid plates on both faces, in plane
    strain (long along y), half-width a, thickness H:

        E_c = E' + (M - E') (1 - tanh(alpha a) / (alpha a)),   alpha^2 = 12 mu / (M H^2)

    with E' = E / (1 - nu^2) and the constrained (oedometric) modulus
    M = E (1 - nu) / ((1 + nu)(1 - 2 nu)). It is the "pressure method" of bonded rubber layers
    (parabolic bulging of the free edges, e.g. Gent & Lindley, Proc. Inst. Mech. Eng. 173 (1959)
    111; Tsai & Lee, Int. J. Solids Struct. 35 (1998) 3053), written to meet both limits: a
    narrow column (a << H) bulges freely and has E'; a wide layer is confined everywhere but
    within ~H of its edges and tends to M; incompressible, it is 4 mu (1 + a^2 / H^2), the
    squeeze-film result. nu = 0 gives E for every shape (a lower bound for all nu >= 0).
    """
    E_ps = E_MPa / (1.0 - nu * nu)
    M = E_MPa * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))
    # alpha a = sqrt(12 mu / M) a / H, mu / M = (1 - 2 nu) / (2 (1 - nu)); + 1e-12: tanh(x)/x -> 1
    x = np.sqrt(6.0 * (1.0 - 2.0 * nu) / (1.0 - nu)) * half_width_mm / thickness_mm + 1e-12
    return E_ps + (M - E_ps) * (1.0 - np.tanh(x) / x)


def contact_stiffness_N_per_mm(
    theta_rad: Floats, t_mm: Floats, width_mm: Floats, b_mm: Floats, E_MPa: Floats, nu: Floats = 0.0
) -> np.ndarray:
    """Stiffness of the closed cavity's contact column: 2t of solid TPU over the contact width.

    Which modulus: the closed pads (t each, bonded to the rigid plates on their outer faces)
    touch on the mid-plane; frictionless contact there is the mirror plane of ONE layer 2t thick
    bonded to both plates (friction only adds constraint). That layer is long along y (the web,
    D = 20 mm: plane strain) and 2 c wide along x, c the inner tip half-width (10-14 mm against
    2t = 0.8-4 mm), so it is laterally constrained in x as well, away from its edges: neither E
    nor E' but the bonded-layer modulus of :func:`pad_compression_modulus_MPa`, which runs from
    E' (a narrow column) to the constrained modulus M (at nu = 0.45, E' = 1.25 E and M = 3.8 E;
    2.5-3.5 E for the cells in the design bounds). ``nu`` = 0 (the default, kept for callers that
    want a bound) gives E b w / 2t, a lower bound for every nu >= 0.
    """
    half = np.maximum(inner_tip_half_width_mm(theta_rad, t_mm, width_mm), 0.5 * t_mm)
    E_c = pad_compression_modulus_MPa(E_MPa, nu, half, 2.0 * t_mm)
    return E_c * b_mm * 2.0 * half / (2.0 * t_mm)


def layer_displacement_mm(
    force_N: Floats,
    k_N_per_mm: Floats,
    d_lock_mm: Floats,
    lock_force_N: Floats,
    k_locked_N_per_mm: Floats,
) -> np.ndarray:
    """Compression of L0 layers at force F, vectorised (all arguments broadcast).

    Slope k up to the knee F1 = KNEE_FRACTION * R, straight on to (d_lock, R), then k_locked.
    With R = k d_lock (textbook) the two pre-lock pieces are one line.
    """
    F = np.asarray(force_N, dtype=float)
    k = np.asarray(k_N_per_mm, dtype=float)
    dl = np.asarray(d_lock_mm, dtype=float)
    R = np.asarray(lock_force_N, dtype=float)
    F1 = KNEE_FRACTION * R
    d1 = F1 / k
    # d1 <= KNEE_FRACTION * d_lock < d_lock because R <= k d_lock (spring_arrays caps it)
    soft = d1 + (F - F1) * (dl - d1) / np.maximum(R - F1, 1e-300)
    return np.where(F <= F1, F / k, np.where(F <= R, soft, dl + (F - R) / k_locked_N_per_mm))


@dataclass(frozen=True)
class LinearLockingLayer:
    """Piecewise-linear law of one L0 layer: k, a softened stretch to (d_lock, R), k_locked after.

    Implements the layer-law protocol of :mod:`mst_cli.model.mechanics`. ``lock_force_N`` None
    means the bilinear law, R = k d_lock.
    """

    k_N_per_mm: float
    d_lock_mm: float
    k_locked_N_per_mm: float
    # None means the bilinear law; __post_init__ sets it to k d_lock, so it is a float after
    lock_force_N: float = None  # type: ignore[assignment]

    def __post_init__(self):
        if self.lock_force_N is None:
            object.__setattr__(self, "lock_force_N", self.k_N_per_mm * self.d_lock_mm)

    @property
    def knots_N(self) -> tuple[float, ...]:
        R = self.lock_force_N
        if R >= self.k_N_per_mm * self.d_lock_mm * (1.0 - 1e-12):
            return (R,)
        return (KNEE_FRACTION * R, R)

    def displacement_mm(self, force_N: Floats) -> np.ndarray:
        return layer_displacement_mm(
            force_N, self.k_N_per_mm, self.d_lock_mm, self.lock_force_N, self.k_locked_N_per_mm
        )


def spring_arrays(
    theta_rad: Floats,
    t_mm: Floats,
    h_mm: Floats,
    b_mm: Floats,
    width_mm: Floats,
    contact_allowance_mm: Floats,
    E_MPa: Floats,
    nu: Floats,
    corrected: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(k, d_lock, R, k_locked) for many layers at once: the design loop's entry point.

    ``corrected`` (default) applies the fits against rung L2
    (:mod:`mst_cli.model.mechanics.correction`, functions of t/L, theta and the stroke): the joint
    factor on k (median stiffness error against L2 about 1 % instead of 14 % over the printable
    box, measured by ``mst bench``; mst_cli/model/data/ladder_errors.json) and the
    softened lock point (R, d_lock). False gives textbook beam theory: R = k d_lock, d_lock
    where the pads meet.
    """
    k = layer_stiffness_N_per_mm(theta_rad, t_mm, h_mm, b_mm, E_MPa, nu)
    d_lock = lock_stroke_mm(t_mm, h_mm, contact_allowance_mm)
    R = k * d_lock
    if corrected:
        L = wall_centreline_length_mm(theta_rad, t_mm, h_mm)
        t_over_L = t_mm / L
        sigma = correction.stroke_ratio(d_lock, L, theta_rad)
        stiffness_factor, force_factor, stroke_factor = correction.spring_factors(t_over_L, theta_rad, sigma)
        k = k * stiffness_factor
        R = k * d_lock * force_factor
        d_lock = d_lock * stroke_factor
        R = np.minimum(R, k * d_lock)  # walls only soften before the lock
    k_locked = k + contact_stiffness_N_per_mm(theta_rad, t_mm, width_mm, b_mm, E_MPa, nu)
    return k, d_lock, R, k_locked


def spring_layers(
    cells: Sequence[HexCell], material: Material, corrected: bool = True, modulus_MPa: ArrayLike | None = None
) -> tuple[LinearLockingLayer, ...]:
    """The L0 laws of a stack's cells from one kernel call (a layer's law does not depend on
    the batch it is computed in: the same numbers as the design loop's batches). ``modulus_MPa``:
    one modulus per cell instead of the material's (the web's finite depth,
    :func:`mst_cli.model.mechanics.depth.web_modulus_MPa`)."""
    fields = ("theta_rad", "t_mm", "h_mm", "b_mm", "width_mm", "contact_allowance_mm")
    columns = [np.array([getattr(c, name) for c in cells], dtype=float) for name in fields]
    E = material.youngs_modulus_MPa if modulus_MPa is None else np.asarray(modulus_MPa, dtype=float)
    # mypy cannot count *columns (six arrays) against the positional parameters
    k, d_lock, R, k_locked = spring_arrays(*columns, E, material.poisson_ratio, corrected)  # type: ignore[arg-type, call-arg]
    return tuple(
        LinearLockingLayer(float(a), float(b), float(c), float(d)) for a, b, c, d in zip(k, d_lock, k_locked, R)
    )


def spring_layer(cell: HexCell, material: Material, corrected: bool = True) -> LinearLockingLayer:
    """The L0 law of one concrete cell (``corrected=False``: textbook beam theory only)."""
    return spring_layers((cell,), material, corrected)[0]
