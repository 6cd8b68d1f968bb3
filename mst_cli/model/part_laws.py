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
point load, when x_c is half the span (the wall heads). The members are stiff in their own
plane, so a tangential force slides no member; its moment turns them with their layer. Pure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from mst_cli.model.load_path import CappedLayer, Members, capped_units, members
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics.tilt import LayerTiltLaw


@dataclass(frozen=True)
class SeriesMember:
    """A layer law with a member that never closes (the cover) in series: the layer's
    compression plus ``member_mm_per_N`` x F at every force, less the part ``contact_mm_per_N``
    that stops once it has moved ``contact_travel_mm`` (:attr:`Stack.contact_mm_per_N`); the
    lock still the layer's own."""

    law: Any  # a layer law of any rung, or a CappedLayer
    member_mm_per_N: float
    contact_mm_per_N: float = 0.0
    contact_travel_mm: float = math.inf

    @property
    def contact_force_N(self) -> float:
        C = self.contact_mm_per_N
        return self.contact_travel_mm / C if C > 0.0 else math.inf

    def member_mm(self, force_N) -> np.ndarray:
        """The member's drop at ``force_N``."""
        F = np.asarray(force_N, dtype=float)
        stopped = np.maximum(self.contact_mm_per_N * F - self.contact_travel_mm, 0.0) if self.contact_mm_per_N else 0.0
        return self.member_mm_per_N * F - stopped

    def _compliance_past(self, force_N: float) -> float:
        landed = force_N >= self.contact_force_N
        return self.member_mm_per_N - (self.contact_mm_per_N if landed else 0.0)

    @property
    def lock_force_N(self) -> float:
        return float(self.law.lock_force_N)

    @property
    def knots_N(self) -> tuple[float, ...]:
        contact = self.contact_force_N
        extra = (contact,) if math.isfinite(contact) and contact < self.lock_force_N else ()
        return tuple(sorted((*self.law.knots_N, *extra)))

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
    then holds (the axial model's by_regime); the lock still the layer's own."""

    law: Any  # a layer law of any rung, or a CappedLayer
    member_mm_per_N: float
    start_N: float

    def member_mm(self, force_N) -> np.ndarray:
        span = max(self.lock_force_N - self.start_N, 0.0)
        return self.member_mm_per_N * np.clip(np.asarray(force_N, dtype=float) - self.start_N, 0.0, span)

    @property
    def lock_force_N(self) -> float:
        return float(self.law.lock_force_N)

    @property
    def knots_N(self) -> tuple[float, ...]:
        extra = (self.start_N,) if 0.0 < self.start_N < self.lock_force_N else ()
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
    for j, X in enumerate(parts.locked_plates_mm_per_N, start=1):  # plate j - 1 under layer j's feet
        if X > 0.0 and starts[j - 1] < starts[j]:
            units[j] = OverLockedMember(units[j], X, starts[j - 1])
    if parts.cover_mm_per_N > 0:
        j = cover_host(units, parts)
        units[j] = SeriesMember(units[j], parts.cover_mm_per_N, parts.cover_contact_mm_per_N, parts.cover_travel_mm)
    return tuple(units)


def cover_host(units: list, parts: Members) -> int:
    """Which unit carries the cover: layer 1, whose wall feet load it, unless the cover lands on
    the board after layer 1 has locked; then the lowest layer still open at the landing. The
    tilt rung follows a unit's knots up to its lock only, so the landing must fall before its
    host's lock to be a knot. A centred press is the same whichever unit hosts it (every layer
    carries the whole force); under a moment the cover turns with its host's chevron lever."""
    C, travel = parts.cover_contact_mm_per_N, parts.cover_travel_mm
    landing = travel / C if C > 0.0 else math.inf
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


def unit_tilt_law(law, cell, modulus_MPa: float, poisson_ratio: float) -> LayerTiltLaw:
    """:meth:`LayerTiltLaw.from_layer` of a unit of :func:`part_layer_laws`. Past the lock the
    rung puts the walls and the pads side by side; a member in series softens both alike, so
    the centred unit keeps the member's compliance there too."""
    tilt = LayerTiltLaw.from_layer(law, cell, modulus_MPa, poisson_ratio)
    if not isinstance(law, SeriesMember):
        return tilt
    own = LayerTiltLaw.from_layer(law.law, cell, modulus_MPa, poisson_ratio)
    scale = law.k_locked_N_per_mm / (own.walls.k_after_N_per_mm + own.pad_stiffness_N_per_mm)
    return replace(
        tilt,
        walls=replace(tilt.walls, k_after_N_per_mm=own.walls.k_after_N_per_mm * scale),
        pad_stiffness_N_per_mm=own.pad_stiffness_N_per_mm * scale,
    )
