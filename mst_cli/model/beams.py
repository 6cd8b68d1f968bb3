"""Closed-form beams of the part's members (model.load_path): a beam's centre deflection per
newton under a centred strip load and under two symmetric line loads, simply supported or
clamped, with its shear (Timoshenko), how far elastically held ends go toward clamped, and a
member's section (E'I, kGA).
Numbers or arrays (broadcast); pure numpy, no I/O. Formulas from the standard beam tables
(Roark's Formulas for Stress and Strain, 7th ed., table 8.1), integrated over the strip here.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

SHEAR_FACTOR = 5.0 / 6.0  # kappa of a rectangular section
# an end built into a body of its own modulus turns against pi/8 E'D d^2, d the end's thickness: a
# rigid flat punch d wide tilted on an elastic half-plane (Johnson, Contact Mechanics, 1985, ch. 2)
END_BUILT_IN = math.pi / 8.0


def as_value(x) -> Any:
    """A 0-d result as a numpy scalar (a float), an array as itself."""
    return np.asarray(x)[()]


def strip_bending_mm_per_N(span_mm, patch_mm, EI_Nmm2, support: str) -> float | np.ndarray:
    """Centre deflection per newton of a beam of ``span_mm`` under a centred uniform strip load
    ``patch_mm`` wide (clipped to the span), bending only; numbers or arrays (broadcast).

    The influence of a point load at a <= L/2 on the mid-span deflection is a (3L^2 - 4a^2)/(48 EI)
    (simply supported) or a^2 (3L - 4a)/(48 EI) (clamped at both ends); integrated over the strip
    with q = F/c. The limit c -> 0 is F L^3/(48 EI) and F L^3/(192 EI)."""
    simple, clamped = strip_bending_pair_mm_per_N(span_mm, patch_mm, EI_Nmm2)
    return simple if support == "simple" else clamped


def strip_bending_pair_mm_per_N(span_mm, patch_mm, EI_Nmm2) -> tuple:
    """(simply supported, clamped) :func:`strip_bending_mm_per_N`, their shared terms computed
    once (the design loop's members call both on small batches: numpy's cost per call)."""
    L = np.asarray(span_mm, dtype=float)
    c = np.clip(patch_mm, 0.0, L)
    a0, a1 = 0.5 * (L - c), 0.5 * L
    L3, a0_4, a1_4 = L**3, a0**4, a1**4
    narrow = c < 1e-9 * L
    strip_N = np.where(narrow, 1.0, c) * 48.0 * EI_Nmm2
    L2 = 1.5 * L**2  # the antiderivatives of a (3L^2 - 4a^2) and a^2 (3L - 4a): 1.5 L^2 a^2 - a^4, L a^3 - a^4
    simple = 2.0 * ((L2 * a1**2 - a1_4) - (L2 * a0**2 - a0_4)) / strip_N
    clamped = 2.0 * ((L * a1**3 - a1_4) - (L * a0**3 - a0_4)) / strip_N
    return (
        as_value(np.where(narrow, L3 / (48.0 * EI_Nmm2), simple)),
        as_value(np.where(narrow, L3 / (192.0 * EI_Nmm2), clamped)),
    )


def strip_shear_mm_per_N(span_mm, patch_mm, kGA_N) -> float | np.ndarray:
    """Centre deflection per newton from shear (Timoshenko), any symmetric supports: the shear
    force is F/2 up to the strip and falls linearly to 0 across it, so delta = F (L - c/2)/(4 kGA)."""
    c = np.clip(patch_mm, 0.0, span_mm)
    return as_value((span_mm - 0.5 * c) / (4.0 * kGA_N))


def two_load_mm_per_N(span_mm, offset_mm, EI_Nmm2, kGA_N, support: str) -> float | np.ndarray:
    """Deflection per newton (total force F, F/2 at each load) under two symmetric line loads
    ``offset_mm`` inside each support of a beam of ``span_mm`` (a plate loaded by the walls above
    it, held by the walls below); numbers or arrays. Bending under each load: P e^2 (3L - 4e)/(6 EI)
    simply supported (four-point bending), less the end moments' lift when clamped
    (:func:`two_load_pair_mm_per_N`); shear P e/(kGA). A load outside the supports (e < 0) hangs on an
    overhang |e| long from a support held level by symmetry: P |e|^3/(3 EI) + P |e|/(kGA)."""
    simple, clamped = two_load_pair_mm_per_N(span_mm, offset_mm, EI_Nmm2, kGA_N)
    return simple if support == "simple" else clamped


def two_load_pair_mm_per_N(span_mm, offset_mm, EI_Nmm2, kGA_N) -> tuple:
    """(simply supported, clamped) :func:`two_load_mm_per_N`, their shared terms computed once.
    Clamped: the simply supported deflection less the end moments' rotation, M = P e (L - e)/L
    each end, which lift the load point by M e (L - e)/(2 EI)."""
    P, e, L = 0.5, np.asarray(offset_mm, dtype=float), np.asarray(span_mm, dtype=float)
    overhang = P * np.abs(e) ** 3 / (3.0 * EI_Nmm2) + P * np.abs(e) / kGA_N
    inside = np.clip(e, 0.0, 0.5 * L)
    bend = P * inside**2 * (3 * L - 4 * inside) / (6.0 * EI_Nmm2)
    M = P * inside * (L - inside) / L
    clamped = bend - M * inside * (L - inside) / (2.0 * EI_Nmm2)
    shear, beyond = P * inside / kGA_N, e < 0
    return as_value(np.where(beyond, overhang, bend + shear)), as_value(np.where(beyond, overhang, clamped + shear))


def offset_pair_mm_per_N(
    near_mm, offset_mm, EI_Nmm2, kGA_N, k_rot_Nmm_per_rad, overhang=None, root_Nmm_per_rad=None
) -> Any:
    """The drop per newton (total F, F/2 at each) of two symmetric line loads at |x| = near + |e|
    relative to two symmetric supports at |x| = near (``offset_mm`` e < 0), or of loads at near
    relative to supports at near + e (e > 0): a plate loaded by the walls above it and held by the
    walls below. Either way the free body is the same (its mirror image about the plate's
    mid-plane swaps loads and supports): the span between the nearer pair carries the moment
    P |e| less what the springs ``k_rot`` there take as it turns (N mm/rad, the walls' restraint
    of the pad's turn, all of it at the nearer pair), and the rest bends as a cantilever:
    P (rho e^2 near + |e|^3/3)/EI + P |e|/kGA, rho = 1/(1 + k near/EI) (the span's half turns by
    M near/EI under its end moment M). k = 0, e > 0 is the simply supported four-point beam
    (:func:`two_load_pair_mm_per_N`, span 2 (near + e)); k infinite, a cantilever |e| long.
    ``overhang``: the cantilever's own (E'I, kGA) when its section is not the span's (the
    plate between unlike layers: only the outer layer's pad reaches past the nearer pair).
    ``root_Nmm_per_rad``: the cantilever's root turning against a spring there (its end built
    into the span's thicker section, not held), P e^2 / k more; None: held."""
    P, e = 0.5, np.abs(np.asarray(offset_mm, dtype=float))
    near, EI = np.asarray(near_mm, dtype=float), np.asarray(EI_Nmm2, dtype=float)
    EI_out, kGA_out = (EI, kGA_N) if overhang is None else overhang
    rho = 1.0 / (1.0 + np.asarray(k_rot_Nmm_per_rad, dtype=float) * near / EI)
    drop = P * (rho * e * e * near / EI + e**3 / 3.0 / EI_out) + P * e / kGA_out
    if root_Nmm_per_rad is not None:
        drop = drop + P * e * e / np.asarray(root_Nmm_per_rad, dtype=float)
    return as_value(drop)


