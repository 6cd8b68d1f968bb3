"""Layers in series: the piecewise force-displacement curve of the stack.

The same force passes through every layer, so the stack compression is the sum of the layer
compressions, d(F) = sum_j d_j(F). Each layer locks at its own force R_j; sorted, the R_j
split the force axis into regimes. Every layer law is piecewise linear between its knots
(rung L0: the knee and R_j), so d(F) is piecewise linear with breakpoints exactly at the
union of the knots: evaluating it there and interpolating linearly is exact, not an
approximation: no time stepping.

Pure numpy; no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from mst_cli.model.mechanics.spring import KNEE_FRACTION, layer_displacement_mm

if TYPE_CHECKING:
    from numpy.typing import ArrayLike


def capped_lock_force_N(
    k_N_per_mm: ArrayLike, d_lock_mm: ArrayLike, lock_force_N: ArrayLike, cap_mm_per_N: ArrayLike
) -> np.ndarray:
    """Where the top layer's cavity closes at its centre when the cap bonded to its top pad also
    bends into it by cap_mm_per_N x F: the force F' at which d(F') + C F' = d_lock, for L0 laws
    (slope k to the knee KNEE_FRACTION x R, straight on to (d_lock, R)), vectorised. Past F'
    the cap rests on the cavity's floor and the layer is locked (docs/design.md 4.6); C = 0
    gives R itself, to the bit."""
    k, dl, R, C = (np.asarray(a, dtype=float) for a in (k_N_per_mm, d_lock_mm, lock_force_N, cap_mm_per_N))
    F1 = KNEE_FRACTION * R
    d1 = F1 / k
    soft = (dl - d1) / np.maximum(R - F1, 1e-300)  # mm/N between the knee and the lock
    g1 = d1 + C * F1
    closes = np.where(dl <= g1, dl / (1.0 / k + C), F1 + (dl - g1) / (soft + C))
    return np.where(C > 0, closes, R)


def contact_drop_mm(force_N: ArrayLike, first_lock_N: ArrayLike, C: ArrayLike, C_locked: ArrayLike) -> np.ndarray:
    """How far the members' contact part (the cover over the board's slot) has moved at
    ``force_N``, before it lands: C per newton until layer 1 (bonded on the cover) locks at
    ``first_lock_N``, C_locked past it (the closed layer's block on the cover's link to the walls,
    model.load_path.cover_parts_locked_mm_per_N); broadcast arrays, inf: layer 1 never locks."""
    F, R1 = np.asarray(force_N, dtype=float), np.asarray(first_lock_N, dtype=float)
    return np.asarray(C, dtype=float) * np.minimum(F, R1) + np.asarray(C_locked, dtype=float) * np.maximum(F - R1, 0.0)


def contact_force_N(first_lock_N: ArrayLike, C: ArrayLike, C_locked: ArrayLike, travel_mm: ArrayLike) -> np.ndarray:
    """Where :func:`contact_drop_mm` reaches ``travel_mm`` (the cover lands on the board; inf:
    never), broadcast arrays."""
    R1, C, C_locked, travel = (np.asarray(a, dtype=float) for a in (first_lock_N, C, C_locked, travel_mm))
    with np.errstate(divide="ignore", invalid="ignore"):
        early = np.where(C > 0.0, travel / C, np.inf)
        late = R1 + np.where(C_locked > 0.0, (travel - C * R1) / C_locked, np.inf)
    return np.where(early <= R1, early, late)


def members_drop_mm(
    force_N: ArrayLike, rate: float, C: float, travel_mm: float, first_lock_N: float, C_locked: float, delta: float
) -> np.ndarray:
    """The drop of members in series at ``force_N``: ``rate`` per newton, ``delta`` more past layer
    1's lock ``first_lock_N``, less what their contact part (C, C_locked past that lock,
    :func:`contact_drop_mm`) has moved beyond ``travel_mm`` (the cover's air): :class:`Stack`'s
    and model.part_laws.SeriesMember's."""
    F = np.asarray(force_N, dtype=float)
    d = rate * F + delta * np.maximum(F - first_lock_N, 0.0)
    return d - np.maximum(contact_drop_mm(F, first_lock_N, C, C_locked) - travel_mm, 0.0)


def members_rate_mm_per_N(
    force_N: float, rate: float, C: float, travel_mm: float, first_lock_N: float, C_locked: float, delta: float
) -> float:
    """d/dF of :func:`members_drop_mm` just past ``force_N`` (right-continuous at the lock and the landing)."""
    past = force_N >= first_lock_N
    landed = force_N >= float(contact_force_N(first_lock_N, C, C_locked, travel_mm))
    return rate + (delta if past else 0.0) - ((C_locked if past else C) if landed else 0.0)


def series_displacement_mm(
    force_N: ArrayLike,
    k_N_per_mm: ArrayLike,
    d_lock_mm: ArrayLike,
    k_locked_N_per_mm: ArrayLike,
    lock_force_N: ArrayLike | None = None,
    members_mm_per_N: ArrayLike = 0.0,
    cap_mm_per_N: ArrayLike | None = None,
    contact: tuple | None = None,
    regime_extra_mm_per_N: ArrayLike | None = None,
    capped_lock_N: np.ndarray | None = None,
) -> np.ndarray:
    """Stack compression of L0 layers in series, vectorised over designs, with the members that
    are not layers (``members_mm_per_N``, shape (...), a linear spring) in series too, and the
    cap (``cap_mm_per_N``, shape (...)) bending into the top layer's cavity until it closes
    there (:func:`capped_lock_force_N`), or per layer (shape (..., n): each plate bends into the
    cavity of the layer under it, :func:`layer_caps`); ``contact`` (C, travel[, C_locked, delta]), shapes
    (...): the part C of the members that stops once it has moved ``travel`` (:attr:`Stack.contact_mm_per_N`),
    C_locked per newton past layer 1's lock, when the members' compliance changes by delta;
    ``regime_extra_mm_per_N`` (..., n): a compliance added in each regime between the (capped)
    lock forces, the last one's past the last lock too (:func:`regime_extra_displacement_mm`:
    the whole-part rung's correction, docs/design.md 4.7).

    ``k``, ``d_lock``, ``k_locked`` and ``lock_force_N`` (None: R = k d_lock, bilinear) have
    shape (..., n_layers), and so has ``capped_lock_N``, the capped lock forces when the caller
    has them (:func:`capped_lock_force_N` of every layer and its cap); ``force_N`` has shape
    (..., m) (broadcast against the leading axes). Returns shape (..., m).
    """
    k = np.asarray(k_N_per_mm, dtype=float)
    dl = np.asarray(d_lock_mm, dtype=float)
    R = k * dl if lock_force_N is None else np.asarray(lock_force_N, dtype=float)
    F = np.asarray(force_N, dtype=float)[..., :, None]
    d_layer = layer_displacement_mm(
        F, k[..., None, :], dl[..., None, :], R[..., None, :], np.asarray(k_locked_N_per_mm, dtype=float)[..., None, :]
    )
    d = d_layer.sum(axis=-1) + np.asarray(members_mm_per_N, dtype=float)[..., None] * F[..., 0]
    # each layer's lock force, where its cap closes its cavity
    if cap_mm_per_N is None:
        Rc = R
    elif capped_lock_N is None:
        Rc = capped_lock_force_N(k, dl, R, layer_caps(cap_mm_per_N, k.shape))
    else:
        Rc = capped_lock_N
    if contact is not None:  # that part of the members stops after travel; past layer 1's lock, its rates (Stack)
        full = contact if len(contact) == 4 else (*contact, contact[0], 0.0)  # (C, travel): no change at the lock
        C_c, travel, C_locked, delta = (np.asarray(a, dtype=float)[..., None] for a in full)
        R1 = Rc[..., :1]
        d = d + delta * np.maximum(F[..., 0] - R1, 0.0)
        d = d - np.maximum(contact_drop_mm(F[..., 0], R1, C_c, C_locked) - travel, 0.0)
    if regime_extra_mm_per_N is not None:
        d = d + regime_extra_displacement_mm(F[..., 0], np.sort(Rc, axis=-1), regime_extra_mm_per_N)
    if cap_mm_per_N is None:
        return d
    C = layer_caps(cap_mm_per_N, k.shape)[..., None, :]  # (..., 1, n)
    Rc = Rc[..., None, :]
    kl = np.asarray(k_locked_N_per_mm, dtype=float)[..., None, :]
    # before the contact: each layer's own law and its cap's bending; after: locked
    capped = np.where(F <= Rc, d_layer + C * F, dl[..., None, :] + (F - Rc) / kl)
    return d + np.where(C > 0, capped - d_layer, 0.0).sum(axis=-1)


def regime_extra_displacement_mm(force_N: ArrayLike, edges_N: ArrayLike, extra_mm_per_N: ArrayLike) -> np.ndarray:
    """(..., m) the drop of a compliance ``extra_mm_per_N`` (..., n) that takes regime r's value
    between the sorted lock forces ``edges_N`` (..., n) (0 to the first, ..., the (n-1)-th to
    the last) and the last regime's past the last lock, or (..., n + 1) its own value past it:
    the integral of a piecewise-constant compliance, so piecewise linear with knots at the lock
    forces (the stack's knots already)."""
    F = np.asarray(force_N, dtype=float)[..., :, None]  # (..., m, 1)
    E = np.asarray(extra_mm_per_N, dtype=float)
    R = np.asarray(edges_N, dtype=float)[..., None, : E.shape[-1] - 1]
    lo = np.concatenate([np.zeros_like(R[..., :1]), R], axis=-1)
    hi = np.concatenate([R, np.full_like(R[..., :1], np.inf)], axis=-1)  # the last runs on
    inside = np.clip(F, lo, hi) - lo
    return (E[..., None, :] * inside).sum(axis=-1)


def run_on(extra_mm_per_N) -> Any:
    """A per-regime compliance (..., n) with its last regime's value past the last lock too
    (..., n + 1), as :func:`regime_extra_displacement_mm` takes it; None: 0."""
    if extra_mm_per_N is None or len(extra_mm_per_N) == 0:
        return 0.0
    E = np.asarray(extra_mm_per_N, dtype=float)
    return np.concatenate([E, E[..., -1:]], axis=-1)


def layer_caps(cap_mm_per_N: ArrayLike, shape: tuple) -> np.ndarray:
    """Every layer's cap (..., n) for layers of ``shape`` (..., n): ``cap_mm_per_N`` given per
    layer (as many axes as the layers: the plate above each one, the cap on the top one), or for
    the top layer alone (one axis fewer)."""
    C = np.asarray(cap_mm_per_N, dtype=float)
    if C.ndim == len(shape):
        return np.broadcast_to(C, np.broadcast_shapes(C.shape, shape))
    out = np.zeros(np.broadcast_shapes(shape, C.shape + (shape[-1],)))
    out[..., -1] = C
    return out


@dataclass(frozen=True)
class Stack:
    """A stack of layer laws (see :mod:`mst_cli.model.mechanics`), listed bottom to top.

    Every law is piecewise linear between its knots, so the sum d(F) is piecewise linear
    between the union of all knots: interpolating on them is exact. The members in series add
    ``members_mm_per_N`` x F, linear too, so the interpolation stays exact. The lock forces
    are the layers' own: the same force passes through every member.
    """

    layers: tuple
    # the members that are not layers (cap, plates, cover: mst_cli.model.load_path), a linear
    # spring in series with the layers; 0: the layers between rigid plates (L0/L1/L2 as verified)
    members_mm_per_N: float = 0.0
    # the part of members_mm_per_N that stops once it has moved contact_travel_mm (the housing's
    # cover landing on the board under it): its drop is min(C F, travel)
    contact_mm_per_N: float = 0.0
    contact_travel_mm: float = math.inf
    # a compliance added per regime (the whole-part rung's correction to the members' closed
    # form, docs/design.md 4.7), between the lock forces, the last one's past the last lock; (): none
    regime_extra_mm_per_N: tuple[float, ...] = ()
    # past layer 1's lock (the first layer's, on the cover): the contact part's compliance (None: the
    # same) and the change of the members' (the cover under the closed layer, model.load_path)
    contact_locked_mm_per_N: float | None = None
    members_locked_delta_mm_per_N: float = 0.0

    @property
    def first_lock_N(self) -> float:
        """Layer 1's lock force (inf: no layers)."""
        return float(self.layers[0].lock_force_N) if self.layers else math.inf

    @property
    def _member_law(self) -> tuple:
        """(rate, C, travel, layer 1's lock, C past it, the change past it): :func:`members_drop_mm`'s."""
        C = self.contact_mm_per_N
        C_locked = C if self.contact_locked_mm_per_N is None else self.contact_locked_mm_per_N
        return (
            self.members_mm_per_N,
            C,
            self.contact_travel_mm,
            self.first_lock_N,
            C_locked,
            self.members_locked_delta_mm_per_N,
        )

    @property
    def contact_force_N(self) -> float:
        """Where the members' contact closes (inf: never)."""
        _, C, travel, R1, C_locked, _ = self._member_law
        return float(contact_force_N(R1, C, C_locked, travel))

    def members_displacement_mm(self, force_N: ArrayLike) -> np.ndarray:
        """The members' drop at ``force_N``: linear (its rate changing at layer 1's lock), less
        what the contact stops, plus the regimes' extra."""
        F = np.asarray(force_N, dtype=float)
        d = members_drop_mm(F, *self._member_law)
        if self.regime_extra_mm_per_N:
            d = d + regime_extra_displacement_mm(
                F.ravel(), self.regime_bounds_N[1:], self.regime_extra_mm_per_N
            ).reshape(F.shape)
        return d

    def members_compliance_mm_per_N(self, force_N: float) -> float:
        """The members' dd/dF just past ``force_N`` (right-continuous at the contact and the locks)."""
        C = members_rate_mm_per_N(force_N, *self._member_law)
        if self.regime_extra_mm_per_N:
            r = min(int(np.searchsorted(self.regime_bounds_N[1:], force_N, side="right")), len(self.layers) - 1)
            C += self.regime_extra_mm_per_N[r]
        return C

    def layers_only(self) -> Stack:
        """The same layers between rigid plates (the ladder's own verification)."""
        return Stack(self.layers)

    @property
    def lock_forces_N(self) -> np.ndarray:
        """R_j of each layer, in the layers' own order."""
        return np.array([law.lock_force_N for law in self.layers])

    @property
    def lock_order(self) -> np.ndarray:
        """Indices of the layers in the order they lock (stable for equal R)."""
        return np.argsort(self.lock_forces_N, kind="stable")

    @property
    def regime_bounds_N(self) -> np.ndarray:
        """Force thresholds 0 = R_0 < R_(1) < ... < R_(n): the regimes' edges, sorted."""
        return np.concatenate([[0.0], np.sort(self.lock_forces_N)])

    @property
    def last_lock_force_N(self) -> float:
        return float(self.lock_forces_N.max())

    @property
    def knots_N(self) -> np.ndarray:
        """0 and every layer's knots up to the last lock, and the members' contact (wherever it
        closes), ascending and unique."""
        F_end = self.last_lock_force_N
        contact = [self.contact_force_N] if math.isfinite(self.contact_force_N) else []
        ks = np.sort(
            np.asarray(
                [0.0, F_end, *contact] + [f for law in self.layers for f in law.knots_N if f < F_end], dtype=float
            )
        )
        # np.unique's own dedupe, without the numpy.ma import it costs (7 ms of a 0.2 s command)
        return ks[np.concatenate(([True], ks[1:] != ks[:-1]))]

    @cached_property
    def _segment_compliance(self) -> tuple[np.ndarray, np.ndarray]:
        """(knots, dd/dF on each segment between them): one pass over the layers for the whole
        curve, so a compliance lookup is a binary search, not a sum over the layers.
        The stack is frozen, so this is computed once."""
        knots, d = self._knot_displacement_mm
        return knots, np.diff(d) / np.diff(knots)

    @cached_property
    def _knot_displacement_mm(self) -> tuple[np.ndarray, np.ndarray]:
        """(knots, d at the knots), each layer's law summed there once."""
        knots = self.knots_N
        return knots, sum(law.displacement_mm(knots) for law in self.layers) + self.members_displacement_mm(knots)

    @property
    def locked_compliance_mm_per_N(self) -> float:
        """Past the last knot every layer is on its locked branch (and the contact closed)."""
        beyond = float(self.knots_N[-1])
        return sum(1.0 / law.k_locked_N_per_mm for law in self.layers) + self.members_compliance_mm_per_N(beyond)

    def local_compliance_mm_per_N(self, force_N: ArrayLike) -> float | np.ndarray:
        """dd/dF on the segment that contains ``force_N`` (right-continuous at knots), for a
        number (float) or an array of forces >= 0 (array of the same shape)."""
        knots, slopes = self._segment_compliance
        F = np.asarray(force_N, dtype=float)
        i = np.clip(np.searchsorted(knots, F, side="right") - 1, 0, len(slopes) - 1)
        out = np.where(F >= knots[-1], self.locked_compliance_mm_per_N, slopes[i])
        return float(out) if out.ndim == 0 else out

    def band_start_compliance_mm_per_N(self, regime: int) -> float:
        """dd/dF at the start of regime ``regime`` (0-based), ties split by the lock order.

        Layers that lock before the regime sit on their locked branch; the others on their
        slope just below the regime's start force. For a regime of zero width (two layers
        locking at the same force) this is the limit of the secant as the width shrinks.
        """
        F = self.regime_bounds_N[regime]
        step = 1e-9 * max(F, 1e-12)
        total = self.members_compliance_mm_per_N(F)
        for pos, j in enumerate(self.lock_order):
            law = self.layers[j]
            if pos < regime:
                total += 1.0 / law.k_locked_N_per_mm
            else:
                lo = max(F - step, 0.0)
                d = law.displacement_mm(np.array([lo, lo + step]))
                total += float((d[1] - d[0]) / step)
        return total

    def displacement_mm(self, force_N: ArrayLike) -> np.ndarray:
        """d(F) for F >= 0 (past the last lock the locked stiffnesses carry the load).

        Interpolated on the knots, which is exact (d is linear between them): a curve of m
        samples costs O(m), where summing the layers' laws at every sample cost O(m n), and
        the samples themselves grow with the regimes, so O(n^2) in layers.
        """
        F = np.asarray(force_N, dtype=float)
        knots, d = self._knot_displacement_mm
        beyond = d[-1] + (F - knots[-1]) * self.locked_compliance_mm_per_N
        return np.where(F <= knots[-1], np.interp(F, knots, d), beyond)

    def force_N(self, displacement_mm: ArrayLike) -> np.ndarray:
        """F(d), the exact inverse of d(F) (both piecewise linear on the same knots)."""
        d = np.asarray(displacement_mm, dtype=float)
        F_knots, d_knots = self._knot_displacement_mm
        inside = np.interp(d, d_knots, F_knots)
        beyond = F_knots[-1] + (d - d_knots[-1]) / self.locked_compliance_mm_per_N
        return np.where(d <= d_knots[-1], inside, beyond)
