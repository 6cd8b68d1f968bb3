"""The stack under a general load (issue 39): a force (Fx, Fy, Fz) pressed at (x0, y0) on the
top face, and the field it gives at one chip or more.

The load model and what it assumes:

* Every layer carries the whole force and the moments of the load above it. About layer j's
  pivot (its mid-plane, z_j) the normal force Fz at (x0, y0) gives the tilt rung's moments
  (Fz x0, Fz y0) (:mod:`mst_cli.model.mechanics.tilt`); the tangential force, applied at the
  top face's height z_top, adds (Fx h_j, Fy h_j) with h_j = z_top - z_j (a push toward +x
  closes the +x side, as a press at +x does). So layer j answers as the tilt rung under Fz
  pressed at (x0 + Fx h_j / Fz, y0 + Fy h_j / Fz): a compression at the axis and two tilts.
  Small rotations, no P-delta; the tangential force does not compress a layer (its part is odd
  about the mid-plane, L2's decoupling, :mod:`mst_cli.model.mechanics.continuum_lateral`).
* The plates translate: each layer's top plate slides over its bottom one by (Fx c_x, Fy c_y),
  the layers in series. The press grows along a ray from zero (Fx : Fy : Fz fixed, inside a
  friction cone), so a layer's slide is the integral of dF_t / k_t along its compression path:
  c(Fz) = (1 / Fz) int_0^Fz dF / k(d(F)), d(F) the layer's centred compression (the tilt's
  change of it ignored). k from the rung: ``spring`` and ``frame`` take L0's small-load closed
  forms (:mod:`mst_cli.model.mechanics.lateral`) up to the layer's lock, and past it the
  pads pressed together stick (L2's stuck tangent past the lock is 8 to 40 times its free one,
  docs/design.md section 4.4) and the closed layer shears as its filled block, as the whole-part
  rung closes it (a few um/N; it was taken rigid before 2026-12-02); ``continuum`` takes L2's
  lateral tangents along its compression path
  (:func:`~mst_cli.model.mechanics.continuum_lateral.lateral_path`), frictionless before the lock
  and stuck past it, k_y times L0's free-face factor.
* With the part's members, the housing's base and the TPU plates between the layers let the
  stack translate too, by c_b Fx and c_p Fx, each stepping as the layers lock
  (:func:`section_sway_laws`: a plane frame of the walls, the plates, the cover and the slot's
  walls, model.plate_sway).
* With the part's members, a tangential force turns them less than its moment alone would: the
  walls' end moments turn the plates and the cover back. Each layer's members' share of the
  pull's turn is scaled by the section frame's ratio of the two, per regime
  (:mod:`mst_cli.model.counter_turn`).
* The magnet's pose adds the tilts' turns and shifts and the slides
  (:func:`mst_cli.model.stack_pose.magnet_pose`); its exact field at each chip follows.

At Fx = Fy = 0 it is the off-centre press (:mod:`mst_cli.model.offcentre`) exactly.

The forward model is written once, batched: :func:`fields_T` takes loads (m, 5) = (Fz, Fx, Fy, x,
y) (one load is a batch of one) to the fields at every chip (m, 3 k), in two parts that its
callers may take apart: :func:`layer_states`, every layer's equilibrium solved exactly per load
(warm-started where a caller knows a close load's), and :func:`fields_of`, the slides, the magnet's
pose and its exact field at every chip in one call. Its Jacobian is :func:`field_jacobian_T`
(differences, the steps :func:`fd_steps`), and :func:`path_fields_T` its fields up a force path
(what a table holds). Its callers: the Cramer-Rao bound (:mod:`mst_cli.model.load_bound`), the exact
shear reader, the offset estimator (on :func:`normal_stack`, no slides), the tables' paths, the
off-centre press's field (:func:`pose_field_T`: ``mst simulate``'s offset map, the tilt
calibration), and the two-chip reader, whose states go through :func:`fields_of`.

Pure: no I/O.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mst_cli.model.assembly import SensorGeometry
from mst_cli.model.counter_turn import (
    CounterTurn,
    counter_turn,
    members_tilt_rad_per_Nmm,
    own_plane_slide_mm_per_N,
    unit_arms_mm,
)
from mst_cli.model.load_path import members
from mst_cli.model.material import Material
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.mechanics.lateral import (
    closed_block_lateral_N_per_mm,
    depth_end_factor,
    lateral_stiffness_N_per_mm,
)
from mst_cli.model.mechanics.tilt import LayerTiltLaw, TiltError, centred_compression_mm
from mst_cli.model.member_pose import MemberPose
from mst_cli.model.part_laws import unit_members
from mst_cli.model.plate_sway import SectionRegimes, member_planes_mm, section_regimes, stack_section
from mst_cli.model.stack_pose import layer_pivots_mm, magnet_field_T, magnet_pose, stack_path, tilt_laws
from mst_cli.parallel import one_blas_thread

SHEAR_RATIO_MAX = 1.0  # |Fx / Fz|, |Fy / Fz| the model takes (a friction cone of TPU on skin or TPU)
COMPLIANCE_SAMPLES = 4001  # force samples of a layer's mean lateral compliance, 0 to FORCE_SPAN x its lock
FORCE_SPAN = 20.0  # beyond it the compliance integral goes on with its last integrand


@dataclass(frozen=True)
class LayerLateralLaw:
    """One layer's slide under a tangential force growing with the normal one: U(F) = int_0^F
    dF' / k(d(F')), the slide at normal force F per unit of the ratio F_t / F (mm), sampled on
    ``force_N``; the mean compliance c(F) = U(F) / F."""

    force_N: np.ndarray  # (k,) from 0
    integral_x_mm: np.ndarray  # (k,) U_x(F), mm per unit of Fx / Fz
    integral_y_mm: np.ndarray  # (k,)

    def compliance_mm_per_N(self, force_N) -> tuple[np.ndarray, np.ndarray]:
        """(c_x, c_y) at normal forces ``force_N``: the slide per newton of tangential force."""
        F = np.asarray(force_N, dtype=float)
        out = []
        for U in (self.integral_x_mm, self.integral_y_mm):
            tail = (U[-1] - U[-2]) / (self.force_N[-1] - self.force_N[-2])  # 1/k past the samples
            u = np.where(F <= self.force_N[-1], np.interp(F, self.force_N, U), U[-1] + tail * (F - self.force_N[-1]))
            small = F <= self.force_N[1]
            first = (U[1] - U[0]) / self.force_N[1]  # c(0) = 1 / k(0)
            out.append(np.where(small, first, u / np.where(small, 1.0, F)))
        return out[0], out[1]


def lateral_law(tilt: LayerTiltLaw, k_x, k_y) -> LayerLateralLaw:
    """The layer's :class:`LayerLateralLaw` from its tangent stiffnesses ``k_x(d)``, ``k_y(d)``
    (callables of the compression, N/mm; inf: no slide) along its centred compression."""
    F = np.linspace(0.0, FORCE_SPAN * tilt.lock_force_N, COMPLIANCE_SAMPLES)
    d = centred_compression_mm(tilt, F)
    mid_d = 0.5 * (d[1:] + d[:-1])
    dF = np.diff(F)
    integrals = [np.concatenate([[0.0], np.cumsum(dF / k(mid_d))]) for k in (k_x, k_y)]
    return LayerLateralLaw(F, integrals[0], integrals[1])


def _l0_law(tilt: LayerTiltLaw, cell, material: Material) -> LayerLateralLaw:
    """L0: the small-load k up to the lock; past it the pads stick and the closed layer shears as
    its filled block (:func:`~mst_cli.model.mechanics.lateral.closed_block_lateral_N_per_mm`)."""
    k0 = lateral_stiffness_N_per_mm(cell, material)
    closed = closed_block_lateral_N_per_mm(cell, material)
    lock = tilt.pad_gap_mm
    return lateral_law(tilt, *(lambda d, k=k: np.where(d < lock, k, closed) for k in k0))


L2_FRACTIONS = (0.0, 0.25, 0.5, 0.75, 0.95, 1.05)  # of the lock stroke where L2's lateral tangents are solved


@functools.lru_cache(maxsize=32)
def _l2_path(cell, material: Material):
    """L2's lateral path of one cell (seconds each: kept for the process)."""
    from mst_cli.model.mechanics.continuum_lateral import lateral_path  # deferred: L2 loads when asked

    return lateral_path(cell, material, L2_FRACTIONS)


