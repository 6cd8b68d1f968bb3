"""Why a spec cannot be met: contradictions (exit 2) and physical limits (exit 1).

The split is deliberate and documented in ``mst design --help``:

* **contradictory input -> exit 2** (:func:`check_contradictions`, raises
  :class:`~mst_cli.errors.InputError` naming the field): statements in the file that no
  physics can reconcile -- lock forces that do not increase (they are cumulative thresholds,
  R_1 < R_2 < ...), or that increase by less than the file's own ``lock_margin_rel`` allows
  even at the edges of the tolerance; variable bounds that leave no printable cell for the
  file's printer; a height limit below the stack of thinnest layers.
* **physically unreachable -> exit 1** (:func:`diagnose`): the spec is consistent but this
  magnet, material and printer cannot give it. The optimiser has then still returned its
  nearest design; the diagnosis names the reason: a total field change beyond what the magnet
  gives over the gaps the geometry allows, forces outside what any printable layer within the
  bounds reaches, sensitivities that rise with force, or else the target that misses most and
  the constraints that hold the design back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.design.problem import DesignProblem
from mst_cli.errors import InputError
from mst_cli.model.cell import cell_margins_mm
from mst_cli.model.load_path import moving_share
from mst_cli.model.mechanics.spring import contact_stiffness_N_per_mm

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

GRID_POINTS = 41  # per variable, for the printable lock-force range
ACTIVE_TOL = 0.02  # a scaled constraint within this of zero counts as binding


def check_contradictions(problem: DesignProblem) -> None:
    """Raise InputError for a spec that contradicts itself (exit code 2)."""
    R, tol, m = problem.R_target, problem.tolerance_rel, problem.lock_margin_rel
    for i in range(1, problem.n):
        if R[i] <= R[i - 1]:
            raise InputError(
                f"layers[{i}].target_range_N",
                float(R[i]),
                f"must be greater than layers[{i - 1}].target_range_N = {R[i - 1]:g} N: "
                "regime i ends where layer i locks, so the ranges are cumulative force "
                "thresholds that increase from the bottom layer to the top one",
            )
        # the largest ratio the tolerance allows must still reach the lock margin
        if R[i] * (1 + tol) < (1 + m) * R[i - 1] * (1 - tol):
            need = (1 + m) * R[i - 1] * (1 - tol) / (1 + tol)
            raise InputError(
                f"layers[{i}].target_range_N",
                float(R[i]),
                f"must be >= {need:.4g} N: layers lock in order with design.lock_margin_rel "
                f"= {m:g} (R_{i + 1} >= {1 + m:g} R_{i}) within the tolerance "
                f"{tol:g}; spread the ranges or lower design.lock_margin_rel",
            )
    pr, fam = problem.printer, problem.family
    t_lo, t_hi = problem.lo[1], problem.hi[1]
    h_lo, h_hi = problem.lo[2], problem.hi[2]
    if t_hi < pr.min_wall_mm:
        raise InputError(
            "design.t_mm_bounds",
            [float(t_lo), float(t_hi)],
            f"the upper bound must reach the printable minimum wall printer.min_wall_mm = {pr.min_wall_mm:g} mm",
        )
    t_min = max(t_lo, pr.min_wall_mm)
    need_h = 2 * t_min + max(pr.min_gap_mm, fam.contact_allowance_mm)
    if h_hi < need_h:
        raise InputError(
            "design.h_mm_bounds",
            [float(h_lo), float(h_hi)],
            f"the upper bound must be >= {need_h:g} mm: two walls of at least "
            f"{t_min:g} mm plus a printable cavity of {pr.min_gap_mm:g} mm",
        )
    if problem.max_height_mm is not None:
        lowest = problem.height_offset_mm + problem.n * max(h_lo, need_h)
        if problem.max_height_mm < lowest:
            raise InputError(
                "design.max_height_mm",
                problem.max_height_mm,
                f"must be >= {lowest:.4g} mm: the housing plus {problem.n} layers of the smallest printable height",
            )


@dataclass(frozen=True)
class Limits:
    """What this magnet, material and printer can give at all (used to explain failures)."""

    field_change_needed: float  # sum S*_i (R*_i - R*_(i-1)), the spec's B_full/B0 - 1
    field_change_needed_min: float  # the same with every target at the tolerance's edge
    field_change_max: float  # upper bound over every geometry in the bounds
    gap_min_mm: float  # smallest magnet-chip gap any design can reach (bound)
    gap0_max_mm: float  # largest unloaded gap within the bounds
    R_min_N: float  # lock-force range of printable single layers (grid)
    R_max_N: float
    R_min_at: tuple  # (theta_deg, t_mm, h_mm) of those extremes
    R_max_at: tuple


def limits(problem: DesignProblem) -> Limits:
    """Bounds on the total field change and on the lock force of one printable layer.

    Field change: S_i is a secant, so sum S_i (R_i - R_(i-1)) = B(gap at the last lock)/B0 - 1
    exactly. B0 is at least B at the largest unloaded gap (every h at its upper bound, or the
    height limit); a locked layer keeps 2t + contact allowance of its height, so the gap at the
    last lock is at least the housing's share + n (2 t_min + allowance) minus what the locked
    layers still compress under the last force (at most F_n / k_locked,min each); and |B| never
    exceeds the saturation limit. Lock force range: a dense grid over the bounds, keeping the
    printable cells only (so an estimate from the inside: the true extremes lie a little beyond).
    """
    n, fam, pr = problem.n, problem.family, problem.printer
    S, R, tol = problem.S_target, problem.R_target, problem.tolerance_rel
    dR = np.diff(np.concatenate([[0.0], R]))
    needed = float(np.sum(S * dR))
    R_lo_edge = R * (1 - tol)
    R_hi_prev = np.concatenate([[0.0], R[:-1] * (1 + tol)])
    needed_min = float(np.sum(S * (1 - tol) * np.maximum(R_lo_edge - R_hi_prev, 0.0)))

    t_min = max(problem.lo[1], pr.min_wall_mm)
    h_sum_max = n * problem.hi[2]
    if problem.max_height_mm is not None:
        h_sum_max = min(h_sum_max, problem.max_height_mm - problem.height_offset_mm)
    gap0_max = float(problem.gap0_mm(h_sum_max))  # as built (printer.gap_offset_mm)
    theta_lo = math.radians(problem.lo[0])
    # locked stiffness = walls + contact column >= the contact column alone
    k_locked_min = float(contact_stiffness_N_per_mm(theta_lo, problem.hi[1], fam.width_mm, fam.depth_mm, problem.E_MPa))
    locked_give = n * R[-1] * (1 + tol) / k_locked_min
    t_printed = t_min + problem.wall_offset_mm
    gap_min = float(problem.gap0_mm(0.0) + n * (2 * t_printed + fam.contact_allowance_mm) - locked_give)
    gaps = np.linspace(max(gap_min, 1e-3), max(gap0_max, gap_min + 1e-3), 400)
    B = problem.field_T(gaps)
    field_max = float(min(B.max(), problem.B_limit_T) / B.min() - 1.0)

    axes = [np.linspace(problem.lo[j], problem.hi[j], GRID_POINTS) for j in range(3)]
    th, t, h = (a.ravel() for a in np.meshgrid(*axes, indexing="ij"))
    margins = cell_margins_mm(
        np.radians(th), t, h, fam.width_mm, fam.contact_allowance_mm, pr.min_wall_mm, pr.min_gap_mm, pr.nozzle_mm
    )
    ok = np.all(margins >= 0.0, axis=-1)
    Rl = problem.responses(th[ok, None], t[ok, None], h[ok, None])[0] if ok.any() else None
    if Rl is None:
        return Limits(needed, needed_min, field_max, gap_min, gap0_max, math.nan, math.nan, (), ())
    Rl = Rl[:, 0]
    i_lo, i_hi = int(np.argmin(Rl)), int(np.argmax(Rl))
    cells = np.stack([th[ok], t[ok], h[ok]], axis=-1)
    return Limits(
        needed,
        needed_min,
        field_max,
        gap_min,
        gap0_max,
        float(Rl[i_lo]),
        float(Rl[i_hi]),
        tuple(float(x) for x in cells[i_lo]),
        tuple(float(x) for x in cells[i_hi]),
    )


def diagnose(
    problem: DesignProblem, u: ArrayLike, achieved_S: ArrayLike, achieved_R: ArrayLike, checks: dict[str, str]
) -> tuple[str, list[str]]:
    """(binding, reasons) for a design that misses: the first reason is the one that binds.

    ``u`` is the written design's normalised point; ``achieved_S`` (1/N) and ``achieved_R`` (N),
    one per layer, come from the forward model on it; ``checks`` maps a failed constraint name
    to its message (from the verification).
    """
    reasons = _members_dominate(problem, u) + _beyond_limits(problem) + _rising_sensitivities(problem, achieved_S)
    reasons += [
        (name, reason + _members_share(problem, u, achieved_S, achieved_R))
        for name, reason in _worst_miss(problem, u, achieved_S, achieved_R)
    ]
    for name, message in checks.items():
        reasons.append((name, message))
    if not reasons:  # nothing failed: the caller should not have asked
        return "", []
    return reasons[0][0], [r for _, r in reasons]


def _members_by_regime(problem: DesignProblem, u: ArrayLike, edges_N: ArrayLike) -> tuple[dict, float, np.ndarray]:
    """({member: the compliance (n,) in mm/N it adds in each regime between ``edges_N`` (0, R_1,
    ..., R_n)}, (d|B|/dgap)/B0 (1/mm) at the unloaded gap, the layers' d_lock (n,)) of the design
    at ``u``, as the forward model moves them (model.load_path.moving_share, the rule the report's
    shares use too): the cap bends until the top layer locks (every regime), a plate until the
    layer under it locks (the regimes up to that layer's), the cover's slot walls always and its
    bending over the slot until it lands on the board (:meth:`DesignProblem.member_parts`)."""
    theta, t, h = problem.to_physical(u)
    _, d_lock, _, _ = problem.layer_laws(theta, t, h)
    cap, plates, cover = problem.member_parts(theta, t, h, edges_N)
    edges = np.asarray(edges_N, dtype=float)
    # plate j bends until layer j locks, the cap until the top one: the design's locks R_1 < ... < R_n
    caps = np.append(plates, cap)[:, None] * moving_share(edges[1:], edges)  # (layers, regimes)
    parts = {"cap": caps[-1], "plates": caps[:-1].sum(axis=0), "housing's cover": np.asarray(cover, float)}
    gap0 = float(problem.gap0_mm(float(np.sum(h))))
    B = problem.field_T(np.array([gap0 - 1e-4, gap0, gap0 + 1e-4]))
    per_mm = float((B[0] - B[2]) / (2e-4 * B[1]))  # (d|B|/dgap)/B0: S over the compliance, 1/mm
    return parts, per_mm, d_lock


def _members_dominate(problem: DesignProblem, u: ArrayLike) -> list[tuple[str, str]]:
    """(name, reason) when the members outside the layers make a target unreachable at the nearest
    design, which no layer can help (docs/design.md 4.6): the cap closes the top layer's cavity by
    its own bending before the target R_n (below d_lock / C_cap), or the members alone give a
    regime more field change per newton than its target (each member while it still moves in that
    target band, :func:`_members_by_regime`; the tangent at the unloaded gap, below the secant as
    the gap closes)."""
    if not problem.whole_part:
        return []
    parts, per_mm, d_lock = _members_by_regime(problem, u, np.concatenate([[0.0], problem.R_target]))
    cap = float(parts["cap"][0])
    tol, n = problem.tolerance_rel, problem.n
    if cap > 0 and problem.R_target[-1] * (1 - tol) > d_lock[-1] / cap:
        return [
            (
                "the cap dominates",
                f"the cap is too soft: it bends {cap:.3g} mm/N into layer {n}'s cavity and closes it by itself "
                f"at {d_lock[-1] / cap:.3g} N, below the target R_{n} = {problem.R_target[-1]:g} N; a stiffer cap "
                "(an insert) is needed (docs/design.md 4.6)",
            )
        ]
    held = problem.regime_extra_mm_per_N  # model.load_path section: the whole-part rung's correction
    measured = held is not None and len(held) == n
    extra = np.asarray(held, dtype=float) if measured else np.zeros(n)
    floor = per_mm * (sum(parts.values()) + (extra if measured else 0.0))  # S (1/N) of the members alone
    over = np.flatnonzero(floor > problem.S_target * (1 + tol))
    if not len(over):
        return []
    i = int(over[-1])
    if measured:  # the rung measures the members outside the layers together, not one by one
        return [
            (
                "the members outside the layers dominate",
                "the members outside the layers are too soft: as the whole-part rung measures them on the "
                f"design, they alone give S >= {floor[i]:.3g} 1/N in regime {i + 1} "
                f"({1e3 * (sum(parts.values())[i] + extra[i]):.3g} um/N), above its target {problem.S_target[i]:g} "
                "1/N, which no layer can lower; stiffer members are needed: a stiff insert per plate, a cover "
                "supported all round (docs/design.md 4.7)",
            )
        ]
    name = max(parts, key=lambda k: parts[k][i])
    verb = "are" if name == "plates" else "is"
    return [
        (
            f"the {name} dominate{'' if name == 'plates' else 's'}",
            f"the {name} {verb} too soft: the members outside the layers alone give "
            f"S >= {floor[i]:.3g} 1/N in regime {i + 1} (most the {name}, {parts[name][i]:.3g} mm/N), above its "
            f"target {problem.S_target[i]:g} 1/N, which no layer can lower; a stiffer cap (an insert), plates or "
            "a cover supported all round (docs/design.md 4.6)",
        )
    ]


def _members_share(problem: DesignProblem, u: ArrayLike, achieved_S: ArrayLike, achieved_R: ArrayLike) -> str:
    """'' or, when the members outside the layers carry a third or more of some regime's motion at
    the nearest design, that share and the member (each as it moves in that regime,
    :func:`_members_by_regime`): what the layers have to work around."""
    if not problem.whole_part:
        return ""
    edges = np.concatenate([[0.0], np.sort(np.asarray(achieved_R, float))])
    parts, per_mm, _ = _members_by_regime(problem, u, edges)
    share = sum(parts.values()) * per_mm / np.maximum(np.asarray(achieved_S, float), 1e-300)
    i = int(np.argmax(share))
    if share[i] < 1.0 / 3.0:
        return ""
    name = max(parts, key=lambda k: parts[k][i])
    return (
        f"; the members outside the layers carry about {100 * min(share[i], 1.0):.0f} % of regime {i + 1}'s "
        f"motion, most the {name} ({parts[name][i]:.3g} mm/N, docs/design.md 4.6)"
    )


def _beyond_limits(problem: DesignProblem) -> list[tuple[str, str]]:
    """(name, reason) of every target the magnet's field or the printable layers cannot reach."""
    lim = limits(problem)
    reasons: list[tuple[str, str]] = []
    n, tol = problem.n, problem.tolerance_rel
    if lim.field_change_needed_min > lim.field_change_max:
        reasons.append(
            (
                "total field change",
                (
                    f"the targets need a total field change dB/B0 = sum S_i (R_i - R_(i-1)) = "
                    f"{lim.field_change_needed:.3g} (>= {lim.field_change_needed_min:.3g} at the tolerance's "
                    f"edge), but this magnet gives at most {lim.field_change_max:.3g} between the largest "
                    f"unloaded gap {lim.gap0_max_mm:.2f} mm and the smallest gap any stack can close to "
                    f"({max(lim.gap_min_mm, 0):.2f} mm, field capped at {problem.B_limit_T * 1e3:.1f} mT): "
                    "lower the sensitivities or ranges, or use a stronger/larger magnet"
                ),
            )
        )
    if math.isfinite(lim.R_min_N) and problem.R_target[0] * (1 + tol) < lim.R_min_N:
        th, t, h = lim.R_min_at
        reasons.append(
            (
                "R_1 too small",
                (
                    f"force too small for any printable wall: target R_1 = {problem.R_target[0]:g} N, but "
                    f"the softest printable layer within the bounds locks at about {lim.R_min_N:.3g} N "
                    f"(theta {th:.1f} deg, t {t:.2f} mm, h {h:.2f} mm); widen the bounds, use a softer "
                    "material or fewer struts"
                ),
            )
        )
    if math.isfinite(lim.R_max_N) and problem.R_target[-1] * (1 - tol) > lim.R_max_N:
        th, t, h = lim.R_max_at
        reasons.append(
            (
                f"R_{n} too large",
                (
                    f"force too large for any printable layer: target R_{n} = {problem.R_target[-1]:g} N, "
                    f"but the stiffest printable layer within the bounds locks at about {lim.R_max_N:.3g} N "
                    f"(theta {th:.1f} deg, t {t:.2f} mm, h {h:.2f} mm); widen the bounds, use a stiffer "
                    "material or more struts"
                ),
            )
        )
    return reasons


def _rising_sensitivities(problem: DesignProblem, achieved_S: ArrayLike) -> list[tuple[str, str]]:
    """(name, reason) of every target S_i that does not fall from the regime below."""
    achieved_S = np.asarray(achieved_S, float)
    reasons = []
    n = problem.n
    for i in range(1, n):
        if problem.S_target[i] >= problem.S_target[i - 1]:
            reasons.append(
                (
                    f"S_{i + 1} rises with force",
                    (
                        f"sensitivity rises with force: target S_{i + 1} = {problem.S_target[i]:g} >= "
                        f"S_{i} = {problem.S_target[i - 1]:g} 1/N. Each lock takes a compliant layer out "
                        "of the stack, so S falls from regime to regime unless the field gradient grows "
                        f"faster than the stack stiffens; here the closest design reaches S_{i + 1} = "
                        f"{achieved_S[i]:.4g} 1/N"
                    ),
                )
            )

    return reasons


def _worst_miss(
    problem: DesignProblem, u: ArrayLike, achieved_S: ArrayLike, achieved_R: ArrayLike
) -> list[tuple[str, str]]:
    """(name, reason) of the output that misses most, when it misses, and what holds the nearest
    design back (the active constraints and bounds)."""
    n, tol = problem.n, problem.tolerance_rel
    reasons = []
    targets = np.concatenate([problem.S_target, problem.R_target])
    achieved = np.concatenate([np.asarray(achieved_S, float), np.asarray(achieved_R, float)])
    err = achieved / targets - 1.0
    names = problem.output_names()
    j = int(np.argmax(np.abs(err)))
    unit = "1/N" if j < n else "N"
    active = active_constraints(problem, u)
    miss = (
        f"target {names[j]} = {targets[j]:g} {unit} not met: the nearest design reaches "
        f"{achieved[j]:.4g} {unit} ({100 * err[j]:+.1f} %, tolerance {100 * tol:g} %)"
    )
    if active:
        miss += "; held back by: " + ", ".join(active)
    if abs(err[j]) > tol:
        reasons.append((names[j], miss))
    return reasons


def active_constraints(problem: DesignProblem, u: ArrayLike) -> list[str]:
    """Constraints and variable bounds that are (nearly) active at normalised point u."""
    e = problem.evaluate(np.asarray(u, float))
    names = problem.constraint_names()
    out = [names[k] for k in np.flatnonzero(e.constraints >= -ACTIVE_TOL)]
    var = ("theta", "t", "h")
    units = ("deg", "mm", "mm")
    uu = np.asarray(u, float).reshape(problem.n, 3)
    for i in range(problem.n):
        for j in range(3):
            if uu[i, j] <= 1e-6:
                out.append(f"layer {i + 1} {var[j]} at its lower bound {problem.lo[j]:g} {units[j]}")
            elif uu[i, j] >= 1 - 1e-6:
                out.append(f"layer {i + 1} {var[j]} at its upper bound {problem.hi[j]:g} {units[j]}")
    return out
