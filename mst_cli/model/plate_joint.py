"""The walls' joints with the TPU plates between the layers: what a wall gives beyond its rung's
clamped root when it stands on a plate of the printed part (issue 44, docs/design.md 4.7).

Every layer rung (L0, L1, L2) clamps a wall's root to a rigid plate. In the exported part the
plate is TPU, and the whole-part rung (mechanics.whole_part) finds the plates giving 7-8 times
what their bending as beams (model.load_path) gives: the walls' roots turn into the plate, and
the plate is squeezed under them. Per root on a plate, for the vertical press's share through it:

* **the root turns** against a rotational spring M / phi = c sin(theta)^a (L/t)^b E'D t^2 (D the
  depth, t the wall's thickness, L its centre-line length): the clamped-guided wall of L0 with
  that spring at its root gives L/k m + (m L^2/2 - L^3/6)/E'I - L^3/(12 E'I) more,
  m = (L^2 / 2E'I) / (1/k + L/E'I), times cos^2 theta for the vertical. The spring is of the
  order of a rigid flat punch's t wide, tilted on an elastic half-plane (pi/8 E'D t^2, pi/8 =
  0.39; Johnson, Contact Mechanics, 1985, chapter 2); a shallow wall bears on a wider, slanted
  footprint (a < 0);
* **the plate is squeezed** under the root: s p / (E'D t), p the plate's thickness.

A layer's walls stand on a plate at their feet (a plate below) and at their heads (a plate
above); half of the layer's vertical compliance passes each, so each root counts half. The cover
carries its own closed form (model.load_path), so only the plates' roots count here; the
top layer's roots in the cap are the cap's (:func:`cap_root_mm_per_N`).
A locked layer's walls carry nothing, so its joints stop with it, as the layer does.

c, a, b and s are fitted, not derived: on the whole-part rung's plates of 102 same-layer designs
over the design box (studies/root_turn_sweep.py, its data in studies/data/: theta 12-58 deg,
t 0.4-1.4 mm, h 1.8-3.6 mm, plates 0.8-2.4 mm; regime 1, where the plates' turn at the heads
vanishes by symmetry), against the layers' and plates' compliance together, what the part's
prediction sees. Over the sweep they leave that within 3.1 % of the rung's (1.1 % rms); the
plates' share alone is within 32 % (13 % rms), one constant spring's 135 %. Between unlike
layers, and next to a locked one, the plate also turns at the wall heads, which this leaves out
(docs/design.md 4.7: the bundled designs, not in the fit, are its check). Pure numpy, no I/O.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mst_cli.model.beams import as_value
from mst_cli.model.cell import wall_centreline_length_mm

# studies/root_turn_sweep.py --fit studies/data/root_turn_*.csv (docs/design.md 4.7): the root's
# spring (c, the exponent a of sin(theta), the exponent b of the wall's slenderness L / t) and
# the plate's squeeze s
FITTED = (0.471, -0.797, -0.285, 0.864)
# the cells and plates those designs span (studies/data/root_turn_box.csv and _shallow.csv); at
# h 1.22-1.5 mm (studies/data/root_turn_low.csv) the joints are up to LOW_CORNER_WORST_REL soft on
# the layers and plates, under steep walls on thick plates (docs/design.md 4.7, "The low corner")
FITTED_BOX = {"theta_deg": (12.0, 58.0), "t_mm": (0.4, 1.4), "h_mm": (1.8, 3.6), "plate_mm": (0.8, 2.4)}
LOW_CORNER_WORST_REL = 0.224


def outside_fitted_box(theta_deg, t_mm, h_mm, plate_mm: float) -> list[int]:
    """The layers (0-based, given as arrays (n,) of theta in degrees, t and h in mm) whose cell, or
    the plates ``plate_mm`` thick they stand on, lie outside the box the constants were fitted on
    (:data:`FITTED_BOX`; a tolerance of 1e-9 at its faces)."""
    n = len(np.atleast_1d(theta_deg))
    if n < 2:
        return []  # one layer stands on no plate

    def outside(key: str, value) -> np.ndarray:
        lo, hi = FITTED_BOX[key]
        v = np.asarray(value, dtype=float)
        return (v < lo - 1e-9) | (v > hi + 1e-9)

    out = outside("plate_mm", np.full(n, plate_mm))
    for key, value in (("theta_deg", theta_deg), ("t_mm", t_mm), ("h_mm", h_mm)):
        out |= outside(key, value)
    return [int(i) for i in np.flatnonzero(out)]


def root_turn_mm_per_N(L_mm, EI_Nmm2, cos_theta, k_Nmm_per_rad) -> Any:
    """A clamped-guided wall's extra vertical compliance (mm/N) when its root turns against
    ``k_Nmm_per_rad`` (module docstring); numbers or arrays."""
    L, EI, k = (np.asarray(a, dtype=float) for a in (L_mm, EI_Nmm2, k_Nmm_per_rad))
    m = (L * L / (2.0 * EI)) / (1.0 / k + L / EI)
    L3 = L**3  # once: a float power is the costliest step over the start's tables
    return as_value(cos_theta**2 * (m * L / k + (m * L * L / 2.0 - L3 / 6.0) / EI - L3 / (12.0 * EI)))


def root_spring_Nmm_per_rad(
    theta_rad, t_mm, L_mm, depth_mm, E_prime_MPa, constants: tuple[float, ...] = FITTED
) -> np.ndarray:
    """A wall's root turning into a TPU plate, M / phi = c sin(theta)^a (L/t)^b E'D t^2, N mm/rad,
    of walls theta (rad), t and their centre line L (mm) long (module docstring)."""
    c, a, b, _ = constants
    t, ED = np.asarray(t_mm, dtype=float), E_prime_MPa * depth_mm
    return c * np.sin(theta_rad) ** a * (L_mm / t) ** b * ED * t**2


def root_joint_mm_per_N(
    theta_rad, t_mm, h_mm, plate_mm, depth_mm, E_prime_MPa, constants: tuple[float, ...] = FITTED
) -> Any:
    """One root of a layer's walls on a plate ``plate_mm`` thick: its turn and the plate's squeeze
    under it, mm/N of the layer's vertical compliance (half a layer's: module docstring), with the
    ``constants`` (c, a, b, s) [default: the fitted ones; studies/root_turn_sweep.py fits them]."""
    theta, t = np.asarray(theta_rad, dtype=float), np.asarray(t_mm, dtype=float)
    ED = E_prime_MPa * depth_mm
    L = wall_centreline_length_mm(theta, t, h_mm)
    k = root_spring_Nmm_per_rad(theta, t, L, depth_mm, E_prime_MPa, constants)
    turn = root_turn_mm_per_N(L, ED * t**3 / 12.0, np.cos(theta), k)
    return as_value(0.5 * turn + 0.25 * constants[3] * plate_mm / (ED * t))


def cap_root_mm_per_N(theta_rad, t_mm, h_mm, depth_mm: float, E_prime_MPa: float) -> Any:
    """The top layer's roots turning into the cap, mm/N: :func:`root_joint_mm_per_N` with the
    squeezed depth the root's own width t (the cap is no thin plate: under a strip t wide the
    load has spread out after about t). Part of the cap's closed form (model.load_path), so it
    stops with the top layer's lock as the cap's bending does."""
    return root_joint_mm_per_N(theta_rad, t_mm, h_mm, t_mm, depth_mm, E_prime_MPa)


def cover_root_mm_per_N(theta_rad, t_mm, h_mm, cover_mm: float, depth_mm: float, E_prime_MPa: float) -> Any:
    """Layer 1's roots turning into the housing's cover, mm/N: :func:`root_joint_mm_per_N` on a
    plate as thick as the cover (it stands on the slot's walls as a plate on the walls below it).
    Part of the cover's closed form (model.load_path); it stops with layer 1's lock, as a plate's
    joints do."""
    return root_joint_mm_per_N(theta_rad, t_mm, h_mm, cover_mm, depth_mm, E_prime_MPa)


def plates_beside(n_layers: int) -> np.ndarray:
    """(n,) how many plates each layer's walls stand on: one for the bottom and the top layer,
    two for those between, none for a single layer (the cover and the cap are not plates)."""
    beside = np.full(n_layers, 2.0)
    beside[0] -= 1.0
    beside[-1] -= 1.0
    return np.maximum(beside, 0.0)


def stack_joints_mm_per_N(theta_rad, t_mm, h_mm, plate_mm: float, depth_mm: float, E_prime_MPa: float) -> Any:
    """(..., n) each layer's joints with the plates beside it, mm/N, of stacks given as arrays
    (..., n) of theta (rad), t and h (mm), bottom to top (:func:`root_joint_mm_per_N` per root)."""
    t = np.asarray(t_mm, dtype=float)
    one = root_joint_mm_per_N(theta_rad, t, h_mm, plate_mm, depth_mm, E_prime_MPa)
    return np.asarray(one) * plates_beside(t.shape[-1])


def joint_scene(scene) -> tuple[float, float, float]:
    """(the plates' thickness, the depth, in mm; E' in MPa) of a model.load_path.MemberScene."""
    return scene.plate_mm, scene.depth_mm, scene.E_prime_MPa


def layer_joints_mm_per_N(scene, theta_rad, t_mm, h_mm) -> Any:
    """:func:`stack_joints_mm_per_N` of the part a model.load_path.MemberScene describes."""
    return stack_joints_mm_per_N(theta_rad, t_mm, h_mm, *joint_scene(scene))
