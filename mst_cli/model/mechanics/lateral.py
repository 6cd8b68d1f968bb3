"""Rung L0 of the lateral stiffness: closed forms for k_x (across the width) and k_y (along the
depth) of one layer at small load, fitted to L2 (:mod:`~mst_cli.model.mechanics.continuum_lateral`,
docs/design.md section 4.4).

Both start from one inclined wall of the chevron, from its root on the pad to the mid-plane,
centre-line length L = (h - t) / (2 sin theta), and the odd (antisymmetric) lateral motion:

* across the width the wall's tip moves u_x / 2 and is free in z and in rotation (a cantilever
  loaded at its tip): transverse stiffness k_t = 1 / (L^3 / (3 E' I) + L / (kappa G A)), axial
  k_a = E' A / L (plane strain, E' = E / (1 - nu^2), per mm of depth: A = t, I = t^3 / 12); free
  in z, the tip's stiffness along x is k_t k_a / (k_t cos^2 theta + k_a sin^2 theta), and the
  layer's k_x is that times the depth b (two chevrons, each two walls in series);
* along the depth, antiplane shear through a strip t thick and L long: G t / L per mm, the layer
  k_y = b G t / L (the same count);

then each times a fitted factor exp(sum c_i term_i(t/L, theta, e)) (:data:`TERMS`: a cubic in
t/L and theta, 1/theta for the shallow walls, and e = exp(-p_i/t), p_i the inner pad's half
width, for the shallow thick cells whose two chevrons share a pad shorter than a few t, where
the beam picture fails; coefficients in model/data/lateral_fit.json, written by
tools/fit_lateral.py from L2 on a seeded sample of valid cells topped up at the corners of the
verified box, and verified on another). The depth's L2 is an infinitely deep web; a web D deep
loses stiffness at its free faces y = +-D/2, the factor :func:`depth_end_factor` fitted to the
3D check (tools/lateral_check.py). Across the width the layer is plane strain, as the normal
stiffness (section 4.1 of docs/design.md).
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.cell import HexCell, inner_pad_half_width_mm, wall_centreline_length_mm
from mst_cli.model.material import Material
from mst_cli.model.mechanics.spring import SHEAR_COEFFICIENT_RECT, plane_strain_modulus_MPa

if TYPE_CHECKING:
    from mst_cli.model.arrays import Floats

DATA = Path(__file__).resolve().parent.parent / "data" / "lateral_fit.json"
# x = t / L, th = theta in radians, e = exp(-p_i / t) (p_i the inner pad's half width)
TERMS = (
    "1", "x", "th", "x^2", "x*th", "th^2", "x^3", "x^2*th", "x*th^2", "th^3",
    "1/th", "x/th", "e", "e*th", "e*x", "e^2", "e*x^2", "e^4", "e^4*x",
)  # fmt: skip


def beam_k_x_N_per_mm(
    theta_rad: Floats, t_mm: Floats, h_mm: Floats, b_mm: Floats, E_MPa: Floats, nu: Floats
) -> np.ndarray:
    """The walls-as-beams k_x of a layer a web b deep (module docstring), N/mm."""
    L = wall_centreline_length_mm(theta_rad, t_mm, h_mm)
    E_ps = plane_strain_modulus_MPa(E_MPa, nu)
    G = np.asarray(E_MPa) / (2.0 * (1.0 + np.asarray(nu)))
    k_t = 1.0 / (L**3 / (3.0 * E_ps * t_mm**3 / 12.0) + L / (SHEAR_COEFFICIENT_RECT * G * t_mm))
    k_a = E_ps * t_mm / L
    c2, s2 = np.cos(theta_rad) ** 2, np.sin(theta_rad) ** 2
    return np.asarray(b_mm * k_t * k_a / (k_t * c2 + k_a * s2))


def beam_k_y_N_per_mm(theta_rad: Floats, t_mm: Floats, h_mm: Floats, b_mm: Floats, G_MPa: Floats) -> np.ndarray:
    """The walls-as-strips k_y = b G t / L of an infinitely deep web (module docstring), N/mm."""
    return np.asarray(b_mm * G_MPa * t_mm / wall_centreline_length_mm(theta_rad, t_mm, h_mm))


def design_matrix(t_over_L: Floats, theta_rad: Floats, pad_over_t: Floats) -> np.ndarray:
    """The fitted factors' terms (:data:`TERMS`) at each (t/L, theta, p_i/t): shape (..., len(TERMS))."""
    x, th, pad = np.broadcast_arrays(
        np.asarray(t_over_L, float), np.asarray(theta_rad, float), np.asarray(pad_over_t, float)
    )
    e = np.exp(-pad)
    one = np.ones_like(x)
    cubic = [one, x, th, x * x, x * th, th * th, x**3, x * x * th, x * th * th, th**3]
    e4 = e**4
    return np.stack(cubic + [1.0 / th, x / th, e, e * th, e * x, e * e, e * x * x, e4, e4 * x], axis=-1)


