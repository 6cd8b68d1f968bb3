"""Forward model of the whole sensor: force -> compression -> gap -> field -> dB/B0.

:func:`regime_kernel` is the vectorised core shared by ``mst simulate`` and the design loop
(so S_i and R_i are computed in one place). :func:`simulate` wraps it for one design and adds
the curves, local slopes, the chip setting and the force resolution. Pure: no I/O.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model import chip as mlx
from mst_cli.model import magnet_field as fld
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.load_path import FINGERTIP_PATCH_MM, Members, capped_units, members
from mst_cli.model.material import CREASE_ONSET_STRETCH, Material
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.past_lock import by_regime
from mst_cli.model.stack import Stack, capped_lock_force_N, layer_caps, run_on, series_displacement_mm

OVERLOAD_REL = 0.25  # simulate's curve runs on past the last lock to (1 + this) x it, out of range

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

GAP_STEP_MM = 1e-4  # central-difference step for d|B|/d gap with the non-closed-form models


def field_magnitude_T(gap_mm: ArrayLike, geometry: SensorGeometry, model: str) -> np.ndarray:
    """|B| at the chip for an array of gaps (the quantity the sensor reads); a gap below 0 (a stack
    whose members let the magnet reach the chip) reads the field at 0: the magnet cannot pass it."""
    gap = np.maximum(np.asarray(gap_mm, dtype=float), 0.0)
    B = fld.field_at_chip_T(gap, geometry.magnet, model, geometry.chip_offset_mm, geometry.magnet_tilt_deg)
    return np.linalg.norm(B, axis=-1)


def regime_kernel(
    k_N_per_mm: ArrayLike,
    d_lock_mm: ArrayLike,
    k_locked_N_per_mm: ArrayLike,
    gap0_mm: ArrayLike,
    field_T: Callable[[np.ndarray], np.ndarray],
    lock_force_N: ArrayLike | None = None,
    members_mm_per_N: ArrayLike = 0.0,
    cap_mm_per_N: ArrayLike | None = None,
    contact: tuple | None = None,
    regime_extra_mm_per_N: ArrayLike | None = None,
    capped_lock_N: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Lock forces and secant sensitivities of many L0 stacks at once, the members that are not
    layers (cap, plates, cover) in series as a linear spring.

    Parameters
    ----------
    k_N_per_mm, d_lock_mm, k_locked_N_per_mm : array (..., n_layers)
    lock_force_N : array (..., n_layers), optional    [default k * d_lock, bilinear layers]
    gap0_mm : array (...)       unloaded magnet-to-chip gap
    field_T : callable          |B| (T) of an array of gaps (mm)
    members_mm_per_N : array (...), optional    the plates' and cover's compliance [default 0: rigid]
    cap_mm_per_N : array (...), optional        the cap's, bending into the top layer's cavity until
                                                it closes there [default None: rigid]
    contact : (C, travel) arrays (...), optional  the part of the members that stops after travel
                                                (the cover landing on the board) [default None]
    regime_extra_mm_per_N : array (..., n), optional  a compliance added in each regime (the
                                                whole-part rung's correction) [default None]
    capped_lock_N : array (..., n), optional    :func:`capped_lock_forces_N` of these, when the
                                                caller has them [default: computed]

    Returns
    -------
    R_sorted_N : (..., n)       lock forces in locking order (regime edges R_1 < ... < R_n)
    S_per_N : (..., n)          secant sensitivity of each regime, (dB/B0 over band) / band
    gap_mm : (..., n+1)         gap at F = 0, R_1, ..., R_n
    B_T : (..., n+1)            |B| at those forces
    """
    k = np.asarray(k_N_per_mm, dtype=float)
    R = k * np.asarray(d_lock_mm, dtype=float) if lock_force_N is None else np.asarray(lock_force_N, dtype=float)
    Rc = capped_lock_forces_N(k, d_lock_mm, R, cap_mm_per_N) if capped_lock_N is None else capped_lock_N
    R_sorted = np.sort(Rc, axis=-1)
    F = np.concatenate([np.zeros(R_sorted.shape[:-1] + (1,)), R_sorted], axis=-1)
    d = series_displacement_mm(
        F, k, d_lock_mm, k_locked_N_per_mm, R, members_mm_per_N, cap_mm_per_N, contact, regime_extra_mm_per_N, Rc
    )
    gap = np.asarray(gap0_mm, dtype=float)[..., None] - d
    B = field_T(gap)
    rel = B / B[..., :1] - 1.0
    S = (rel[..., 1:] - rel[..., :-1]) / np.maximum(F[..., 1:] - F[..., :-1], 1e-300)  # np.diff's, unwrapped
    return R_sorted, S, gap, B


