"""The cover's air: how much of it keeps the cover off the board over the whole range
(docs/design.md 4.6, Contacts). The cover bends over the board's slot until it has closed the air
over the board's tallest part (:func:`~mst_cli.model.load_path.cover_landing_N`); past that the
press bears on the chip and its connectors, a support only the assembled sensor has. Pure.
"""

from __future__ import annotations

from dataclasses import replace

from mst_cli.model.load_path import FINGERTIP_PATCH_MM, first_lock_N, members
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.response import OVERLOAD_REL
from mst_cli.model.stack import contact_drop_mm

# the cover should land no earlier than the end of what simulate draws, the overload included: the
# general load's tilt rung is linear past a layer's lock, so it cannot follow a landing that comes
# after every lock (model.part_laws.cover_host), and none is left on the curves the two compare
LANDING_MARGIN_REL = OVERLOAD_REL


def air_keeping_cover_off_mm(
    geometry,
    material,
    end_N: float,
    patch_mm: float = FINGERTIP_PATCH_MM,
    margin_rel: float = LANDING_MARGIN_REL,
    mechanics: str = "spring",
) -> float:
    """The cover's air, housing.chip_clearance_mm, at which its bending over the slot closes that
    air only at (1 + ``margin_rel``) x ``end_N`` (the range's end), for ``geometry`` (a
    SensorGeometry) in ``material``. A fixed point, not a ratio: the air is part of the slot
    walls' height, and taller walls turn more, so the bending grows with the air (4.3 % for
    0.25 mm more on the forward design). The iteration contracts: that growth is far below 1. The
    bending slows once layer 1 locks (its lock on the rung ``mechanics``, model.stack.contact_drop_mm)."""
    target_N = (1.0 + margin_rel) * end_N
    air_mm = geometry.housing.chip_clearance_mm
    laws = layer_laws(geometry.layers, material, mechanics)
    for _ in range(60):
        g = replace(geometry, housing=replace(geometry.housing, chip_clearance_mm=air_mm))
        parts = members(g, material, patch_mm, "simple")
        C, _, C_locked, _ = parts.cover_contact
        new_mm = float(contact_drop_mm(target_N, first_lock_N(laws, parts), C, C_locked))
        if abs(new_mm - air_mm) <= 1e-9:
            break
        air_mm = new_mm
    return new_mm
