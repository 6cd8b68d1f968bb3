"""What the whole-part rung's members add to the magnet's pose beyond their closed form, per
regime of the part (``model.load_path: section`` in the general load, docs/design.md 4.7).

The general load folds the cap, the plates and the cover into the layers they ride with
(:mod:`mst_cli.model.part_laws`): each turns with its layer under a moment; the base and the
plates also translate (a plane frame, :func:`~mst_cli.model.general_load.section_sway_laws`). The
whole-part rung (:func:`~mst_cli.model.mechanics.whole_part.press_general`) measures what the
members really add in the part's section: the slot's walls sway, the walls' roots turn on the
plates. With ``load_path: section`` the difference is carried as a linear compliance per regime,
the way the axial model carries the centred press's (``Members.regime_extra_mm_per_N``): between
the part's lock forces each figure takes its regime's value, so along a load's ray (its offset
and its tangential ratio fixed, the normal force rising) the pose it adds is the integral of a
piecewise-constant compliance, piecewise linear with knots at the locks.

The rung is a section in the x-z plane, so the figures are about x: a press's offset along x,
a tangential force along x, a turn about +y. Along y the closed form stands (the part is not the
same across its depth: the board slot opens toward +y). Pure.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mst_cli.model.stack import regime_extra_displacement_mm

MEMBER_POSE_FIGURES = (
    "drop_mm_per_N",  # the centred press's drop (down > 0)
    "side_mm_per_N",  # the centred press's motion along +x (the slot opens on one side)
    "turn_rad_per_N",  # the centred press's turn about +y
    "slide_mm_per_N",  # per newton of tangential force along +x on the top face
    "turn_per_moment_rad_per_Nmm",  # about +y per N mm of a press's moment x Fz
    "turn_per_tangential_rad_per_N",  # about +y per newton of tangential force along +x
)


@dataclass(frozen=True)
class MemberPose:
    """Per regime of the part (bottom regime first), what the members add beyond their closed
    form to the magnet's pose per unit load (:data:`MEMBER_POSE_FIGURES`; turns right-handed,
    a turn about +y moves the top toward +x). ``edges_N``: the part's lock forces, ascending,
    one per regime: regime r (from 1) ends at ``edges_N[r - 1]``, the last one's figures hold
    past the last lock (:func:`~mst_cli.model.stack.regime_extra_displacement_mm`)."""

    edges_N: tuple[float, ...]
    drop_mm_per_N: tuple[float, ...]
    side_mm_per_N: tuple[float, ...]
    turn_rad_per_N: tuple[float, ...]
    slide_mm_per_N: tuple[float, ...]
    turn_per_moment_rad_per_Nmm: tuple[float, ...]
    turn_per_tangential_rad_per_N: tuple[float, ...]

    def __post_init__(self) -> None:
        n = len(self.edges_N)
        if any(len(getattr(self, k)) != n for k in MEMBER_POSE_FIGURES):
            raise ValueError(f"every figure needs one value per regime ({n})")

    def at(self, force_N: float) -> dict[str, float]:
        """The figures of the regime the normal force ``force_N`` is in (right-continuous at the
        locks): the tangent a linear model of the part has there (the ray's pose's slope)."""
        r = min(int(np.searchsorted(self.edges_N, float(force_N), side="right")), len(self.edges_N) - 1)
        return {k: getattr(self, k)[r] for k in MEMBER_POSE_FIGURES}

    def _integral(self, force_N: np.ndarray, figure: str) -> np.ndarray:
        """The figure's compliance integrated from 0 to each force (m,)."""
        return regime_extra_displacement_mm(force_N, self.edges_N, getattr(self, figure))

    def pose_gradient(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(d shift (m, 3, 5) mm, d rotation vector (m, 3, 5)): :meth:`pose`'s derivative in the
        loads ``theta`` (m, 5) = (Fz N, Fx N, Fy N, x mm, y mm), the ratio rx = Fx / Fz (0 at Fz <= 0).
        Each figure's integral W has its regime's figure for slope (:meth:`at`: right-continuous
        at a lock); d rx / dFz = -rx / Fz, d rx / dFx = 1 / Fz."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        F, x = theta[:, 0], theta[:, 3]
        safe = np.where(F > 0.0, F, 1.0)
        rx = np.where(F > 0.0, theta[:, 1] / safe, 0.0)
        r = np.minimum(np.searchsorted(self.edges_N, F, side="right"), len(self.edges_N) - 1)
        W = {k: self._integral(F, k) for k in MEMBER_POSE_FIGURES}
        c = {k: np.asarray(getattr(self, k))[r] for k in MEMBER_POSE_FIGURES}
        drx_dF, drx_dFx = -rx / safe, 1.0 / safe
        dshift, drot = np.zeros((len(F), 3, 5)), np.zeros((len(F), 3, 5))
        dshift[:, 0, 0] = c["side_mm_per_N"] + drx_dF * W["slide_mm_per_N"] + rx * c["slide_mm_per_N"]
        dshift[:, 0, 1] = drx_dFx * W["slide_mm_per_N"]
        dshift[:, 2, 0] = -c["drop_mm_per_N"]
        tpt = "turn_per_tangential_rad_per_N"
        turn_F = c["turn_rad_per_N"] + x * c["turn_per_moment_rad_per_Nmm"] + drx_dF * W[tpt] + rx * c[tpt]
        drot[:, 1, 0] = turn_F
        drot[:, 1, 1] = drx_dFx * W[tpt]
        drot[:, 1, 3] = W["turn_per_moment_rad_per_Nmm"]
        return dshift, drot

    def pose(self, force_N, ratio_x, offset_x_mm) -> tuple[np.ndarray, np.ndarray]:
        """(shift (m, 3) mm, rotation vector (m, 3) rad) the members add at the normal forces
        ``force_N`` (m,), the tangential force along x ``ratio_x`` (m,) x the normal one, pressed
        at x = ``offset_x_mm`` (m,)."""
        F = np.atleast_1d(np.asarray(force_N, dtype=float))
        rx = np.broadcast_to(np.asarray(ratio_x, dtype=float), F.shape)
        x = np.broadcast_to(np.asarray(offset_x_mm, dtype=float), F.shape)
        W = {k: self._integral(F, k) for k in MEMBER_POSE_FIGURES}
        shift = np.zeros((len(F), 3))
        rotvec = np.zeros((len(F), 3))
        shift[:, 0] = W["side_mm_per_N"] + rx * W["slide_mm_per_N"]
        shift[:, 2] = -W["drop_mm_per_N"]
        turn = W["turn_rad_per_N"] + x * W["turn_per_moment_rad_per_Nmm"]
        rotvec[:, 1] = turn + rx * W["turn_per_tangential_rad_per_N"]
        return shift, rotvec