def end_fixity(k_rot_Nmm_per_rad, EI_Nmm2, span_mm) -> float | np.ndarray:
    """The share of the clamped end moments a symmetric load on a beam of ``span_mm`` gets when
    each end turns against a rotational spring ``k_rot`` (N mm/rad): the beam turns both ends
    equally and oppositely with 2 EI / L, so M = M_clamped k / (k + 2 EI / L). 0: simply
    supported, 1: clamped (k infinite); the deflection is simple - fixity x (simple - clamped),
    exactly, by superposition."""
    k = np.asarray(k_rot_Nmm_per_rad, dtype=float)
    beam = 2.0 * np.asarray(EI_Nmm2, dtype=float) / np.asarray(span_mm, dtype=float)
    held = np.isinf(k)
    finite = np.where(held, 0.0, k)
    return as_value(np.where(held, 1.0, finite / (finite + beam)))


def section_EI_kGA(
    depth_mm: float,
    thickness_mm,
    E_prime_MPa: float,
    G_MPa: float,
    hole_width_mm: float = 0.0,
    hole_z_mm: tuple = (0.0, 0.0),
    insert=None,
    insert_z_mm=None,
) -> tuple:
    """(E'I in N mm^2, kappa G A in N) of a rectangle ``depth_mm`` x ``thickness_mm`` less a hole
    ``hole_width_mm`` wide (along the depth) between heights ``hole_z_mm`` above its bottom, and
    with an optional bonded ``insert`` (:class:`~mst_cli.model.load_path.Insert`, its underside at
    ``insert_z_mm`` [default: its own ``z_mm``] above the bottom, over the whole depth, replacing
    the TPU there): the transformed section about its own neutral axis. Thicknesses and heights
    may be arrays."""
    b, T = depth_mm, thickness_mm
    if not hole_width_mm and insert is None:  # a plain rectangle (most calls of the design loop)
        return as_value((b * E_prime_MPa) * (T**3 / 12.0)), as_value(SHEAR_FACTOR * G_MPa * (b * np.asarray(T)))
    # strips (z0, z1, width x modulus), parallel axes about the modulus-weighted centroid; a hole
    # of no width adds exactly nothing to any sum (a plate's or the cover's section: not computed)
    strips = [(0.0, T, b * E_prime_MPa)]
    if hole_width_mm:
        strips.append((hole_z_mm[0], hole_z_mm[1], -hole_width_mm * E_prime_MPa))
        hole_height = np.maximum(np.subtract(hole_z_mm[1], hole_z_mm[0]), 0.0)
        shear = SHEAR_FACTOR * G_MPa * (b * np.asarray(T) - hole_width_mm * hole_height)
    else:
        shear = SHEAR_FACTOR * G_MPa * (b * np.asarray(T))
    if insert is not None:
        z0 = insert.z_mm if insert_z_mm is None else insert_z_mm
        z1 = z0 + insert.thickness_mm
        bi = b if insert.depth_mm is None else min(insert.depth_mm, b)  # the plate's own depth
        strips.append((z0, z1, bi * (insert.modulus_MPa - E_prime_MPa)))
        shear = shear + SHEAR_FACTOR * bi * insert.thickness_mm * (insert.shear_modulus_MPa - G_MPa)
    # the strips' sums, in order (plain loops: the design loop's small batches); each strip's
    # height and mid-height once (w dz 0.5 (z0 + z1) is w dz x mid to the bit: halving is exact)
    EA = zc_EA = EI = 0
    heights = []
    for z0, z1, w in strips:
        dz, mid = z1 - z0, 0.5 * (z0 + z1)
        w_dz = w * dz
        EA = EA + w_dz
        zc_EA = zc_EA + w_dz * mid
        heights.append((dz, mid, w))
    zc = zc_EA / EA
    for dz, mid, w in heights:
        EI = EI + w * (dz**3 / 12.0 + dz * (mid - zc) ** 2)
    return as_value(EI), as_value(shear)


@functools.lru_cache(maxsize=64)
def plain_section(depth_mm: float, thickness_mm: float, E_prime_MPa: float, G_MPa: float) -> tuple:
    """:func:`section_EI_kGA` of a plain rectangle of given numbers: the cover alone's, the same
    for every candidate of a design run (computed once, not once a kernel call)."""
    return section_EI_kGA(depth_mm, thickness_mm, E_prime_MPa, G_MPa)
