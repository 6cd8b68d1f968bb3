"""The part's members in the general load: each member rides with the layer whose walls load it
(docs/design.md 4.5 and 4.6).

The axial model (:func:`mst_cli.model.response.part_stack`) puts the cap, the plates and the
housing's cover in series with the layers (:mod:`mst_cli.model.load_path`). The general load
solves every layer's equilibrium under a force and two moments (the tilt rung,
:mod:`mst_cli.model.mechanics.tilt`), so here each member joins the law of the layer that loads
it, and the tilt rung sees the layer and its member as one unit:

* the cap, bonded to the top layer's top pad, bends into that layer's cavity until it closes
  there (:class:`~mst_cli.model.load_path.CappedLayer`, the axial model's own law); plate j,
  the top pad of layer j, likewise bends into layer j's cavity under layer j + 1's wall feet
  (part_stack's own caps);
* plate j over a locked layer j gives more under layer j + 1's feet until that layer locks
  (:class:`OverLockedMember`, model.past_lock);
* the cover, under layer 1's wall feet, is in series with layer 1 (:class:`SeriesMember`), its
  bending over the slot stopping once it has dropped the air under it onto the board (when that
  landing comes after layer 1's lock, the cover rides with the lowest layer still open then,
  :func:`cover_host`).

A centred press then gives the axial part's drop exactly (the units' compressions sum to
part_stack's, on the same knots). Under a moment each chevron line carries its side's force
through the member's compliance, half of it a side, so the member adds to the unit's tilt per
moment C / x_c^2 (C the member's centred compliance, x_c the chevron lever): for the cap at a
small offset that is the simply supported beam's mid-span slope, L / (12 E'I) per N mm for a
point load, when x_c is half the span (the wall heads). The cover never closes, so it stays
outside its layer's contact problem (:func:`unit_tilt_law`): it adds that drop and turn to the
layer's own in every regime, and the layer's pads touch by the layer's own closure. A tangential
force's moment turns the members with their layer; the base and the plates also translate, and
turn back under the walls' end moments, as a plane frame of the section
(:func:`mst_cli.model.general_load.section_sway_laws`, :mod:`mst_cli.model.counter_turn`). Pure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from mst_cli.model.load_path import CappedLayer, Members, capped_units, cover_landing_N, members
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics.tilt import LayerTiltLaw, MemberInSeries
from mst_cli.model.stack import contact_force_N, members_drop_mm, members_rate_mm_per_N

OWN_LEVER = None  # unit_members' "which" of a term that turns at its layer's own lever


@dataclass(frozen=True)
class SeriesMember:
    """A layer law with a member that never closes (the cover) in series: the layer's
    compression plus ``member_mm_per_N`` x F at every force, less the part ``contact_mm_per_N``
    that stops once it has moved ``contact_travel_mm``, both changing past layer 1's lock
    (model.stack.members_drop_mm, :class:`~mst_cli.model.stack.Stack`'s own); the lock still the
    layer's own."""

    law: Any  # a layer law of any rung, or a CappedLayer
    member_mm_per_N: float
    contact_mm_per_N: float = 0.0
    contact_travel_mm: float = math.inf
    first_lock_N: float = math.inf  # layer 1's (its capped unit's): the cover under it stiffens there
    contact_locked_mm_per_N: float | None = None  # the contact part past it (None: the same)
    locked_delta_mm_per_N: float = 0.0  # the member's change past it

    @property
    def _member_law(self) -> tuple:
        C = self.contact_mm_per_N
        C_locked = C if self.contact_locked_mm_per_N is None else self.contact_locked_mm_per_N
        return self.member_mm_per_N, C, self.contact_travel_mm, self.first_lock_N, C_locked, self.locked_delta_mm_per_N

    @property
    def contact_force_N(self) -> float:
        _, C, travel, R1, C_locked, _ = self._member_law
        return float(contact_force_N(R1, C, C_locked, travel))

    def member_mm(self, force_N) -> np.ndarray:
        """The member's drop at ``force_N``."""
        return members_drop_mm(force_N, *self._member_law)

    def _compliance_past(self, force_N: float) -> float:
        return members_rate_mm_per_N(force_N, *self._member_law)

    @property
    def lock_force_N(self) -> float:
        return float(self.law.lock_force_N)

    @property
    def knots_N(self) -> tuple[float, ...]:
        inside = (
            f for f in (self.contact_force_N, self.first_lock_N) if math.isfinite(f) and 0.0 < f < self.lock_force_N
        )
        return tuple(sorted({*self.law.knots_N, *inside}))

    @property
    def k_N_per_mm(self) -> float:
        return 1.0 / (1.0 / self.law.k_N_per_mm + self._compliance_past(0.0))

    @property
    def d_lock_mm(self) -> float:  # the unit's closure when the layer locks
        return float(self.law.d_lock_mm) + float(self.member_mm(self.lock_force_N))

    @property
    def k_locked_N_per_mm(self) -> float:
        return 1.0 / (1.0 / self.law.k_locked_N_per_mm + self._compliance_past(self.lock_force_N))

    def displacement_mm(self, force_N) -> np.ndarray:
        F = np.asarray(force_N, dtype=float)
        return np.asarray(self.law.displacement_mm(F)) + self.member_mm(F)


@dataclass(frozen=True)
class OverLockedMember:
    """A layer law standing on a plate over a locked layer (model.past_lock): the plate gives
    ``member_mm_per_N`` x F more from the lower layer's lock ``start_N`` until this layer locks,
    ``deeper_mm_per_N`` more past ``deeper_start_N`` (the layer under that one locked too), then
    holds (the axial model's by_regime); the lock still the layer's own."""

    law: Any  # a layer law of any rung, or a CappedLayer
    member_mm_per_N: float
    start_N: float
    deeper_mm_per_N: float = 0.0
    deeper_start_N: float = math.inf

    def member_mm(self, force_N) -> np.ndarray:
        F, R = np.asarray(force_N, dtype=float), self.lock_force_N
        d = self.member_mm_per_N * np.clip(F - self.start_N, 0.0, max(R - self.start_N, 0.0))
        if self.deeper_mm_per_N:
            both = max(self.start_N, self.deeper_start_N)
            d = d + self.deeper_mm_per_N * np.clip(F - both, 0.0, max(R - both, 0.0))
        return d

    @property
    def lock_force_N(self) -> float:
        return float(self.law.lock_force_N)

    @property
    def knots_N(self) -> tuple[float, ...]:
        both = max(self.start_N, self.deeper_start_N) if self.deeper_mm_per_N else math.inf
        extra = tuple(f for f in {self.start_N, both} if 0.0 < f < self.lock_force_N)
        return tuple(sorted((*self.law.knots_N, *extra)))

    @property
    def k_N_per_mm(self) -> float:  # from no load: the lower layer is open
        return self.law.k_N_per_mm if self.start_N > 0.0 else 1.0 / (1.0 / self.law.k_N_per_mm + self.member_mm_per_N)

    @property
    def d_lock_mm(self) -> float:
        return float(self.law.d_lock_mm) + float(self.member_mm(self.lock_force_N))

    @property
    def k_locked_N_per_mm(self) -> float:
        return self.law.k_locked_N_per_mm

    def displacement_mm(self, force_N) -> np.ndarray:
        F = np.asarray(force_N, dtype=float)
        return np.asarray(self.law.displacement_mm(F)) + self.member_mm(F)


def part_layer_laws(laws: tuple, parts: Members) -> tuple:
    """The layer laws (bottom to top) with the members folded in as
    :func:`~mst_cli.model.response.part_stack` folds them (module docstring); rigid members (all
    compliances 0) give ``laws`` themselves."""
    units = capped_units(laws, parts)
    starts = [u.lock_force_N for u in units]
    two = parts.two_locked_plates_mm_per_N or parts.locked_plates_mm_per_N
    for j, X in enumerate(parts.locked_plates_mm_per_N, start=1):  # plate j - 1 under layer j's feet
        if X > 0.0 and starts[j - 1] < starts[j]:
            deeper = (two[j - 1] - X, starts[j - 2]) if j >= 2 else (0.0, math.inf)  # layer j - 2 locked too
            units[j] = OverLockedMember(units[j], X, starts[j - 1], *deeper)
    if parts.cover_mm_per_N > 0:
        j = cover_host(units, parts)
        C, travel, C_locked, delta = parts.cover_contact
        R1 = float(units[0].lock_force_N)
        units[j] = SeriesMember(units[j], parts.cover_mm_per_N, C, travel, R1, C_locked, delta)
    return tuple(units)


def unit_members(laws: tuple, parts: Members, lock_order) -> list[list[list[tuple[float, int | None]]]]:
    """Per regime r (the first r layers of ``lock_order`` locked) and per unit j of
    :func:`part_layer_laws`: the members that ride with it then, each (its centred compliance, mm/N;
    which: -1 the cover, k < n - 1 the plate over layer k, n - 1 the cap, OWN_LEVER the top layer's
    walls' thrust and the feet's press), by the rules above: an open layer's plate or cap and half
    its walls' joints on each side; the plate over a locked layer under it, and what the plate
    under that one adds once its layer is locked too; the cover on its host in every regime.
    model.counter_turn weighs each member's lever under a pull by them. The walls' thrust
    (model.wall_thrust) and the feet's press into a locked block's edge
    (model.past_lock.foot_press_mm_per_N) are the centred press's: under a pull the two sides'
    feet carry forces of opposite sign, so they bend no member against the pull's couple and turn
    with their layer at the pull's own lever."""
    n = len(laws)

    def padded(values, size):
        return (*values, *(0.0,) * (size - len(values)))

    plates, joints = padded(parts.plates_mm_per_N, n - 1), padded(parts.joints_mm_per_N, n)
    over = padded(parts.locked_plates_mm_per_N, n - 1)
    two = padded(parts.two_locked_plates_mm_per_N or parts.locked_plates_mm_per_N, n - 1)
    thrust = padded(parts.thrust_mm_per_N, n - 1)  # in both of the above, and so is the feet's press
    own = [a + b for a, b in zip(thrust, padded(parts.press_mm_per_N, n - 1))]
    host = cover_host(capped_units(laws, parts), parts) if parts.cover_mm_per_N > 0 else None
    out = []
    for r in range(n + 1):
        locked = {int(i) for i in lock_order[:r]}
        rows: list[list[tuple[float, int | None]]] = []
        for j in range(n):
            riding: list[tuple[float, int | None]] = []
            if j not in locked:
                riding += [(plates[j] if j < n - 1 else parts.cap_mm_per_N, j), (0.5 * joints[j], j)]
                riding.append((0.5 * joints[j], j - 1))
                if j >= 1 and j - 1 in locked:
                    riding += [(over[j - 1] - own[j - 1], j - 1), (own[j - 1], OWN_LEVER)]
                if j >= 2 and {j - 1, j - 2} <= locked:  # the plates and the block between them hang together
                    riding.append((two[j - 1] - over[j - 1], j - 2))
            if j == host:
                riding.append((parts.cover_mm_per_N, -1))
            rows.append([(float(c), k) for c, k in riding if c > 0.0])
        out.append(rows)
    return out


def cover_host(units: list, parts: Members) -> int:
    """Which unit carries the cover: layer 1, whose wall feet load it, unless the cover lands on
    the board after layer 1 has locked; then the lowest layer still open at the landing. The
    tilt rung follows a unit's knots up to its lock only, so the landing must fall before its
    host's lock to be a knot. A centred press is the same whichever unit hosts it (every layer
    carries the whole force); under a moment the cover turns with its host's chevron lever."""
    landing = cover_landing_N(parts, float(units[0].lock_force_N))
    open_at_landing = [j for j, u in enumerate(units) if u.lock_force_N > landing]
    return 0 if not math.isfinite(landing) or 0 in open_at_landing or not open_at_landing else open_at_landing[0]


def part_units(geometry, material, mechanics: str) -> tuple:
    """The layer laws of ``geometry`` (a SensorGeometry) in ``material`` on the rung
    ``mechanics``, each with the members of :func:`~mst_cli.model.load_path.members` its walls
    load (:func:`part_layer_laws`)."""
    return part_layer_laws(layer_laws(geometry.layers, material, mechanics), members(geometry, material))


def closure_limit_mm(unit, cavity_mm: float) -> float:
    """The unit's closure at which its own pads would reach the cavity's height ``cavity_mm``
    (the rotation flag's past_closure). Past the lock the rung softens the pads by the member in
    series with them (:func:`unit_tilt_law`), so of the unit's closure past its pad gap only the
    share s = k_locked(unit) / k_locked(layer) closes the pads; the cap rests on the cavity's
    floor once the layer's own closure is d_lock - C R', so the unit reaches the pads' own
    closure C R' later."""
    if isinstance(unit, SeriesMember):
        inner = unit.law
        share = unit.k_locked_N_per_mm / inner.k_locked_N_per_mm
        return unit.d_lock_mm + (closure_limit_mm(inner, cavity_mm) - inner.d_lock_mm) / share
    if isinstance(unit, CappedLayer):
        return cavity_mm + unit.cap_mm_per_N * unit.lock_force_N
    return cavity_mm


def unit_tilt_law(
    law, cell, modulus_MPa: float, poisson_ratio: float, locked_base_turn_rad_per_Nmm: float | None = None
) -> LayerTiltLaw:
    """:meth:`LayerTiltLaw.from_layer` of a unit of :func:`part_layer_laws`. A unit with the
    cover (:class:`SeriesMember`) is its layer's own tilt law with the cover in series outside
    the layer's contact problem (:class:`~mst_cli.model.mechanics.tilt.MemberInSeries`): its drop
    the unit's less the layer's, its turn as a beam's under the couple, C / x_c^2, until layer 1
    locks; past that lock, when ``locked_base_turn_rad_per_Nmm`` is given (the section frame's
    base under a locked layer 1, :func:`mst_cli.model.plate_sway.locked_base_turn_rad_per_Nmm`),
    that turn per N mm instead, in proportion to the cover's rate should it land on the board.
    Under a moment the cover and the slot's walls work as a portal: the cover's ends turn its
    walls' tops, which sway, so its turn is not its centred drop's C / x_c^2 (docs/design.md
    4.7, "The base's portal under a moment")."""
    if not isinstance(law, SeriesMember):
        return LayerTiltLaw.from_layer(law, cell, modulus_MPa, poisson_ratio)
    own = LayerTiltLaw.from_layer(law.law, cell, modulus_MPa, poisson_ratio)
    gain = (math.inf, 1.0)
    free_locked = law.member_mm_per_N + law.locked_delta_mm_per_N  # the cover's rate past the lock, not landed
    if locked_base_turn_rad_per_Nmm is not None and math.isfinite(law.first_lock_N) and free_locked > 0.0:
        gain = (law.first_lock_N, locked_base_turn_rad_per_Nmm * own.lever_mm**2 / free_locked)
    return replace(own, member=member_in_series(law, gain))


def member_in_series(unit: SeriesMember, moment_gain_after: tuple[float, float] = (math.inf, 1.0)) -> MemberInSeries:
    """The cover of ``unit`` as the tilt rung carries it: its drop at 0 and at each knot of its
    law (where it lands on the board, layer 1's lock), its rate past the last; its turn under a
    moment ``moment_gain_after`` (F_N, g): g times C / x_c^2 from F_N on."""
    kinks = (unit.contact_force_N, unit.first_lock_N)
    F = np.array([0.0, *sorted({float(f) for f in kinks if math.isfinite(f) and f > 0.0})])
    drop = np.asarray(unit.member_mm(F), dtype=float)
    return MemberInSeries(F, drop, float(unit._compliance_past(float(F[-1]))), moment_gain_after)
