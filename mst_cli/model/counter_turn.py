"""The members' turn under a tangential force (issue 44, docs/design.md 4.7, "The members' turn
under a tangential force: built").

The general load gives each layer the tangential force's moment, Fx h_j about its pivot
(:mod:`mst_cli.model.general_load`), and the members that ride with the layer (the cap, the
plates, the cover: :mod:`mst_cli.model.part_laws`) turn under it as under an off-centre press's
moment. Under a pull they turn less, or the other way: the walls carry the pull's shear into the
plates and the cover as end moments, which turn them against the moment's couple, as a storey's
columns turn its beam in a sway frame. The whole-part rung finds the members adding -0.06, +0.21
and +0.15 mrad/N to the forward design's turn per tangential newton in its three regimes, where
the closed form's tilt laws give -2.6, -2.0 and -1.7.

The section's frame (:func:`mst_cli.model.plate_sway.section_regimes`) gives, per regime and per
member (the base, each plate, the cap), the pull's lever on it: its turn under the pull over its
turn per N mm of a pure moment. Each layer's members, as they ride with it in that regime
(:func:`mst_cli.model.part_laws.unit_members`), weighed by the compliance each adds, give the
layer's lever a_j,r (:func:`unit_arms_mm`); the closed form turns them by the pull's moment about
the layer's pivot, h_j dC_j,r (dC its tilt compliance with its members less without, where its own
regime starts, as ``mst check --whole-part`` reads them), so the layer's tilt gains
(a_j,r - h_j) dC_j,r per newton of Fx. One ratio for every member at the layer's lever, as
before 2026-12-02, missed the plate over a locked layer, which the pull turns twice as far as its
moment (docs/design.md 4.7, "Each member at its own lever"). The frame's own members turn 0.3 to
0.7 times the rung's under a moment (no pocket, no depth), so its levers, not its turns, are what
is taken. Along y nothing (the frame is the section's). Pure.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mst_cli.model.mechanics.tilt import LayerTiltLaw, tilt_compliance_rad_per_Nmm

REGIME_START_REL = 0.02  # where a regime's closed form is linearised: 2 % into it


def regime_start_N(locks_N, regime: int) -> float:
    """Where regime ``regime`` (from 0) of a stack whose sorted lock forces are ``locks_N`` is
    linearised: 2 % of the first lock, else 2 % past the lock that opens it."""
    return REGIME_START_REL * locks_N[0] if regime == 0 else (1.0 + REGIME_START_REL) * locks_N[regime - 1]


@dataclass(frozen=True)
class CounterTurn:
    """What the members' counter-turn adds to each layer's tilt about y, per newton of the
    tangential force along x, in each regime of the part (module docstring). The press grows
    along a ray, so, as a layer's slide (model.general_load.LayerLateralLaw), the tilt is the path
    integral of the regimes' rates: continuous at the locks."""

    edges_N: np.ndarray  # (k,) the part's finite lock forces, ascending: regime r from edges_N[r - 1]
    tilt_rad_per_N: np.ndarray  # (k + 1, n)
    # (k + 1,) the magnet's slide per newton of Fx from each member turning about its own mid-plane,
    # not its layer's pivot (:func:`own_plane_slide_mm_per_N`); None: not given
    slide_mm_per_N: np.ndarray | None = None

    def _regime(self, force_N) -> tuple[np.ndarray, np.ndarray]:
        F = np.atleast_1d(np.asarray(force_N, dtype=float))
        return F, np.searchsorted(self.edges_N, F, side="right")

    def integral_rad(self, force_N) -> np.ndarray:
        """(m, n) int_0^F rate dF at normal forces ``force_N`` (m,): each layer's extra phi_y on the
        ray whose tangential force along x equals the normal one."""
        F, regime = self._regime(force_N)
        knots = np.concatenate([[0.0], self.edges_N])
        rates = self.tilt_rad_per_N
        at_knots = np.concatenate(
            [np.zeros((1, rates.shape[1])), np.cumsum(np.diff(knots)[:, None] * rates[:-1], axis=0)]
        )
        return at_knots[regime] + rates[regime] * (F - knots[regime])[:, None]

    def tilt_rad(self, force_N, ratio_x) -> np.ndarray:
        """(m, n, 2) the layers' extra (phi_y, phi_x) at normal forces ``force_N`` (m,) on the ray
        whose tangential force along x is ``ratio_x`` x the normal one: ratio x int_0^F rate dF."""
        integral = self.integral_rad(force_N)
        out = np.zeros((*integral.shape, 2))
        out[..., 0] = integral * np.broadcast_to(np.asarray(ratio_x, dtype=float), integral.shape[:1])[:, None]
        return out

    def tilt_gradient_rad(self, theta: np.ndarray) -> np.ndarray:
        """(m, 5, n) d(each layer's extra phi_y)/d(Fz, Fx, Fy, x, y) at the loads ``theta`` (m, 5)
        (:mod:`mst_cli.model.general_load`'s): Fx U(Fz) / Fz differentiated, U' the regime's rate
        (0 at Fz <= 0)."""
        F, regime = self._regime(theta[:, 0])
        safe = np.where(F > 0.0, F, 1.0)[:, None]
        U, rate = self.integral_rad(F), self.tilt_rad_per_N[regime]
        out = np.zeros((len(F), 5, U.shape[1]))
        out[:, 0] = theta[:, 1:2] * (rate * safe - U) / safe**2
        out[:, 1] = U / safe
        return np.where((F > 0.0)[:, None, None], out, 0.0)

    def tangent_tilt_rad(self, force_N, fx_N) -> np.ndarray:
        """(m, n, 2) the same for a small tangential force ``fx_N`` (m,) added at the normal forces
        ``force_N``: the regime's rate (what a linear model of the part gives)."""
        F, regime = self._regime(force_N)
        out = np.zeros((len(F), self.tilt_rad_per_N.shape[1], 2))
        out[..., 0] = self.tilt_rad_per_N[regime] * np.broadcast_to(np.asarray(fx_N, dtype=float), F.shape)[:, None]
        return out