def _l2_law(tilt: LayerTiltLaw, cell, material: Material) -> LayerLateralLaw:
    """L2: the lateral path's tangents, frictionless before the lock, stuck past it."""
    fractions = L2_FRACTIONS
    p = _l2_path(cell, material)
    end = float(depth_end_factor(cell.t_mm, cell.wall_length_mm, cell.depth_mm))
    lock = tilt.pad_gap_mm
    f = np.array(fractions[:-1])

    def tangent(free, stuck, scale=1.0):
        return lambda d: scale * np.where(d < lock, np.interp(d / lock, f, free[:-1]), stuck[-1])

    return lateral_law(
        tilt,
        tangent(p.k_x_free_N_per_mm, p.k_x_stuck_N_per_mm),
        tangent(p.k_y_free_N_per_mm, p.k_y_stuck_N_per_mm, end),
    )


@dataclass(frozen=True)
class LoadedStack:
    """What the general load's forward model needs, built once per design and rung."""

    geometry: SensorGeometry
    mechanics: str
    tilt: list[LayerTiltLaw]
    lateral: list[LayerLateralLaw]  # the layers', bottom first, then (the whole part) the base's sway
    lever_mm: np.ndarray  # (n,) the top face's height over each layer's pivot
    # model.load_path section: what the whole-part rung's members add beyond the closed form
    members_pose: MemberPose | None = None
    counter_turn: CounterTurn | None = None  # the whole part: its members' turn under a pull, the frame's

    def tilts_with_counter_turn(self, force_N, tilt: np.ndarray, ratio_x, tangent: bool = False) -> np.ndarray:
        """The layers' tilts (m, n, 2) at normal forces ``force_N`` (m,) with the members'
        counter-turn on the ray whose tangential force is ``ratio_x`` x the normal one added (its
        path integral; with ``tangent``, its rate there, as a linear model of the part)."""
        if self.counter_turn is None:
            return tilt
        if tangent:
            F = np.asarray(force_N, dtype=float)
            return tilt + self.counter_turn.tangent_tilt_rad(F, np.asarray(ratio_x, dtype=float) * F)
        return tilt + self.counter_turn.tilt_rad(force_N, ratio_x)

    def pose(
        self, force_N: np.ndarray, d: np.ndarray, tilt: np.ndarray, slide: np.ndarray | None, ratio_x, offset_x_mm
    ) -> tuple[np.ndarray, np.ndarray]:
        """(the magnet centre's displacement (m, 3) mm, its rotation vector (m, 3)) from the
        layers' compressions, tilts and slides at the normal forces ``force_N`` (m,), plus what
        the members add in section mode (pressed at x = ``offset_x_mm``, the tangential force
        along x ``ratio_x`` x the normal one)."""
        shift, rotvec = magnet_pose(self.geometry, d, self.tilts_with_counter_turn(force_N, tilt, ratio_x), slide)
        if self.members_pose is not None:
            extra_shift, extra_turn = self.members_pose.pose(force_N, ratio_x, offset_x_mm)
            shift, rotvec = shift + extra_shift, rotvec + extra_turn
        return shift, rotvec

    def layer_offsets_mm(self, offset_mm, ratio) -> np.ndarray:
        """(n, 2): where each layer sees Fz pressed, the tangential force's moment included;
        ``ratio`` = (Fx / Fz, Fy / Fz)."""
        return np.asarray(offset_mm, dtype=float)[None, :] + np.outer(self.lever_mm, np.asarray(ratio, dtype=float))

    def slides_mm(self, force_N, ratio) -> np.ndarray:
        """(m, n, 2): every layer's slide at normal forces ``force_N`` (m,) and tangential
        ``ratio`` x the normal force."""
        F = np.asarray(force_N, dtype=float)
        out = np.zeros((len(F), len(self.lateral), 2))
        for j, law in enumerate(self.lateral):
            cx, cy = law.compliance_mm_per_N(F)
            out[:, j, 0], out[:, j, 1] = ratio[0] * F * cx, ratio[1] * F * cy
        return out