def capped_lock_forces_N(
    k: ArrayLike, d_lock_mm: ArrayLike, R: np.ndarray, cap_mm_per_N: ArrayLike | None
) -> np.ndarray:
    """Every layer's lock force (..., n), each capped one's where its cap (the top layer's cap,
    the plate above a lower one: :func:`~mst_cli.model.stack.layer_caps`) closes its cavity
    (:func:`~mst_cli.model.stack.capped_lock_force_N`); ``cap_mm_per_N`` None: R itself."""
    if cap_mm_per_N is None:
        return R
    return capped_lock_force_N(k, d_lock_mm, R, layer_caps(cap_mm_per_N, np.shape(R)))


@dataclass
class Regime:
    """One force band between two successive lock forces."""

    index: int  # regime number from 1
    layer: int  # index (from 1, bottom to top) of the layer that locks at its end
    force_from_N: float
    force_to_N: float
    k_layer_N_per_mm: float
    d_lock_layer_mm: float
    k_effective_N_per_mm: float  # 1 / stack compliance inside the band
    sensitivity_secant_per_N: float
    sensitivity_min_per_N: float
    sensitivity_max_per_N: float
    force_resolution_N: float  # field resolution / (B0 * S secant)
    force_resolution_worst_N: float  # field resolution / (B0 * S min)
    sensitivity_layers_secant_per_N: float  # the layers' alone, between rigid plates (L0/L2 as verified)


@dataclass
class Response:
    """Everything ``mst simulate`` reports about one design."""

    mechanics: str
    field_model: str
    force_N: np.ndarray
    displacement_mm: np.ndarray
    gap_mm: np.ndarray
    B_T: np.ndarray  # (m, 3) field vector at the chip
    B_abs_T: np.ndarray
    dB_rel: np.ndarray  # (|B| - B0) / B0
    in_range: np.ndarray  # False past the last lock
    regimes: list[Regime]
    B0_T: float
    B_full_T: float  # at the last lock force
    gap0_mm: float
    gap_min_mm: float  # at the last lock force
    remanence_T: float
    chip_setting: mlx.ChipSetting | None
    saturated: bool
    field_resolution_T: float
    noise_uT_rms: float
    warnings: list[str] = field(default_factory=list)
    # the cap, plates and cover in series with the layers (Members.rigid: the layers alone)
    members: Members = field(default_factory=Members.rigid)
    displacement_layers_mm: np.ndarray | None = None  # the layers' compression alone
    dB_rel_layers: np.ndarray | None = None  # the field change of the layers alone (rigid members)

    @property
    def lock_forces_N(self) -> list[float]:
        return [r.force_to_N for r in self.regimes]

    @property
    def max_force_N(self) -> float:
        return self.regimes[-1].force_to_N


