"""The part's members in the general load (issue 44: mst_cli/model/part_laws.py): the cap, the
plates and the cover ride with the layer whose walls load them.

Every number here is fixed outside the code under test: the axial model of the part and of the
layers alone (``mst simulate``, model.load_path part or layers), the members' closed forms
(mst_cli/model/load_path.py), the statics of two springs at +-x_c (a unit below its knee under a
moment), continuity (members far stiffer than the layers give the layers' answer back) and
mirror symmetry.
"""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mst_cli.model.general_load import loaded_stack, pose_field_T
from mst_cli.model.load_path import Members, members
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics.depth import in_web
from mst_cli.model.mechanics.lateral import closed_block_lateral_N_per_mm
from mst_cli.model.mechanics.tilt import solve_layer_tilt
from mst_cli.model.part_laws import SeriesMember, cover_host, part_layer_laws, unit_tilt_law
from mst_cli.model.plate_sway import section_regimes, stack_section
from mst_cli.model.response import simulate
from mst_cli.model.stack_pose import magnet_field_T, magnet_pose, stack_path, tilt_laws
from mst_cli.sensor.as_printed import as_printed
from mst_cli.sensor.document import load_design_document

FORWARD = Path(__file__).resolve().parents[1] / "configs" / "mohammadi2021-forward.yaml"


@pytest.fixture(scope="module")
def scene():
    doc, _ = load_design_document(FORWARD)
    printed = as_printed(doc)
    return printed.geometry(), printed.material


def units_tilt_laws(geometry, material, parts: Members):
    laws = part_layer_laws(layer_laws(geometry.layers, material, "spring"), parts)
    return [
        unit_tilt_law(law, c, in_web(c, material).youngs_modulus_MPa, material.poisson_ratio)
        for law, c in zip(laws, geometry.layers)
    ]


@pytest.mark.parametrize("whole_part", [True, False])
def test_a_centred_press_is_the_axial_model_of_the_same_load_path(scene, whole_part):
    geometry, material = scene
    axial = simulate(geometry, material, whole_part=whole_part)
    F = axial.force_N
    laws = tilt_laws(geometry, material, "spring", whole_part=whole_part)
    d, tilt = stack_path(laws, F, (0.0, 0.0))
    assert np.all(tilt == 0.0)  # a centred press turns nothing: the part is mirror symmetric
    np.testing.assert_allclose(d.sum(axis=1), axial.displacement_mm, rtol=1e-12, atol=1e-15)
    B = magnet_field_T(geometry, *magnet_pose(geometry, d, tilt))
    np.testing.assert_allclose(B, axial.B_T, rtol=1e-9, atol=1e-15)


def test_each_member_turns_its_layer_as_a_spring_under_each_chevron(scene):
    # below the knee a unit is linear: two chevron lines k/2 at +-x_c, each through its member's
    # compliance C (the member's centred closed form, half of it a side), so the unit turns by
    # phi_y = F x0 (1/k + C) / x_c^2, and the member adds F x0 C / x_c^2 to the layer's own turn
    geometry, material = scene
    parts = members(geometry, material)
    laws = layer_laws(geometry.layers, material, "spring")
    units = tilt_laws(geometry, material, "spring")
    bare = tilt_laws(geometry, material, "spring", whole_part=False)
    # layer j carries its own top pad's bending (plate j, the cap on the top layer) and its walls'
    # joints with the plates, and one layer the cover too (part_stack's members; below the
    # landing all of it bends)
    under = [c + j for c, j in zip([*parts.plates_mm_per_N, parts.cap_mm_per_N], parts.joints_mm_per_N)]
    under[cover_host(list(part_layer_laws(laws, parts)), parts)] += parts.cover_mm_per_N
    F, x0 = 0.02, 5.0
    for law, unit, own, C in zip(laws, units, bare, under):
        assert C > 0.0
        got = solve_layer_tilt(unit, F, (x0, 0.0)).phi_y_rad
        assert got == pytest.approx(F * x0 * (1.0 / law.k_N_per_mm + C) / unit.lever_mm**2, rel=1e-9)
        assert got - solve_layer_tilt(own, F, (x0, 0.0)).phi_y_rad == pytest.approx(
            F * x0 * C / unit.lever_mm**2, rel=1e-6
        )