def loaded_stack(
    geometry: SensorGeometry,
    material: Material,
    mechanics: str = "spring",
    lever_factor: float = 1.0,
    whole_part: bool = True,
    members: MemberPose | None = None,
) -> LoadedStack:
    """The tilt laws and lateral laws of every layer on the named rung, each layer with the
    part's members its walls load unless ``whole_part`` is False (model.load_path: layers;
    :func:`~mst_cli.model.stack_pose.tilt_laws`), and ``members``, what the whole-part rung's
    members add beyond their closed form, when given (model.load_path: section,
    :func:`~mst_cli.model.offcentre.section_members_pose`)."""
    tilts = tilt_laws(geometry, material, mechanics, lever_factor, whole_part)
    build = _l2_law if mechanics == "continuum" else _l0_law
    lateral = [build(t, c, material) for t, c in zip(tilts, geometry.layers)]
    lever = geometry.total_height_mm - layer_pivots_mm(geometry)
    if not whole_part:
        return LoadedStack(geometry, mechanics, tilts, lateral, lever, members)
    lateral += section_sway_laws(tilts, _section_regimes(geometry, material, _lock_order(tilts)))
    turn = _counter_turn(geometry, material, mechanics, lever_factor)
    assert turn.slide_mm_per_N is not None  # part_counter_turn gives it
    lateral += regime_lateral_laws(tilts, turn.slide_mm_per_N)  # the members' turn about their own planes
    return LoadedStack(geometry, mechanics, tilts, lateral, lever, members, turn)