def simulate(
    geometry: SensorGeometry,
    material: Material,
    mechanics: str = "spring",
    field_model: str | None = None,
    noise_uT_rms: float = mlx.DEFAULT_NOISE_uT,
    points_per_regime: int = 200,
    overload: float = OVERLOAD_REL,
    whole_part: bool = True,
    patch_mm: float = FINGERTIP_PATCH_MM,
    parts: Members | None = None,
    section: bool = False,
) -> Response:
    """Curves and per-regime figures of one design, by default of the whole part: the cap, plates
    and cover (``parts`` [default: :func:`~mst_cli.model.load_path.members` under a centred press
    ``patch_mm`` wide]) in series with the layers of rung ``mechanics`` (docs/design.md 4.6); the
    layers' own curve rides along (``*_layers*``), ``whole_part=False`` makes it the response.
    Forces run to (1 + overload) x the last lock, ``in_range`` False past it; ``field_model``
    [default: from the chip offset and tilt]; ``noise_uT_rms`` sets the force resolution;
    ``section``: the members corrected by the whole-part rung (model.load_path: section, 4.7)."""
    model = fld.choose_field_model(geometry.chip_offset_mm, geometry.magnet_tilt_deg, field_model)
    laws = layer_laws(geometry.layers, material, mechanics)
    parts = parts or model_members(geometry, material, laws, patch_mm, whole_part, section)
    layer_stack, stack = Stack(laws), part_stack(laws, parts)
    edges = stack.regime_bounds_N
    F, F_last = _force_grid(edges, points_per_regime, overload), edges[-1]
    gap0, (d, gap, Bvec, Babs) = geometry.gap0_mm, _curve(stack, F, geometry, model)
    B0 = float(Babs[0])
    field_T = partial(field_magnitude_T, geometry=geometry, model=model)  # |B| (T) of gaps (mm)
    slope, band = _local_slope(stack, F, gap, field_T, B0)
    gap_edges = gap0 - stack.displacement_mm(edges)
    S, degenerate, B_edges = _secant_sensitivities(stack, gap_edges, field_T, B0)
    B_full = float(B_edges[-1])
    layers_only = _layers_only(layer_stack, F, gap0, field_T, B0)
    setting, saturated, res_T = _chip(Bvec[F <= F_last + 1e-12], B_full, noise_uT_rms)
    return Response(
        mechanics=mechanics,
        field_model=model,
        force_N=F,
        displacement_mm=d,
        gap_mm=gap,
        B_T=Bvec,
        B_abs_T=Babs,
        dB_rel=Babs / B0 - 1.0,
        in_range=F <= F_last * (1 + 1e-12),
        regimes=_regimes(stack, S, degenerate, (slope, band), (res_T, B0), layers_only[2]),
        B0_T=B0,
        B_full_T=B_full,
        gap0_mm=gap0,
        gap_min_mm=float(gap_edges[-1]),
        remanence_T=geometry.magnet.remanence_T,
        chip_setting=setting,
        saturated=saturated,
        field_resolution_T=res_T,
        noise_uT_rms=noise_uT_rms,
        warnings=_warnings(stack, degenerate, B_full if saturated else None, gap0),
        members=parts,
        displacement_layers_mm=layers_only[0],
        dB_rel_layers=layers_only[1],
    )


def model_members(
    geometry: SensorGeometry, material: Material, laws: tuple, patch_mm: float, whole_part: bool, section: bool
) -> Members:
    """:func:`simulate`'s members: rigid (the layers alone), the closed form, or the closed form
    corrected by the whole-part rung (``section``)."""
    if not whole_part:
        return Members.rigid(patch_mm, len(laws) - 1)
    if section:
        from mst_cli.model.mechanics.whole_part import section_members  # deferred: scikit-fem's rung

        return section_members(geometry, material, laws, patch_mm)[0]
    return members(geometry, material, patch_mm)


def _curve(stack: Stack, F: np.ndarray, geometry: SensorGeometry, model: str) -> tuple:
    """(drop mm, gap mm, B vector (m, 3) T, |B| T) at the forces ``F``; past a gap of 0 the field
    is the field at 0 (:func:`field_magnitude_T`)."""
    d = stack.displacement_mm(F)
    gap = geometry.gap0_mm - d
    at = np.maximum(gap, 0.0)
    Bvec = fld.field_at_chip_T(at, geometry.magnet, model, geometry.chip_offset_mm, geometry.magnet_tilt_deg)
    return d, gap, Bvec, np.linalg.norm(Bvec, axis=-1)


def _chip(B_in_range_T: np.ndarray, B_full_T: float, noise_uT_rms: float) -> tuple:
    """(the MLX90393 setting for the in-range fields (m, 3) in T, saturated?, field resolution T)."""
    Bmax_vec = np.abs(B_in_range_T).max(axis=0)
    setting = mlx.choose_setting(max(Bmax_vec[0], Bmax_vec[1]), Bmax_vec[2])
    saturated = setting is None or B_full_T >= mlx.SATURATION_T
    return setting, saturated, mlx.field_resolution_T(setting, noise_uT_rms) if setting else float("nan")


def part_stack(laws: tuple, parts: Members) -> Stack:
    """The whole part's stack: the cap bends into the top layer's cavity until it closes there
    (:class:`~mst_cli.model.load_path.CappedLayer`), each plate into the cavity of the layer
    under it likewise, the cover in series, its bending over the slot until it lands on the board,
    and per regime the plates over locked layers (model.past_lock) and the whole-part rung's
    correction when the members carry one."""
    capped = tuple(capped_units(laws, parts))
    extra: tuple = parts.regime_extra_mm_per_N
    if parts.locked_plates_mm_per_N:
        lock_N = [u.lock_force_N for u in capped]
        locked = by_regime(parts.locked_plates_mm_per_N, lock_N, parts.two_locked_plates_mm_per_N or None)
        extra = tuple(float(v) for v in np.add(locked, run_on(extra)))
    C, travel, C_locked, delta = parts.cover_contact
    return Stack(capped, parts.cover_mm_per_N, C, travel, extra, C_locked, delta)