@cache
def _fit() -> dict:
    return json.loads(DATA.read_text())


def clear_caches() -> None:
    """Forget the coefficients read (tools/fit_lateral.py rewrites the file)."""
    _fit.cache_clear()


def lateral_factors(t_over_L: Floats, theta_rad: Floats, pad_over_t: Floats) -> tuple[np.ndarray, np.ndarray]:
    """(L2 / beam for k_x, L2 / strip for k_y) from the fitted coefficients."""
    A = design_matrix(t_over_L, theta_rad, pad_over_t)
    fit = _fit()
    return np.exp(A @ np.array(fit["x"]["coef"])), np.exp(A @ np.array(fit["y"]["coef"]))


def depth_end_factor(t_mm: Floats, wall_length_mm: Floats, depth_mm: Floats) -> np.ndarray:
    """k_y of a web D deep over that of an infinitely deep one: 1 - c (L + t) / D (c fitted to
    the 3D check, floored at 0.5 for webs not much deeper than their walls are long)."""
    c = float(_fit()["depth_end"]["c"])
    return np.maximum(1.0 - c * (np.asarray(wall_length_mm) + t_mm) / depth_mm, 0.5)


def lateral_stiffness_arrays(
    theta_rad: Floats, t_mm: Floats, h_mm: Floats, width_mm: Floats, depth_mm: Floats, E_MPa: Floats, nu: Floats
) -> tuple[np.ndarray, np.ndarray]:
    """(k_x, k_y) in N/mm at small load, vectorised over cells (module docstring)."""
    L = wall_centreline_length_mm(theta_rad, t_mm, h_mm)
    pad = inner_pad_half_width_mm(theta_rad, t_mm, h_mm, width_mm) / np.asarray(t_mm)
    g_x, g_y = lateral_factors(np.asarray(t_mm) / L, theta_rad, pad)
    G = np.asarray(E_MPa) / (2.0 * (1.0 + np.asarray(nu)))
    k_x = g_x * beam_k_x_N_per_mm(theta_rad, t_mm, h_mm, depth_mm, E_MPa, nu)
    k_y = g_y * beam_k_y_N_per_mm(theta_rad, t_mm, h_mm, depth_mm, G) * depth_end_factor(t_mm, L, depth_mm)
    return k_x, k_y


def lateral_stiffness_N_per_mm(cell: HexCell, material: Material, depth_mm: float | None = None) -> tuple[float, float]:
    """Small-load (k_x, k_y) in N/mm of one layer, a web ``depth_mm`` deep (the cell's D unless
    given): k_x across the width, k_y along the depth (module docstring)."""
    D = cell.depth_mm if depth_mm is None else depth_mm
    k_x, k_y = lateral_stiffness_arrays(
        cell.theta_rad, cell.t_mm, cell.h_mm, cell.width_mm, D, material.youngs_modulus_MPa, material.poisson_ratio
    )
    return float(k_x), float(k_y)


def closed_block_lateral_N_per_mm(cell: HexCell, material: Material) -> float:
    """The lateral stiffness (N/mm, along x or y alike) of a layer past its lock taken as its
    closed cavity filled, as the whole-part rung and the issue's independent model close it: a
    TPU block bonded to the plates, in shear through the pads' width, G D 2p / h. The tips'
    triangles beyond the pads, their faces free and sloping at theta, carry little of it: against
    an independent plane-strain FE of the filled hexagon (tools/lateral_check.py's mesh; tests/
    test_lateral.py) this is 1-3 % stiff along x and 1-5 % soft along y, where the whole hexagon
    in uniform shear over each height is up to 33 % stiff (11 degree walls)."""
    return material.shear_modulus_MPa * cell.depth_mm * 2.0 * cell.p_mm / cell.h_mm


def small_load_lateral_N_per_mm(cell: HexCell, material: Material, mechanics: str) -> tuple[float, float]:
    """(k_x, k_y) at small load from the rung ``mst simulate`` uses: L0's closed forms for the
    spring and frame rungs, L2's solves (k_y with L0's free-face factor) for the continuum."""
    if mechanics != "continuum":
        return lateral_stiffness_N_per_mm(cell, material)
    from mst_cli.model.mechanics import continuum_lateral as l2  # deferred: L2 (scikit-fem) loads when asked

    k_y = l2.lateral_stiffness_y_N_per_mm(cell, material) * float(
        depth_end_factor(cell.t_mm, cell.wall_length_mm, cell.depth_mm)
    )
    return l2.lateral_stiffness_x_N_per_mm(cell, material), k_y


def expected_error_rel() -> dict[str, float]:
    """The fit's out-of-sample errors against L2 (max relative, per direction), as stored."""
    fit = _fit()
    return {k: float(fit["out_of_sample"][k]["max_rel"]) for k in ("x", "y")}
