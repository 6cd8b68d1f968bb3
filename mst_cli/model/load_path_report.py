"""report.json's ``load_path`` section and what ``mst check`` reads from it: the members'
compliance in closed form (:mod:`mst_cli.model.load_path`), each member's share of the magnet's
motion per regime, the supports' uncertainty and the press's patch (docs/design.md 4.6). Pure
numpy, no I/O.
"""

from __future__ import annotations

import math
from dataclasses import replace

from mst_cli.model.load_path import (
    ACCURACY_BUDGET_REL,
    FINGERTIP_PATCH_MM,
    Members,
    cover_landing_N,
    first_lock_N,
    members,
    motion_shares,
)


def load_path_report(
    geometry, material, stack, patch_mm: float = FINGERTIP_PATCH_MM, regime_extra_mm_per_N: tuple = ()
) -> dict:
    """report.json's ``load_path``: the members' compliance (simply supported, and the clamped
    bound) and, per regime of the part, each member's share of the magnet's motion as the forward
    model moves it (:func:`motion_shares`, docs/design.md 4.6), with the whole-part rung's
    correction per regime when one is given (model.load_path: section, both bounds alike)."""
    extra = tuple(regime_extra_mm_per_N)
    simple = replace(members(geometry, material, patch_mm, "simple"), regime_extra_mm_per_N=extra)
    clamped = replace(members(geometry, material, patch_mm, "clamped"), regime_extra_mm_per_N=extra)
    bound = motion_shares(stack, clamped)
    regimes = []
    for row, stiff in zip(motion_shares(stack, simple), bound):
        row["outside_layers_clamped"] = stiff["outside_layers"]
        row["members_clamped_mm_per_N"] = stiff["members_mm_per_N"]
        regimes.append(row)
    first_lock = first_lock_N(stack.layers, simple)  # layer 1's in the part: the cover stiffens under it
    report = {
        "patch_mm": patch_mm,
        "support": "simple (clamped: the stiff bound)",
        "cap_mm_per_N": simple.cap_mm_per_N,
        "plates_mm_per_N": list(simple.plates_mm_per_N),
        "plate_joints_mm_per_N": list(simple.joints_mm_per_N),  # each layer's, model.plate_joint
        "plates_over_locked_mm_per_N": list(simple.locked_plates_mm_per_N),  # each plate's, model.past_lock
        # of which the top layer's walls' thrust (model.wall_thrust) and the feet's press into the block
        "plates_over_locked_thrust_mm_per_N": list(simple.thrust_mm_per_N),
        "plates_over_locked_press_mm_per_N": list(simple.press_mm_per_N),
        "housing_mm_per_N": simple.cover_mm_per_N,
        # once layer 1 is locked on the cover (its closed block on the cover's link: load_path)
        "housing_under_locked_layer_1_mm_per_N": simple.cover_mm_per_N + simple.cover_contact[3],
        "cap_clamped_mm_per_N": clamped.cap_mm_per_N,
        "members_simple_mm_per_N": _by_member(simple),
        "members_clamped_mm_per_N": _by_member(clamped),
        "regimes": regimes,
        "outside_layers_max": max(r["outside_layers"] for r in regimes),
        # null: the cover never lands (no bending over the slot)
        "cover_lands_N": None if math.isinf(landing := cover_landing_N(simple, first_lock)) else landing,
        "patch_dependence": patch_dependence(geometry, material, stack),
        "not_modelled": "the cover's bending along the depth over the cable windows (3D; walls on both sides)",
    }
    if extra:  # model.load_path section: what the whole-part rung adds per regime (docs/design.md 4.7)
        report["section_correction_mm_per_N"] = list(extra)
    return report


def support_uncertainty(report: dict) -> list[dict]:
    """Per regime of :func:`load_path_report`: the share of the part's compliance the members'
    closed form leaves uncertain, between its simply supported and clamped wall heads
    (|C_simple - C_clamped| of the members as each moves in that regime, over the part's
    compliance there), against the regime's accuracy budget (:data:`ACCURACY_BUDGET_REL`), with
    the member whose supports matter most there. The tolerance on the share outside the layers
    that ``mst check`` applies by default."""
    rows = []
    for i, row in enumerate(report["regimes"]):
        simple, clamped = row["members_mm_per_N"], row["members_clamped_mm_per_N"]
        spread = {k: simple[k] - clamped[k] for k in simple}
        rows.append(
            {
                "regime": row["regime"],
                "uncertain_share": abs(sum(spread.values())) / row["compliance_mm_per_N"],
                "budget": ACCURACY_BUDGET_REL[min(i, len(ACCURACY_BUDGET_REL) - 1)],
                "member": max(spread, key=lambda k: abs(spread[k])),
            }
        )
    return rows


def _by_member(parts: Members) -> dict:
    plates = sum(parts.plates_mm_per_N) + sum(parts.joints_mm_per_N)  # the plates' bending and their joints
    return {"cap": parts.cap_mm_per_N, "plates": plates, "housing": parts.cover_mm_per_N}


def dominant_member(row: dict) -> tuple[str, float]:
    """The member outside the layers with the largest share in a regime row of :func:`motion_shares`."""
    name = max(("cap", "plates", "housing"), key=lambda k: row["shares"][k])
    return name, row["shares"][name]


def patch_dependence(geometry, material, stack) -> list[dict]:
    """How the response depends on the press's contact patch: the cap's compliance and the share
    outside the layers in the first and last regimes, for a fingertip's half, itself, twice it
    and the whole face."""
    rows = []
    for patch in (0.5 * FINGERTIP_PATCH_MM, FINGERTIP_PATCH_MM, 2.0 * FINGERTIP_PATCH_MM, geometry.width_mm):
        parts = members(geometry, material, patch)
        shares = motion_shares(stack, parts)
        rows.append(
            {
                "patch_mm": patch,
                "cap_mm_per_N": parts.cap_mm_per_N,
                "compliance_first_regime_mm_per_N": shares[0]["compliance_mm_per_N"],
                "outside_layers_first_regime": shares[0]["outside_layers"],
                "outside_layers_last_regime": shares[-1]["outside_layers"],
            }
        )
    return rows