@functools.lru_cache(maxsize=32)
def _counter_turn(geometry: SensorGeometry, material: Material, mechanics: str, lever_factor: float) -> CounterTurn:
    """The part's members' counter-turn (model.counter_turn; 5 to 10 ms on the bundled designs past
    the frame's solves), kept per part and rung as the frame is."""
    turn = part_counter_turn(geometry, material, mechanics, lever_factor)
    assert turn.slide_mm_per_N is not None  # part_counter_turn gives it
    return _frozen(turn, turn.edges_N, turn.tilt_rad_per_N, turn.slide_mm_per_N)


def part_counter_turn(
    geometry: SensorGeometry, material: Material, mechanics: str, lever_factor: float,
    regimes: SectionRegimes | None = None,
) -> CounterTurn:  # fmt: skip
    """The counter-turn of a part from its section's frame ``regimes`` (in the part's lock order;
    None: the part's own, kept per part): each unit's members, as they ride with it regime by
    regime (model.part_laws.unit_members), turned by the pull at their own levers
    (model.counter_turn.unit_arms_mm)."""
    part = tilt_laws(geometry, material, mechanics, lever_factor, True)
    regimes = _section_regimes(geometry, material, _lock_order(part)) if regimes is None else regimes
    alone = tilt_laws(geometry, material, mechanics, lever_factor, False)
    lever = geometry.total_height_mm - layer_pivots_mm(geometry)
    laws = layer_laws(geometry.layers, material, mechanics)
    riding = unit_members(laws, members(geometry, material), _lock_order(part))
    tilt = members_tilt_rad_per_Nmm(part, alone)
    z = member_planes_mm(stack_section(geometry, material))
    slide = own_plane_slide_mm_per_N(riding, regimes.member_arm_mm, tilt[1], layer_pivots_mm(geometry), z)
    return counter_turn(part, alone, lever, unit_arms_mm(riding, regimes.member_arm_mm, lever), slide, tilt)


