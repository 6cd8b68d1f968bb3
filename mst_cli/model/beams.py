"""Closed-form beams of the part's members (model.load_path): a beam's centre deflection per
newton under a centred strip load and under two symmetric line loads, simply supported or
clamped, with its shear (Timoshenko), and how far elastically held ends go toward clamped.
Numbers or arrays (broadcast); pure numpy, no I/O. Formulas from the standard beam tables
(Roark's Formulas for Stress and Strain, 7th ed., table 8.1), integrated over the strip here.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def as_value(x) -> Any:
    """A 0-d result as a numpy scalar (a float), an array as itself."""
    return np.asarray(x)[()]


def strip_bending_mm_per_N(span_mm, patch_mm, EI_Nmm2, support: str) -> float | np.ndarray:
    """Centre deflection per newton of a beam of ``span_mm`` under a centred uniform strip load
    ``patch_mm`` wide (clipped to the span), bending only; numbers or arrays (broadcast).

    The influence of a point load at a <= L/2 on the mid-span deflection is a (3L^2 - 4a^2)/(48 EI)
    (simply supported) or a^2 (3L - 4a)/(48 EI) (clamped at both ends); integrated over the strip
    with q = F/c. The limit c -> 0 is F L^3/(48 EI) and F L^3/(192 EI)."""
    L = np.asarray(span_mm, dtype=float)
    c = np.clip(patch_mm, 0.0, L)
    a0, a1 = 0.5 * (L - c), 0.5 * L
    if support == "simple":
        point = L**3 / (48.0 * EI_Nmm2)
        prim = lambda a: 1.5 * L**2 * a**2 - a**4  # noqa: E731  (the antiderivative of a (3L^2 - 4a^2))
    else:
        point = L**3 / (192.0 * EI_Nmm2)
        prim = lambda a: L * a**3 - a**4  # noqa: E731  (of a^2 (3L - 4a))
    narrow = c < 1e-9 * L
    strip = 2.0 * (prim(a1) - prim(a0)) / (np.where(narrow, 1.0, c) * 48.0 * EI_Nmm2)
    return as_value(np.where(narrow, point, strip))


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
    (:func:`_clamped_two_load`); shear P e/(kGA). A load outside the supports (e < 0) hangs on an
    overhang |e| long from a support held level by symmetry: P |e|^3/(3 EI) + P |e|/(kGA)."""
    P, e, L = 0.5, np.asarray(offset_mm, dtype=float), np.asarray(span_mm, dtype=float)
    overhang = P * np.abs(e) ** 3 / (3.0 * EI_Nmm2) + P * np.abs(e) / kGA_N
    inside = np.clip(e, 0.0, 0.5 * L)
    if support == "simple":
        bend = P * inside**2 * (3 * L - 4 * inside) / (6.0 * EI_Nmm2)
    else:
        bend = _clamped_two_load(P, inside, L, EI_Nmm2)
    return as_value(np.where(e < 0, overhang, bend + P * inside / kGA_N))


def _clamped_two_load(P, e, L, EI):
    """Deflection under each of two symmetric loads P at e from the ends of a clamped-clamped beam:
    the simply supported one less the end moments' rotation, M = P e (L - e)/L each end, which
    lift the load point by M e (L - e)/(2 EI)."""
    simple = P * e**2 * (3 * L - 4 * e) / (6.0 * EI)
    M = P * e * (L - e) / L
    return simple - M * e * (L - e) / (2.0 * EI)


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
