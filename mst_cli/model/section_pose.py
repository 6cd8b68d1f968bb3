"""The members' pose in section mode: the whole-part rung's members against their closed form
in the general load, per regime (``model.load_path: section``, docs/design.md 4.7).

Per regime of the part (the layers locked before it closed, as the axial model's section
correction takes them), the rung's three loads of the plane on one factorised stiffness
(:func:`~mst_cli.model.mechanics.whole_part.press_general`), as printed and with the members
rigid: what the members add is the difference. mst's closed form's own share is its general
load with the members (``whole_part``) less without, each linearised where its own regime starts
(2 % of the first lock, else 2 % past the lock that opens it: the part's locks come before the
layers' own, its cap and plates closing a cavity early), as ``mst check --whole-part`` reads it.
The :class:`~mst_cli.model.member_pose.MemberPose` carries the rung's share less the closed
form's; its drop is the axial model's own correction (``Members.regime_extra_mm_per_N``), so a
centred press gives the axial section model's drop, as the closed form's general load gives the
closed form's. 2 solves a regime, side by side; the rows of one geometry are kept in the process.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

import mst_cli.model.mechanics.whole_part as wp
from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.counter_turn import regime_start_N
from mst_cli.model.general_load import centred_response, linear_response, loaded_stack
from mst_cli.model.material import Material
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.member_pose import MEMBER_POSE_FIGURES, MemberPose
from mst_cli.model.response import part_stack

_MEMO: dict = {}
MEMO_SIZE = 4


def section_member_pose(
    geometry: SensorGeometry,
    material: Material,
    mechanics: str,
    patch_mm: float = wp.FINGERTIP_PATCH_MM,
    options: wp.PartOptions | None = None,
) -> MemberPose:
    """The members' pose beyond their closed form, per regime of the part (module docstring)."""
    key = (repr(geometry), repr(material), mechanics, patch_mm, options)
    if key in _MEMO:
        return _MEMO[key]
    laws = layer_laws(geometry.layers, material, mechanics)
    parts, _ = wp.section_members(geometry, material, laws, patch_mm, options)
    part = part_stack(laws, parts)
    edges = tuple(float(f) for f in part.regime_bounds_N[1:])
    opts = wp.PartOptions(patch_mm=patch_mm) if options is None else replace(options, patch_mm=patch_mm)
    jobs = [
        replace(opts, locked=tuple(locked), member_factor=factor)
        for locked in wp.regime_locked(part)
        for factor in (1.0, wp.RIGID_FACTOR)
    ]
    motions = wp.general_motions(geometry, material, jobs)
    closed = {whole: loaded_stack(geometry, material, mechanics, 1.0, whole) for whole in (True, False)}
    layer_locks = sorted(float(t.lock_force_N) for t in closed[False].tilt)
    rows = []
    for r in range(len(edges)):
        rung = rung_figures(motions[2 * r]) - rung_figures(motions[2 * r + 1])
        # each model where its own regime r starts: the part's members lock its layers earlier
        # than the layers alone lock (a cap bends into its cavity), so one force would read the
        # layers in another state than the part's
        with_members = closed_figures(closed[True], regime_start_N(edges, r))
        stated = with_members - closed_figures(closed[False], regime_start_N(layer_locks, r))
        rows.append(rung - stated)
    figures = dict(zip(MEMBER_POSE_FIGURES, np.array(rows).T))
    figures["drop_mm_per_N"] = np.asarray(parts.regime_extra_mm_per_N, dtype=float)
    pose = MemberPose(edges, **{k: tuple(float(v) for v in figures[k]) for k in MEMBER_POSE_FIGURES})
    _MEMO[key] = pose
    while len(_MEMO) > MEMO_SIZE:
        _MEMO.pop(next(iter(_MEMO)))
    return pose


def rung_figures(motion: wp.GeneralMotion) -> np.ndarray:
    """The rung's figures (:data:`MEMBER_POSE_FIGURES`) in the general load's sign (turns
    right-handed about +y: the rung's turn lifts +x, so its opposite)."""
    return np.array(
        [
            motion.press.drop_mm_per_N,
            motion.press.side_mm_per_N,
            -motion.press.turn_rad_per_N,
            motion.pull.side_mm_per_N,
            -motion.turn_per_moment_rad_per_Nmm,
            -motion.pull.turn_rad_per_N,
        ]
    )


def closed_figures(stack, force_N: float) -> np.ndarray:
    """The general load's figures (:data:`MEMBER_POSE_FIGURES`) linearised at ``force_N``."""
    drop, side, turn = centred_response(stack, force_N)
    per_moment, slide, per_tangential = linear_response(stack, force_N)
    return np.array([drop, side, turn, slide, per_moment, per_tangential])