def test_past_its_lock_the_covers_unit_turns_by_the_layer_and_the_beam_as_before(scene):
    # past the lock a layer is walls at +-x_c (k_w) beside pads pressed over +-a (k_p): under a
    # small moment it turns by 1 / (k_w x_c^2 + k_p a^2 / 3) per N mm (the statics of a line pair
    # and of a uniform bed). The cover in series, outside the layer's contact, adds its turn as a
    # beam's under a couple, C / x_c^2 per N mm (C its compliance past the lock: the unit's less the
    # layer's), in every regime, and its drop C per N; the pads' contact is the layer's own
    geometry, material = scene
    parts = members(geometry, material)
    units = part_layer_laws(layer_laws(geometry.layers, material, "spring"), parts)
    j = cover_host(list(units), parts)
    unit, cell = units[j], geometry.layers[j]
    assert isinstance(unit, SeriesMember)
    law = unit_tilt_law(unit, cell, in_web(cell, material).youngs_modulus_MPa, material.poisson_ratio)
    own = replace(law, member=None)
    C = 1.0 / unit.k_locked_N_per_mm - 1.0 / unit.law.k_locked_N_per_mm
    assert C > 0.0
    k_w, k_p, x_c, a = own.walls.k_after_N_per_mm, own.pad_stiffness_N_per_mm, own.lever_mm, own.pad_half_width_mm
    F, x0, dF = 1.5 * unit.lock_force_N, 0.02, 0.1
    pressed, alone = solve_layer_tilt(law, F, (x0, 0.0)), solve_layer_tilt(own, F, (x0, 0.0))
    assert pressed.phi_y_rad == pytest.approx(F * x0 * (1.0 / (k_w * x_c**2 + k_p * a**2 / 3.0) + C / x_c**2), rel=1e-6)
    assert alone.phi_y_rad == pytest.approx(F * x0 / (k_w * x_c**2 + k_p * a**2 / 3.0), rel=1e-6)
    assert pressed.pad_end_mm == pytest.approx(alone.pad_end_mm, rel=1e-9) and pressed.pads_touch == alone.pads_touch
    more = solve_layer_tilt(law, F + dF, (0.0, 0.0)).d_mm - solve_layer_tilt(law, F, (0.0, 0.0)).d_mm
    assert more == pytest.approx(dF / unit.k_locked_N_per_mm, rel=1e-9)


def test_members_far_stiffer_than_the_layers_give_the_layers_alone(scene):
    geometry, material = scene
    parts = members(geometry, material)
    stiff = replace(
        parts,
        cap_mm_per_N=1e-9 * parts.cap_mm_per_N,
        plates_mm_per_N=tuple(1e-9 * p for p in parts.plates_mm_per_N),
        joints_mm_per_N=tuple(1e-9 * j for j in parts.joints_mm_per_N),
        locked_plates_mm_per_N=tuple(1e-9 * x for x in parts.locked_plates_mm_per_N),
        two_locked_plates_mm_per_N=tuple(1e-9 * x for x in parts.two_locked_plates_mm_per_N),
        cover_mm_per_N=1e-9 * parts.cover_mm_per_N,
        cover_contact_mm_per_N=1e-9 * parts.cover_contact_mm_per_N,
        cover_locked_mm_per_N=1e-9 * parts.cover_contact[3] + 1e-9 * parts.cover_mm_per_N,
        cover_contact_locked_mm_per_N=1e-9 * parts.cover_contact[2],
    )
    F = np.linspace(0.5, 30.0, 7)
    near = pose_field_T(geometry, units_tilt_laws(geometry, material, stiff), F, (4.0, -3.0))
    alone = pose_field_T(geometry, tilt_laws(geometry, material, "spring", whole_part=False), F, (4.0, -3.0))
    np.testing.assert_allclose(near, alone, rtol=1e-6, atol=1e-12)
    # and the members as they are move the magnet further: the part is softer than its layers
    part = pose_field_T(geometry, tilt_laws(geometry, material, "spring"), F, (4.0, -3.0))
    assert np.all(np.linalg.norm(part, axis=1) > np.linalg.norm(alone, axis=1))