def _frozen(kept, *arrays: np.ndarray):
    """``kept``, a cached answer, with its ``arrays`` read-only: every caller shares them."""
    for a in arrays:
        a.flags.writeable = False
    return kept


def _lock_order(tilts: list[LayerTiltLaw]) -> tuple[int, ...]:
    """The layers' indices, first to lock first."""
    return tuple(int(i) for i in np.argsort([t.lock_force_N for t in tilts], kind="stable"))


def section_sway_laws(tilts: list[LayerTiltLaw], regimes: SectionRegimes) -> list[LayerLateralLaw]:
    """[the housing's base, the plates]: their translation under the tangential force along x as
    lateral laws (:func:`regime_lateral_laws`; ``regimes``: the section's frame,
    :func:`~mst_cli.model.plate_sway.section_regimes` in the lock order of ``tilts``)."""
    return regime_lateral_laws(tilts, regimes.base_sway_mm_per_N, regimes.plate_sway_mm_per_N)


def regime_lateral_laws(tilts: list[LayerTiltLaw], *compliances: np.ndarray) -> list[LayerLateralLaw]:
    """Each of ``compliances`` (a slide along x per newton of Fx per regime, in the lock order of
    ``tilts``) as a lateral law: constant within a regime, stepping at the layers' lock forces; none
    along y (the frame is the section's)."""
    locks = np.sort([t.lock_force_N for t in tilts])
    edges = np.concatenate([[0.0], locks])
    edges = edges[np.isfinite(edges)]  # a layer that never locks: the regimes past it are never reached
    force = np.concatenate([edges, [edges[-1] + 1.0]])  # past the last lock: its slope goes on
    laws = []
    for c in compliances:
        integral = np.concatenate([[0.0], np.cumsum(np.diff(force) * c[: len(edges)])])
        laws.append(LayerLateralLaw(force, integral, np.zeros_like(force)))
    return laws


@functools.lru_cache(maxsize=32)
def _section_regimes(geometry: SensorGeometry, material: Material, lock_order: tuple[int, ...]) -> SectionRegimes:
    """The section's frame per regime (26 frame solves on three layers, 21 to 32 ms idle:
    benchmarks/bench_whole_part.py --section-sway), kept per part: every stack of one design (its
    tables, its readers) takes the same."""
    with one_blas_thread():  # solves of about 300 dofs: BLAS's threads give nothing, and cost on a busy machine
        r = section_regimes(stack_section(geometry, material), lock_order)
    return _frozen(r, r.base_sway_mm_per_N, r.plate_sway_mm_per_N, r.member_turn_ratio, r.member_arm_mm)


def normal_stack(
    geometry: SensorGeometry, tilts: list[LayerTiltLaw], mechanics: str, members: MemberPose | None = None
) -> LoadedStack:
    """A stack for normal loads alone (the off-centre press's, without the lateral laws' cost):
    its layers' tilt laws ``tilts``, no slide (a tangential load on it is not modelled), and
    ``members`` (model.load_path: section) when given."""
    return LoadedStack(geometry, mechanics, tilts, [], geometry.total_height_mm - layer_pivots_mm(geometry), members)