def _layers_only(
    stack: Stack, F: np.ndarray, gap0: float, field_T: Callable[[np.ndarray], np.ndarray], B0: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(compression, dB/B0 at the forces ``F``, secant S per regime of its own lock forces) of the
    layers alone between rigid plates: the curve the ladder verifies layer by layer."""
    layers = stack
    d = layers.displacement_mm(F)
    gap_edges = gap0 - layers.displacement_mm(layers.regime_bounds_N)
    S = _secant_sensitivities(layers, gap_edges, field_T, B0)[0]
    return d, field_T(gap0 - d) / B0 - 1.0, S


def _force_grid(edges: np.ndarray, points_per_regime: int, overload: float) -> np.ndarray:
    """Forces (N): uniform inside each regime, the edges included exactly, then the overload."""
    n = len(edges) - 1
    pieces = [np.linspace(edges[i], edges[i + 1], points_per_regime, endpoint=False) for i in range(n)]
    F_last = edges[-1]
    pieces.append(np.linspace(F_last, F_last * (1.0 + overload), max(points_per_regime // 4, 2)))
    return np.concatenate(pieces)


def _local_slope(
    stack: Stack, F: np.ndarray, gap: np.ndarray, field_T: Callable[[np.ndarray], np.ndarray], B0: float
) -> tuple[np.ndarray, np.ndarray]:
    """(slope, band) at every force: d(dB/B0)/dF (1/N) = (1/B0) d|B|/dgap * dgap/dF, with dgap/dF
    = -compliance, and the index of the band each force lies in (n: past the last lock)."""
    edges = stack.regime_bounds_N
    n = len(edges) - 1
    dB_dgap = (field_T(gap + GAP_STEP_MM) - field_T(gap - GAP_STEP_MM)) / (2 * GAP_STEP_MM)
    # compliance is one-sided at the lock forces: evaluate it just inside each point's band
    band = np.clip(np.searchsorted(edges, F, side="right") - 1, 0, n)
    lo_b, hi_b = edges[band], np.append(edges, np.inf)[band + 1]
    width = np.where(np.isfinite(hi_b), hi_b - lo_b, edges[-1])
    F_inside = np.clip(F, lo_b + 1e-9 * width, hi_b - 1e-9 * width)
    compliance = stack.local_compliance_mm_per_N(F_inside)  # one lookup for all samples: O(n) in layers
    return -dB_dgap * compliance / B0, band


def _secant_sensitivities(
    stack: Stack, gap_edges: np.ndarray, field_T: Callable[[np.ndarray], np.ndarray], B0: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(S per regime in 1/N, which regimes have zero width, |B| in T at the regime edges), with
    ``B0`` the unloaded |B| (T) of the curve.

    From the stack itself, so they hold for every mechanics rung (regime_kernel gives the same
    numbers for L0 layers; the design loop uses it)."""
    edges = stack.regime_bounds_N
    B_edges = field_T(gap_edges)
    widths = np.diff(edges)
    degenerate = widths <= 1e-9 * edges[-1]
    S = np.diff(B_edges / B_edges[0] - 1.0) / np.where(degenerate, 1.0, widths)
    for i in np.flatnonzero(degenerate):
        # zero-width band: the secant's limit is the local slope at that force
        dB = (field_T(gap_edges[i] + GAP_STEP_MM) - field_T(gap_edges[i] - GAP_STEP_MM)) / (2 * GAP_STEP_MM)
        # squeeze: the cylinder model gives shape (1,) for one gap, which S[i] cannot hold
        S[i] = -float(np.squeeze(dB)) * stack.band_start_compliance_mm_per_N(int(i)) / B0
    return S, degenerate, B_edges


def _regimes(
    stack: Stack,
    S: np.ndarray,
    degenerate: np.ndarray,
    slopes: tuple[np.ndarray, np.ndarray],
    resolution: tuple[float, float],
    S_layers: np.ndarray,
) -> list[Regime]:
    """Every force band's figures; ``slopes`` = (local slope, band of each force sample),
    ``resolution`` = (the chip's field resolution, B0), both in T; ``S_layers`` the layers'
    own secant sensitivities (rigid members)."""
    slope, band = slopes
    res_T, B0 = resolution
    edges, order, laws = stack.regime_bounds_N, stack.lock_order, stack.layers
    n = len(edges) - 1
    mid_compliance = np.asarray(stack.local_compliance_mm_per_N(0.5 * (edges[:-1] + edges[1:])))  # one lookup, not n
    # slope extremes of every band in one pass: F ascends, so each band's samples are one run,
    # [starts[i], starts[i + 1]); band n is the overload past the last lock, never empty
    starts = np.minimum(np.searchsorted(band, np.arange(n + 1)), len(band) - 1)
    present = np.diff(starts) > 0
    slope_min = np.minimum.reduceat(slope, starts)
    slope_max = np.maximum.reduceat(slope, starts)
    regimes = []
    for i in range(n):
        s_lo, s_hi = (S[i], S[i]) if degenerate[i] or not present[i] else (slope_min[i], slope_max[i])
        j = int(order[i])
        regimes.append(
            Regime(
                index=i + 1,
                layer=j + 1,
                force_from_N=float(edges[i]),
                force_to_N=float(edges[i + 1]),
                k_layer_N_per_mm=float(laws[j].k_N_per_mm),
                d_lock_layer_mm=float(laws[j].d_lock_mm),
                k_effective_N_per_mm=1.0 / float(mid_compliance[i]),
                sensitivity_secant_per_N=float(S[i]),
                sensitivity_min_per_N=float(s_lo),
                sensitivity_max_per_N=float(s_hi),
                force_resolution_N=res_T / (B0 * float(S[i])) if S[i] > 0 else math.inf,  # 0: the magnet on the chip
                force_resolution_worst_N=res_T / (B0 * float(s_lo)) if s_lo > 0 else math.inf,
                sensitivity_layers_secant_per_N=float(S_layers[i]),
            )
        )
    return regimes


def _warnings(stack: Stack, degenerate: np.ndarray, saturated_at_T: float | None, gap0_mm: float) -> list[str]:
    """Zero-width regimes, a lock order other than the file's, a saturated chip (|B| in T), the
    magnet reaching the chip inside the range (the stack's drop reaching ``gap0_mm``)."""
    edges, order = stack.regime_bounds_N, stack.lock_order
    warnings = []
    if float(stack.displacement_mm(edges[-1])) >= gap0_mm:
        warnings.append(
            f"the magnet reaches the chip at {float(stack.force_N(gap0_mm)):.4g} N, inside the range (to "
            f"{edges[-1]:.4g} N): the layers and members give more than the {gap0_mm:.3g} mm gap, and past it "
            "the field stays the chip's at contact (a sensitivity of 0)"
        )
    for i in np.flatnonzero(degenerate):
        warnings.append(
            f"layers {', '.join(str(int(j) + 1) for j in order[i - 1 : i + 1])} lock at the "
            f"same force {edges[i + 1]:.4g} N: regime {i + 1} has zero width (its S is "
            f"the local slope there)"
        )
    if list(order) != list(range(len(order))):
        warnings.append(
            "layers do not lock bottom-to-top in file order: lock order is " + ", ".join(str(j + 1) for j in order)
        )
    if saturated_at_T is not None:
        warnings.append(
            f"field at full load {saturated_at_T * 1e3:.1f} mT exceeds the MLX90393's range "
            f"({mlx.SATURATION_T * 1e3:.0f} mT saturation): move the magnet away"
        )
    return warnings + _crease_warnings(stack)


def _crease_warnings(stack: Stack) -> list[str]:
    """One line per continuum-rung layer whose wall is squeezed past the crease onset at its lock."""
    warnings = []
    for i, law in enumerate(stack.layers, start=1):
        stretch = getattr(law, "min_stretch_at_lock", None)  # L2's laws carry it
        if stretch is not None and stretch < CREASE_ONSET_STRETCH:
            warnings.append(
                f"layer {i}: its wall is squeezed to a stretch of {stretch:.2f} at the lock, past the "
                f"{CREASE_ONSET_STRETCH:g} at which its outer root creases; the continuum model cannot form "
                f"the crease, so R_{i} = {law.lock_force_N:.4g} N is an upper bound, a few per cent high "
                "(README: Models)"
            )
    return warnings