def test_a_press_mirrored_in_x_mirrors_the_field_with_the_members(scene):
    geometry, material = scene
    laws = tilt_laws(geometry, material, "spring")
    F = np.array([2.0, 12.0, 30.0])
    a = pose_field_T(geometry, laws, F, (5.0, 2.0))
    b = pose_field_T(geometry, laws, F, (-5.0, 2.0))
    # the chip sits on the axis: mirrored in x, Bx changes sign, By and Bz do not
    np.testing.assert_allclose(b, a * np.array([-1.0, 1.0, 1.0]), rtol=1e-9, atol=1e-15)


def test_a_layers_spec_reads_the_layers_alone_through_the_api(scene):
    # model.load_path: layers keeps the old general load exactly: the layers between rigid plates
    import mst_cli.api as mst
    from mst_cli.model.offcentre import simulate_offcentre

    geometry, material = scene
    doc, _ = load_design_document(FORWARD)
    layers = mst.simulate_offcentre(replace(doc, load_path="layers"), (4.0, -2.0))
    assert not layers.whole_part
    bare = simulate_offcentre(geometry, material, (4.0, -2.0), whole_part=False)
    np.testing.assert_array_equal(layers.B_T, bare.B_T)
    part = mst.simulate_offcentre(doc, (4.0, -2.0))
    assert part.whole_part and np.max(np.abs(part.B_T - layers.B_T)) > 1e-6  # the members move the magnet


def test_past_every_lock_a_tangential_force_slides_the_magnet_by_the_sections_sway_alone(scene):
    """Past the last lock every layer is stuck and shears as its filled block
    (lateral.closed_block_lateral_N_per_mm), so a tangential force along x slides the magnet
    further by those blocks in series, the base's and the plates' sway with every layer filled
    (model.plate_sway.section_regimes' last regime) and the cover, which never locks, turning
    about its own plane (model.counter_turn's slide past the last lock) per newton at every normal
    force; along y by the blocks alone; the layers alone have none of the members' terms."""
    geometry, material = scene
    part = loaded_stack(geometry, material, "spring", whole_part=True)
    alone = loaded_stack(geometry, material, "spring", whole_part=False)
    assert len(part.lateral) == len(alone.lateral) + 3 == len(geometry.layers) + 3
    order = np.argsort([t.lock_force_N for t in part.tilt], kind="stable")
    regimes = section_regimes(stack_section(geometry, material), order)
    base, plates = regimes.base_sway_mm_per_N, regimes.plate_sway_mm_per_N
    last = max(t.lock_force_N for t in part.tilt)
    F = np.array([1.5, 2.0, 3.0]) * last
    slide = part.slides_mm(F, (1.0, 1.0)).sum(axis=1)  # per unit of Fx / Fz and Fy / Fz: U(F)
    own_plane = part.counter_turn.slide_mm_per_N[-1]
    blocks = sum(1.0 / closed_block_lateral_N_per_mm(c, material) for c in geometry.layers)
    rate = np.diff(slide, axis=0) / np.diff(F)[:, None]
    np.testing.assert_allclose(rate[:, 0], blocks + base[-1] + plates[-1] + own_plane, rtol=1e-6)
    np.testing.assert_allclose(rate[:, 1], blocks, rtol=1e-6)
    assert base[-1] > 0.01  # the slot's walls sway
    # between two filled blocks a plate gives only its own shear and turn on the blocks' beds: on
    # the rung (studies/data/plate_slide.csv, past two locks) 0.0004 to 0.0017 mm/N against the
    # base's 0.09 to 0.11, under 2 % of it; here (the forward design past every lock) 1.8 %
    assert 0.0 < plates[-1] < 0.05 * base[-1]