def load_path(
    stack: LoadedStack, force_N: np.ndarray, offset_mm, ratio=(0.0, 0.0)
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(d (m, n), tilts (m, n, 2), slides (m, n, 2)) along normal forces ``force_N`` (m,)
    ascending, pressed at ``offset_mm`` with the tangential force ``ratio`` x the normal one."""
    F = np.asarray(force_N, dtype=float)
    d, tilt = stack_path(stack.tilt, F, stack.layer_offsets_mm(offset_mm, ratio))
    return d, tilt, stack.slides_mm(F, ratio)


def load_ratios(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Fz, Fx / Fz, Fy / Fz) of loads (m, 5) (ratios 0 at Fz <= 0)."""
    F = theta[:, 0]
    safe = np.where(F > 0.0, F, 1.0)
    return F, np.where(F > 0.0, theta[:, 1] / safe, 0.0), np.where(F > 0.0, theta[:, 2] / safe, 0.0)


def linear_response(
    stack: LoadedStack, force_N: float, offset_mm: float = 0.05, ratio: float = 1e-3
) -> tuple[float, float, float]:
    """The general load linearised about the centred press ``force_N`` in the x-z plane, as a
    linear model of the part (the whole-part rung) is: (the magnet's turn about +y per N mm of an
    off-centre press's moment, its slide along +x per newton of tangential force along +x, its
    turn about +y per newton of that force); turns right-handed, in rad. A small ``offset_mm`` and
    shear ``ratio`` at that normal force: the tilts' elastic equilibrium, plus the layers' tangent
    lateral compliance there (the slides' path integral's slope; the model's slides follow the
    load's ray, so its own secant is not a linear model's figure), and in section mode the
    members' figures of the regime there (their pose's slope along the ray, likewise)."""
    F = np.array([float(force_N)])

    def pose(offset: tuple[float, float], shear: tuple[float, float]) -> tuple[float, float]:
        d, tilt, _ = load_path(stack, F, offset, shear)
        shift, rotvec = magnet_pose(stack.geometry, d, stack.tilts_with_counter_turn(F, tilt, shear[0], tangent=True))
        return float(shift[0, 0]), float(rotvec[0, 1])

    x0, t0 = pose((0.0, 0.0), (0.0, 0.0))
    _, t_off = pose((offset_mm, 0.0), (0.0, 0.0))
    x_t, t_t = pose((0.0, 0.0), (ratio, 0.0))
    h = 1e-3 * float(force_N)
    unit = (1.0, 0.0)  # slides_mm at ratio 1: the path integral U(F) itself
    lateral = float((stack.slides_mm(F + h, unit) - stack.slides_mm(F, unit))[0, :, 0].sum()) / h
    tangential_N = ratio * float(force_N)
    per_moment, slide, per_tangential = (
        (t_off - t0) / (float(force_N) * offset_mm),
        (x_t - x0) / tangential_N + lateral,
        (t_t - t0) / tangential_N,
    )
    if stack.members_pose is None:
        return per_moment, slide, per_tangential
    # the members' pose follows the load's ray too: its tangent there is its regime's figures
    m = stack.members_pose.at(force_N)
    return (
        per_moment + m["turn_per_moment_rad_per_Nmm"],
        slide + m["slide_mm_per_N"],
        per_tangential + m["turn_per_tangential_rad_per_N"],
    )


def centred_response(stack: LoadedStack, force_N: float) -> tuple[float, float, float]:
    """The centred press's tangent at ``force_N``: the magnet's drop (mm/N, down > 0), its
    motion along +x (mm/N) and its turn about +y (rad/N, right-handed) per newton, by a forward
    difference of 1e-3 x the force (the model is piecewise linear between its knots)."""
    F = float(force_N) * np.array([1.0, 1.0 + 1e-3])
    d, tilt, _ = load_path(stack, F, (0.0, 0.0))
    shift, rotvec = stack.pose(F, d, tilt, None, 0.0, 0.0)
    h = F[1] - F[0]
    return -(shift[1, 2] - shift[0, 2]) / h, (shift[1, 0] - shift[0, 0]) / h, (rotvec[1, 1] - rotvec[0, 1]) / h


def layer_states(
    stack: LoadedStack, theta: np.ndarray, start: np.ndarray | None = None, unsolved_nan: bool = False
) -> np.ndarray:
    """(m, n, 3) every layer's (d mm, phi_y rad, phi_x rad) under the loads ``theta`` (m, 5) =
    (Fz, Fx, Fy, x, y), each load's tilt rung solved on its own from ``start`` (m, n, 3) when given
    (a close load's states), else from the centred answer. A load whose equilibrium is not found
    raises TiltError, or gets NaN states with ``unsolved_nan``."""
    F, rx, ry = load_ratios(theta)
    out = np.zeros((len(theta), len(stack.tilt), 3))
    for i in range(len(theta)):
        offsets = stack.layer_offsets_mm(theta[i, 3:5], (rx[i], ry[i]))
        try:
            d, tilt = stack_path(stack.tilt, F[i : i + 1], offsets, None if start is None else start[i])
        except TiltError:
            if not unsolved_nan:
                raise
            out[i] = np.nan
            continue
        out[i] = np.column_stack([d[0], tilt[0]])
    return out


def fields_of(
    stack: LoadedStack, theta: np.ndarray, states: np.ndarray, chips_mm: Sequence[tuple[float, float]] | None = None
) -> np.ndarray:
    """(m, 3 k) the fields in T at the chips ``chips_mm`` (the geometry's one chip unless given)
    under the loads ``theta`` (m, 5) with the layers in ``states`` (m, n, 3): the slides, the
    magnet's pose and its exact field, every chip in one call of the field (its cost is mostly
    per call)."""
    return _chips_field_T(stack.geometry, *magnet_pose_of(stack, theta, states), chips_mm)


def magnet_pose_of(stack: LoadedStack, theta: np.ndarray, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the magnet centre's displacement (m, 3) mm, its rotation vector (m, 3)) under the loads
    ``theta`` (m, 5) with the layers in ``states`` (m, n, 3): their compressions and tilts, and
    the slides the loads give."""
    F, rx, ry = load_ratios(theta)
    return stack.pose(F, states[..., 0], states[..., 1:], stack.slides_mm(F, (rx, ry)), rx, theta[:, 3])


def _chips_field_T(
    geometry: SensorGeometry, shift: np.ndarray, rotvec: np.ndarray, chips_mm: Sequence[tuple[float, float]] | None
) -> np.ndarray:
    """(m, 3 k) the field of the magnet in the poses (m, 3), (m, 3) at every chip, one call."""
    chips = np.array([geometry.chip_offset_mm] if chips_mm is None else chips_mm, dtype=float)
    k, m = len(chips), len(shift)
    if not m:  # no load (the field takes at least one observer)
        return np.zeros((0, 3 * k))
    B = magnet_field_T(geometry, np.tile(shift, (k, 1)), np.tile(rotvec, (k, 1)), np.repeat(chips, m, axis=0))
    return B.reshape(k, m, 3).transpose(1, 0, 2).reshape(m, 3 * k)


def path_fields_T(
    stack: LoadedStack,
    force_N: np.ndarray,
    offset_mm,
    ratio=(0.0, 0.0),
    chips_mm: Sequence[tuple[float, float]] | None = None,
) -> np.ndarray:
    """(m, 3 k) the forward model's fields along the normal forces ``force_N`` (m,) ascending,
    pressed at ``offset_mm`` with the tangential force ``ratio`` x the normal one, each solve
    started from the previous force's (:func:`load_path`): what a table holds at its nodes."""
    d, tilt, slide = load_path(stack, force_N, offset_mm, ratio)
    F = np.asarray(force_N, dtype=float)
    return _chips_field_T(stack.geometry, *stack.pose(F, d, tilt, slide, ratio[0], offset_mm[0]), chips_mm)


def pose_field_T(
    geometry: SensorGeometry,
    layers: list[LayerTiltLaw],
    force_N: np.ndarray,
    offset_mm: tuple[float, float],
    members: MemberPose | None = None,
) -> np.ndarray:
    """The field at the chip (m, 3) in T for normal forces ``force_N`` (m,) ascending, pressed at
    ``offset_mm``, the layers' tilt laws ``layers`` given: :func:`path_fields_T` on their
    :func:`normal_stack` (the stack's tilts, the members' pose in section mode, the magnet's
    pose, the exact field)."""
    stack = normal_stack(geometry, list(layers), "given", members)
    return path_fields_T(stack, np.asarray(force_N, dtype=float), offset_mm)


def fields_T(
    stack: LoadedStack,
    theta,
    chips_mm: Sequence[tuple[float, float]] | None = None,
    start: np.ndarray | None = None,
    unsolved_nan: bool = False,
) -> np.ndarray:
    """The forward model: (m, 3 k) the fields in T at the chips ``chips_mm`` (the geometry's one
    chip unless given) under the loads ``theta`` (m, 5) = (Fz N, Fx N, Fy N, x mm, y mm), Fz >= 0
    (one load (5,) is a batch of one), each layer's equilibrium solved exactly (from ``start``,
    :func:`layer_states`). A load whose equilibrium is not found raises TiltError, or gives a
    row of NaN with ``unsolved_nan``."""
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    states = layer_states(stack, theta, start, unsolved_nan)
    if not unsolved_nan:
        return fields_of(stack, theta, states, chips_mm)
    solved = np.all(np.isfinite(states), axis=(1, 2))
    out = np.full((len(theta), 3 * (1 if chips_mm is None else len(chips_mm))), np.nan)
    out[solved] = fields_of(stack, theta[solved], states[solved], chips_mm)
    return out


FORCE_STEP_REL = 1e-4  # finite-difference steps: of the normal force (floored at FORCE_STEP_MIN_N)
FORCE_STEP_MIN_N = 1e-3
POSITION_STEP_MM = 1e-3


def fd_steps(theta: np.ndarray) -> np.ndarray:
    """(m, 5) the finite-difference step of every unknown of the loads ``theta`` (m, 5) (N for
    forces, mm for positions)."""
    h_F = np.maximum(FORCE_STEP_REL * np.abs(theta[:, 0]), FORCE_STEP_MIN_N)
    h_p = np.full(len(theta), POSITION_STEP_MM)
    return np.column_stack([h_F, h_F, h_F, h_p, h_p])


def stepped_loads(theta: np.ndarray, free: Sequence[int], sign: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(the loads (q, m, 5), each free unknown's own moved by ``sign`` x its step, the steps
    (m, q)) of the loads ``theta`` (m, 5): the differences of a Jacobian's q columns."""
    h = fd_steps(theta)[:, list(free)]
    shifted = np.repeat(theta[None, :, :], len(free), axis=0)
    for c, i in enumerate(free):
        shifted[c, :, i] += sign * h[:, c]
    return shifted, h


def field_jacobian_T(
    stack: LoadedStack,
    theta,
    chips_mm: Sequence[tuple[float, float]] | None = None,
    free: Sequence[int] = (0, 1, 2, 3, 4),
    at: np.ndarray | None = None,
) -> np.ndarray:
    """The forward model's Jacobian: (m, 3 k, len(free)) dB/dtheta in T per N or per mm at the
    loads ``theta`` (m, 5), by differences of :func:`fields_T`: central, or forward from ``at``
    (m, 3 k), the fields there already known; all the moved loads in one batch."""
    theta = np.atleast_2d(np.asarray(theta, dtype=float))
    m, q, K = len(theta), len(free), 3 * (1 if chips_mm is None else len(chips_mm))
    up, h = stepped_loads(theta, free)
    B_up = fields_T(stack, up.reshape(q * m, 5), chips_mm).reshape(q, m, K)
    if at is None:
        B_down = fields_T(stack, stepped_loads(theta, free, -1.0)[0].reshape(q * m, 5), chips_mm).reshape(q, m, K)
        return ((B_up - B_down) / (2 * h.T[:, :, None])).transpose(1, 2, 0)
    return ((B_up - np.atleast_2d(at)[None]) / h.T[:, :, None]).transpose(1, 2, 0)


def field_T(
    stack: LoadedStack,
    force_N: float,
    shear_N: tuple[float, float],
    offset_mm: tuple[float, float],
    chips_mm: Sequence[tuple[float, float]] | None = None,
) -> np.ndarray:
    """The field (k, 3) in T at each of the chips ``chips_mm`` (the geometry's one chip unless
    given) under the normal force ``force_N`` (> 0) and tangential ``shear_N`` = (Fx, Fy)
    pressed at ``offset_mm``: :func:`fields_T` of one load. Raises TiltError when a layer's
    equilibrium is not found."""
    theta = [force_N, shear_N[0], shear_N[1], offset_mm[0], offset_mm[1]]
    return fields_T(stack, theta, chips_mm).reshape(-1, 3)