def unit_arms_mm(riding: list[list[list[tuple[float, int | None]]]], member_arm_mm: np.ndarray, lever_mm) -> np.ndarray:
    """(regimes, n) each unit's members' lever under the pull: their own levers (the frame's
    ``member_arm_mm``, columns the cover, the plates, the cap) weighed by the compliance each adds
    to the unit (``riding``: model.part_laws.unit_members; under a moment a unit's members turn in
    that proportion, all on the unit's one chevron lever); a unit with none takes ``lever_mm``, the
    pull's own lever on it: no counter-turn."""
    lever = np.asarray(lever_mm, dtype=float)
    out = np.tile(lever, (len(riding), 1))
    for r, units in enumerate(riding):
        for j, members in enumerate(units):
            if members:
                arms = (lever[j] if k is None else member_arm_mm[r, k + 1] for _, k in members)
                out[r, j] = sum(share * arm for (share, _), arm in zip(_shares(members), arms))
    return out


def _shares(members: list[tuple[float, int | None]]) -> list[tuple[float, int | None]]:
    """A unit's riding members (compliance, which) as (the share of the unit's members' compliance,
    which): how its members' turn under a moment divides among them."""
    total = sum(c for c, _ in members)
    return [(c / total, k) for c, k in members]


def members_tilt_rad_per_Nmm(part: list[LayerTiltLaw], alone: list[LayerTiltLaw]) -> tuple[np.ndarray, np.ndarray]:
    """(the part's finite lock forces (k,), ascending; (k + 1, n) each layer's tilt per N mm with its
    members less without, where each regime starts) of a stack whose layers' tilt laws are ``part``
    (with their members) and ``alone`` (without)."""
    locks = np.sort([t.lock_force_N for t in part])
    edges = locks[np.isfinite(locks)]
    locks_alone = np.sort([t.lock_force_N for t in alone])
    rows = []
    for r in range(len(edges) + 1):
        at_part = regime_start_N(locks, r)
        at_alone = regime_start_N(locks_alone, r)
        at_alone = at_alone if np.isfinite(at_alone) else at_part
        rows.append(
            [
                tilt_compliance_rad_per_Nmm(p, at_part) - tilt_compliance_rad_per_Nmm(a, at_alone)
                for p, a in zip(part, alone)
            ]
        )
    return edges, np.array(rows)


def counter_turn(
    part: list[LayerTiltLaw], alone: list[LayerTiltLaw], lever_mm: np.ndarray, arm_mm: np.ndarray,
    slide_mm_per_N=None, members_tilt: tuple[np.ndarray, np.ndarray] | None = None,
) -> CounterTurn:  # fmt: skip
    """The :class:`CounterTurn` of a stack whose layers' tilt laws are ``part`` (with their
    members) and ``alone`` (without), the top face ``lever_mm`` (n,) over each layer's pivot, and
    each unit's members' lever under the pull per regime ``arm_mm`` (regimes, n; :func:`unit_arms_mm`,
    in the part's lock order): the tilt rung turns a unit's members by the pull's moment about the
    layer's pivot, lever x dC; the frame turns them by arm x dC, so the difference is added.
    ``slide_mm_per_N``: :func:`own_plane_slide_mm_per_N`'s, carried along; ``members_tilt``:
    :func:`members_tilt_rad_per_Nmm`'s of the two, when the caller has it already."""
    edges, tilt = members_tilt_rad_per_Nmm(part, alone) if members_tilt is None else members_tilt
    arm = np.asarray(arm_mm, dtype=float)[: len(tilt)]
    return CounterTurn(edges, (arm - np.asarray(lever_mm, dtype=float)) * tilt, slide_mm_per_N)


def own_plane_slide_mm_per_N(
    riding: list[list[list[tuple[float, int | None]]]], member_arm_mm: np.ndarray, members_tilt: np.ndarray,
    pivot_mm: np.ndarray, member_z_mm: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """(regimes,) per regime, what the members' turn under a pull moves the magnet along x, per
    newton of Fx, beyond what it gives turning about their layer's pivot: each member k of unit j
    (``riding``, :func:`unit_arms_mm`'s) turns by arm_k x its share of dC_j (``members_tilt``,
    :func:`members_tilt_rad_per_Nmm`'s), about its own mid-plane at ``member_z_mm`` [k + 1] (the
    cover, the plates, the cap; the pivots ``pivot_mm`` (n,) in the same frame), so the magnet
    moves that turn x (pivot_j - z_k) more: a turn phi about y moves a point dz above its centre
    by phi dz along x."""
    out = []
    for r, tilt in enumerate(members_tilt):
        slide = 0.0
        for j, members in enumerate(riding[r]):
            for share, k in _shares(members):
                if k is not None:  # a term at its layer's own lever turns about the layer's pivot
                    slide += member_arm_mm[r, k + 1] * share * tilt[j] * (pivot_mm[j] - member_z_mm[k + 1])
        out.append(slide)
    return np.array(out)
