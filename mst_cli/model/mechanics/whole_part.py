"""The whole-part rung: the section of the part as exported, in plane strain, pressed over a
centred strip (docs/design.md section 4.7).

Rungs L0-L2 model the layers between rigid plates; :mod:`mst_cli.model.load_path` adds the
cap, plates and cover as beams in closed form. This rung models them all at once: the section at
mid-depth (:mod:`~mst_cli.model.mechanics.whole_part_mesh`, from the one geometry the CAD
extrudes), P2 triangles, linear small-strain plane-strain elasticity (scikit-fem), each region
its own material (TPU; the magnet N42-stiff or the pocket left empty; an insert in its own), the
base's bottom face held, a uniform pressure over the centred strip ``patch_mm`` wide on the top
face (the force per mm of depth 1/D, so every figure is per newton on the part D deep).

Per regime the layers locked before it are taken as closed (their cavity filled), as the
issue's independent model does; the contacts that bending closes elsewhere are not modelled
(a linear solve: an upper bound on the compliance where a gap would close). The magnet's
motion is the rigid-body least-squares fit of the displacement at the magnet's (or the empty
pocket's floor's) nodes: drop, side motion and turn; the field change per newton at the chip is
the drop times dB_z/dz on the axis at the unloaded gap (:mod:`mst_cli.model.magnet_field`).
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from mst_cli.model.load_path import (
    FINGERTIP_PATCH_MM,
    Insert,
    Members,
    capped_units,
    member_band_compliances,
    members,
)
from mst_cli.model.magnet_field import axial_dBz_dz_T_per_mm
from mst_cli.model.mechanics import rung_keep
from mst_cli.model.mechanics.whole_part_mesh import TAGS, Region, mesh_section, rect, section_regions
from mst_cli.model.stack import Stack
from mst_cli.parallel import fork_map

if TYPE_CHECKING:
    from skfem import MeshTri

N42_MODULUS_MPA = 160e3  # sintered NdFeB, Young's modulus ~160 GPa (Arnold Magnetic Technologies datasheet)
N42_POISSON = 0.24
RIGID_FACTOR = 1e4  # the rigid-member control: cap, plates and base this much stiffer than TPU
# lattice spacing of the production mesh (benchmarks/bench_whole_part.py): 0.3 mm, or half the
# thinnest wall when that is finer (two P2 triangles across a wall)
DEFAULT_SPACING_MM = 0.3
DEFAULT_LEVELS = 3  # rounds of refinement at the layers' corners
MEMBER_TAGS = ("base", "plate", "cap")
# how the magnet sits: "resting" loose in its pocket as printed (0.1 mm clearance: it rides on
# the pocket's floor and stiffens nothing; its motion the floor's under it), "bonded" glued in,
# an N42 block filling the pocket (its motion its own)
MAGNET_SEATS = ("resting", "bonded")


@dataclass(frozen=True)
class PartOptions:
    """How the section is built and pressed: the strip's width (mm), the mesh spacing (mm), its
    offset and direction (down, or along +x), the corner refinements, the magnet
    (:data:`MAGNET_SEATS`), the members' stiffness factor (1: as printed; :data:`RIGID_FACTOR`:
    the rigid-member control) and which members it scales (``scaled``, tags of :data:`MEMBER_TAGS`
    or "insert"), the locked layers by index, the plates held rigid whatever ``scaled`` says
    (``rigid_plates``, by index: one plate's share alone), an insert
    (:class:`~mst_cli.model.load_path.Insert`; None: the geometry's own, if it has one)."""

    patch_mm: float = FINGERTIP_PATCH_MM
    spacing_mm: float | None = None  # None: :func:`default_spacing_mm`
    offset_mm: float = 0.0  # the strip's centre on the top face (x, mm): an off-centre press
    tangential: bool = False  # the strip pulls along +x instead of pressing down
    magnet: str = "resting"
    member_factor: float = 1.0
    scaled: tuple[str, ...] = MEMBER_TAGS  # the members member_factor applies to (one at a time: attribution)
    locked: tuple[int, ...] = ()
    rigid_plates: tuple[int, ...] = ()  # plates (bottom first) held rigid whatever ``scaled`` says
    insert: Insert | None = None
    levels: int = DEFAULT_LEVELS
    # one part of the base held rigid whatever ``scaled`` says (the attribution's): "cover" (the
    # base above the slot's roof) or "slot_walls" (below it: the slot's side walls and floor); "": none
    rigid_base: str = ""


@dataclass(frozen=True)
class MagnetMotion:
    """The magnet's rigid motion per newton of press: drop (mm/N, > 0 down), side (mm/N, +x),
    turn (rad/N, about +y); the problem's size and its solve time."""

    drop_mm_per_N: float
    side_mm_per_N: float
    turn_rad_per_N: float
    dofs: int
    seconds: float
    extra: dict = field(default_factory=dict)


MOTION_NUMBERS = ("drop_mm_per_N", "side_mm_per_N", "turn_rad_per_N", "dofs", "seconds")


def _motion_numbers(motion: MagnetMotion) -> dict:
    return {f: getattr(motion, f) for f in MOTION_NUMBERS}


def part_insert(geometry, options: PartOptions) -> Insert | None:
    """The insert pressed with: the options' own, else the geometry's (``geometry.insert``, the
    one source of its size and place, once the spec declares it), else None."""
    return options.insert if options.insert is not None else getattr(geometry, "insert", None)


def _moduli(material, options: PartOptions, insert) -> tuple[np.ndarray, np.ndarray]:
    """(E, nu) per tag (:data:`TAGS`)."""
    E = {t: material.youngs_modulus_MPa for t in TAGS}
    nu = {t: material.poisson_ratio for t in TAGS}
    for t in options.scaled:
        E[t] *= options.member_factor
    E["rigid_plate"] = material.youngs_modulus_MPa * RIGID_FACTOR
    E["magnet"], nu["magnet"] = N42_MODULUS_MPA, N42_POISSON
    if insert is not None:
        # load_path.Insert keeps its modulus in plane strain; back to E for the plane-strain form
        E["insert"] = insert.modulus_MPa * (1.0 - insert.poisson_ratio**2)
        nu["insert"] = insert.poisson_ratio
    return np.array([E[t] for t in TAGS]), np.array([nu[t] for t in TAGS])


def press_points(geometry, patch_mm: float, offset_mm: float = 0.0) -> np.ndarray:
    """The press's edges on the top face, so that the mesh has nodes there."""
    c = min(patch_mm, geometry.width_mm)
    x = np.clip([offset_mm - 0.5 * c, offset_mm + 0.5 * c], -0.5 * geometry.width_mm, 0.5 * geometry.width_mm)
    return np.array([[x[0], geometry.total_height_mm], [x[1], geometry.total_height_mm]])


def default_spacing_mm(geometry) -> float:
    """The production mesh's lattice spacing: :data:`DEFAULT_SPACING_MM` or half the thinnest wall."""
    return min(DEFAULT_SPACING_MM, 0.5 * min(c.t_mm for c in geometry.layers))


def build_mesh(geometry, options: PartOptions, offsets_mm: Sequence[float] | None = None) -> tuple[MeshTri, np.ndarray]:
    """The section's MeshTri and each triangle's tag index: the lattice mesh with nodes at the
    edges of the strip pressed at each of ``offsets_mm`` (``options.offset_mm`` alone unless
    given), then ``options.levels`` rounds of refinement within t / 2^i of each layer's corners
    (the cavity's tips and the walls' roots, where the strain is singular, as in L2's own mesh)."""
    from skfem import MeshTri as _MeshTri  # deferred: scikit-fem loads when this rung is asked for

    if options.magnet not in MAGNET_SEATS:
        raise ValueError(f"magnet must be one of {MAGNET_SEATS}, not {options.magnet!r}")
    regions = section_regions(
        geometry, options.locked, options.magnet == "bonded", part_insert(geometry, options),
        rigid_plates=options.rigid_plates,
    )  # fmt: skip
    spacing = options.spacing_mm if options.spacing_mm is not None else default_spacing_mm(geometry)
    offsets = (options.offset_mm,) if offsets_mm is None else offsets_mm
    edges = np.concatenate([press_points(geometry, options.patch_mm, x) for x in offsets])
    p, t, _ = mesh_section(regions, spacing, edges)
    mesh = _MeshTri(p, t)
    corners = np.concatenate([np.array(e) for r in regions if r.tag == "layer" for e in r.edges()])
    radius = 0.5 * min(c.t_mm for c in geometry.layers)
    for i in range(options.levels):
        mid = mesh.p[:, mesh.t].mean(axis=1)
        d2 = ((mid.T[:, None, :] - corners[None, :, :]) ** 2).sum(-1).min(axis=1)
        marked = np.flatnonzero(d2 < (radius * 0.5**i) ** 2)
        if marked.size:
            mesh = mesh.refined(marked)
    mid = mesh.p[:, mesh.t].mean(axis=1).T
    tag = np.full(mesh.t.shape[1], -1)
    for r in regions[::-1]:
        tag[r.contains(mid)] = TAGS.index(r.tag)
    if options.rigid_base:
        # by the triangle's centroid: over the slot its roof is a region edge, beyond it a zigzag
        # one lattice spacing deep (a study's split, not the production mesh)
        above = mid[:, 1] >= geometry.z_cover_bottom_mm
        part = {"cover": above, "slot_walls": ~above}[options.rigid_base]
        tag[(tag == TAGS.index("base")) & part] = TAGS.index("rigid_plate")
    return mesh, tag


def _stiffness(basis, tag: np.ndarray, E: np.ndarray, nu: np.ndarray):
    """Plane-strain linear elasticity with a modulus per triangle."""
    # deferred: scikit-fem loads when this rung is asked for
    from skfem import BilinearForm, asm
    from skfem.helpers import ddot, sym_grad, trace

    lam_e = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    mu_e = E / (2.0 * (1.0 + nu))
    lam, mu = lam_e[tag][:, None], mu_e[tag][:, None]  # (elements, 1): constant over each

    @BilinearForm
    def elasticity(u, v, w):
        eu, ev = sym_grad(u), sym_grad(v)
        return 2.0 * mu * ddot(eu, ev) + lam * trace(eu) * trace(ev)

    return asm(elasticity, basis)


def _load(geometry, basis_mesh, element, patch_mm: float, offset_mm: float = 0.0, tangential: bool = False):
    """The strip's traction: 1/D N per mm of depth over |x - offset| <= c/2 of the top face,
    pressing down (or, ``tangential``, along +x)."""
    # deferred: scikit-fem loads when this rung is asked for
    from skfem import FacetBasis, LinearForm, asm

    H, c = geometry.total_height_mm, min(patch_mm, geometry.width_mm)
    tol = 1e-7
    facets = basis_mesh.facets_satisfying(
        lambda x: (np.abs(x[1] - H) < tol) & (np.abs(x[0] - offset_mm) <= 0.5 * c + tol), boundaries_only=True
    )
    fb = FacetBasis(basis_mesh, element, facets=facets)
    q = 1.0 / (c * geometry.depth_mm)  # N/mm^2 on the strip, per mm of depth: F = 1 N on D
    component = 0 if tangential else 1
    sign = 1.0 if tangential else -1.0

    @LinearForm
    def traction(v, w):
        return sign * q * v[component]

    return asm(traction, fb)


def rigid_fit(xz: np.ndarray, u: np.ndarray, about_xz=None) -> tuple[float, float, float]:
    """(U_x, U_z, theta) of the least-squares rigid motion u ~ U + theta e_y x (x - c) of points
    ``xz`` (n, 2) moved by ``u`` (n, 2); theta about +y in the (x, z) plane: u_x = -theta dz,
    u_z = theta dx (counter-clockwise in x-z seen from -y positive). U is the motion of the
    points' centroid c, or of the point ``about_xz`` when given (the same rigid motion)."""
    c = xz.mean(axis=0)
    d = xz - c
    U = u.mean(axis=0)
    du = u - U
    theta = float((d[:, 0] * du[:, 1] - d[:, 1] * du[:, 0]).sum() / (d**2).sum())
    if about_xz is not None:
        dx, dz = np.asarray(about_xz, dtype=float) - c
        U = U + np.array([-theta * dz, theta * dx])
    return float(U[0]), float(U[1]), theta


def press(geometry, material, options: PartOptions = PartOptions()) -> MagnetMotion:
    """The magnet's rigid motion per newton under the centred strip (module docstring)."""
    # deferred: scikit-fem loads when this rung is asked for
    from skfem import condense, solve

    t0 = time.perf_counter()
    mesh, tag, element, basis, K, held = _system(geometry, material, options)
    f = _load(geometry, mesh, element, options.patch_mm, options.offset_mm, options.tangential)
    return _motion(geometry, basis, tag, solve(*condense(K, f, D=held)), options, t0)


def kept_press(geometry, material, options: PartOptions) -> MagnetMotion:
    """:func:`press`, its result kept in the rung's store (:mod:`rung_keep`) and read back from it
    when it is there and every number finite (anything else is solved again)."""
    key = (repr(geometry), repr(material), options)
    kept = rung_keep.stored("press", key)
    with contextlib.suppress(KeyError, TypeError, ValueError):
        drop, side, turn, dofs, seconds = (float(kept[k]) for k in MOTION_NUMBERS)  # type: ignore[index]
        if all(math.isfinite(v) for v in (drop, side, turn, dofs, seconds)):
            return MagnetMotion(drop, side, turn, int(dofs), seconds)
    motion = press(geometry, material, options)
    rung_keep.store("press", key, _motion_numbers(motion))
    return motion


def _system(geometry, material, options: PartOptions, offsets_mm: Sequence[float] | None = None):
    """(mesh, tags, element, basis, stiffness, held dofs) of the section as ``options`` builds it,
    its mesh with nodes at the edges of the strips at ``offsets_mm`` (:func:`build_mesh`)."""
    # deferred: scikit-fem loads when this rung is asked for
    from skfem import Basis, ElementTriP2, ElementVector

    mesh, tag = build_mesh(geometry, options, offsets_mm)
    element = ElementVector(ElementTriP2())
    basis = Basis(mesh, element)
    E, nu = _moduli(material, options, part_insert(geometry, options))
    held = basis.get_dofs(lambda x: np.abs(x[1]) < 1e-7).all()  # the base's bottom face
    return mesh, tag, element, basis, _stiffness(basis, tag, E, nu), held


def _motion(geometry, basis, tag: np.ndarray, u: np.ndarray, options: PartOptions, t0: float) -> MagnetMotion:
    """The magnet's rigid motion in the displacement ``u``: the least-squares fit of its nodes' (or
    of the floor's it rests on), the translation its centre's. The resting magnet's points lie on
    its pocket's floor, half its thickness below its centre: a turn moves the centre that much
    further along x than the floor (before 2026-12-02 the slide was the floor's)."""
    xz, uv = _magnet_points(geometry, basis, tag, u, options.magnet == "bonded")
    centre = (0.0, geometry.z_magnet_bottom_mm + 0.5 * geometry.magnet.thickness_mm)
    Ux, Uz, th = rigid_fit(xz, uv, centre)
    return MagnetMotion(-Uz, Ux, th, basis.N, time.perf_counter() - t0, {"elements": basis.mesh.t.shape[1]})


OFF_CENTRE_MM = 3.0  # where press_general's off-centre strip is centred (a new user's offset)


@dataclass(frozen=True)
class GeneralMotion:
    """The magnet's rigid motion per newton under the three loads of the plane: the centred
    press (down), a tangential pull along +x on the same strip, and the strip pressed
    ``arm_mm`` off centre (toward +x); ``arm_mm`` the assembled press's own lever (the strip as
    the mesh resolves it)."""

    press: MagnetMotion
    pull: MagnetMotion
    off_centre: MagnetMotion
    arm_mm: float

    def as_dict(self) -> dict:
        """Plain numbers (a :class:`RungStore`'s value)."""
        return {
            "arm_mm": self.arm_mm,
            **{k: _motion_numbers(getattr(self, k)) for k in ("press", "pull", "off_centre")},
        }

    @classmethod
    def from_dict(cls, d: dict) -> GeneralMotion:
        """The motion :meth:`as_dict` wrote."""
        motions = {}
        for k in ("press", "pull", "off_centre"):
            drop, side, turn, dofs, seconds = (float(d[k][f]) for f in MOTION_NUMBERS)
            if not np.all(np.isfinite([drop, side, turn, dofs, seconds])):
                raise ValueError("a motion that is not a number")
            motions[k] = MagnetMotion(drop, side, turn, int(dofs), seconds)
        return cls(**motions, arm_mm=float(d["arm_mm"]))

    @property
    def turn_per_moment_rad_per_Nmm(self) -> float:
        """The off-centre press's turn per N mm of its moment, less the centred press's own turn
        (the section is not symmetric: the slot opens on one side)."""
        return (self.off_centre.turn_rad_per_N - self.press.turn_rad_per_N) / self.arm_mm


def press_general(
    geometry, material, options: PartOptions = PartOptions(), offset_mm: float = OFF_CENTRE_MM
) -> GeneralMotion:
    """The section pressed, pulled and pressed ``offset_mm`` off centre, on the centred press's
    mesh with one factorised stiffness for the three (``options.offset_mm`` and ``tangential``
    unused). Each load is scaled by its own assembled resultant (x is in the P2 space, so the
    load vector's sums are the traction's integrals): per newton exactly, the off-centre press's
    lever its own, whatever the mesh makes of the strip's edges."""
    # deferred: scikit-fem and scipy load when this rung is asked for
    from scipy.sparse.linalg import splu
    from skfem import condense

    t0 = time.perf_counter()
    opts = replace(options, offset_mm=0.0, tangential=False)
    mesh, tag, element, basis, K, held = _system(geometry, material, opts, (0.0, offset_mm))
    loads = (
        _load(geometry, mesh, element, opts.patch_mm),
        _load(geometry, mesh, element, opts.patch_mm, tangential=True),
        _load(geometry, mesh, element, opts.patch_mm, offset_mm),
    )
    is_z = np.zeros(basis.N, dtype=bool)
    is_z[basis.nodal_dofs[1]] = True
    is_z[basis.facet_dofs[1]] = True
    x_of = basis.doflocs[0]
    D = geometry.depth_mm  # the traction is per mm of depth
    units = (-D * loads[0][is_z].sum(), D * loads[1][~is_z].sum(), -D * loads[2][is_z].sum())
    arm = float(-D * (loads[2][is_z] * x_of[is_z]).sum() / units[2])
    A, _, _, free = condense(K, loads[0], D=held)
    lu = splu(A.tocsc())
    motions = []
    for f, unit in zip(loads, units):
        u = np.zeros(basis.N)
        u[free] = lu.solve(np.asarray(f[free], dtype=float) / unit)
        motions.append(_motion(geometry, basis, tag, u, opts, t0))
    return GeneralMotion(motions[0], motions[1], motions[2], arm)


def _magnet_points(geometry, basis, tag: np.ndarray, u: np.ndarray, magnet: bool):
    """(positions (n, 2), displacements (n, 2)) of the magnet's nodes, or of the empty pocket's
    floor's under the magnet (where it rests; a rigid magnet on a floor that sags rides on its
    edges, a few per cent of the floor's own bending from this fit)."""
    ux, uz = u[basis.nodal_dofs[0]], u[basis.nodal_dofs[1]]
    p = basis.mesh.p
    if magnet:
        nodes = np.unique(basis.mesh.t[:, tag == TAGS.index("magnet")])
    else:
        r, z0 = geometry.magnet.radius_mm, geometry.z_magnet_bottom_mm
        nodes = np.flatnonzero((np.abs(p[1] - z0) < 1e-7) & (np.abs(p[0]) <= r + 1e-7))
    return p[:, nodes].T, np.stack([ux[nodes], uz[nodes]], axis=1)


def field_per_drop_uT_per_mm(geometry) -> float:
    """|dB_z/dz| on the magnet's axis at the unloaded gap, uT per mm of drop."""
    m = geometry.magnet
    return 1e6 * abs(float(axial_dBz_dz_T_per_mm(geometry.gap0_mm, m.radius_mm, m.thickness_mm, m.remanence_T)))


GENERAL_MEMO_SIZE = 24  # press_general solves this process keeps (:func:`general_motions`)
_GENERAL_MEMO: dict = {}


def general_motions(geometry, material, options: Sequence[PartOptions]) -> list[GeneralMotion]:
    """:func:`press_general` for each of ``options``, the missing ones side by side
    (:func:`mst_cli.parallel.fork_map`), memoised in this process: ``model.load_path: section``'s
    members' pose and ``mst check --whole-part``'s shear report ask for the same solves."""
    keys = [(repr(geometry), repr(material), o) for o in options]
    for key in dict.fromkeys(k for k in keys if k not in _GENERAL_MEMO):
        kept = rung_keep.stored("general", key)
        with contextlib.suppress(KeyError, TypeError, ValueError):  # none kept, or not what was written
            _GENERAL_MEMO[key] = GeneralMotion.from_dict(kept)  # type: ignore[arg-type]
    todo = list(dict.fromkeys(k for k in keys if k not in _GENERAL_MEMO))

    def solve(key: tuple) -> GeneralMotion:
        return press_general(geometry, material, key[2])

    rung_keep.solving(len(todo), "the part's section under its three loads (the general load)")
    for key, motion in zip(todo, fork_map(solve, todo) or [solve(k) for k in todo]):
        _GENERAL_MEMO[key] = motion
        rung_keep.store("general", key, motion.as_dict())
    out = [_GENERAL_MEMO[k] for k in keys]
    while len(_GENERAL_MEMO) > GENERAL_MEMO_SIZE:
        _GENERAL_MEMO.pop(next(iter(_GENERAL_MEMO)))
    return out


def regime_locked(stack) -> list[tuple[int, ...]]:
    """Per regime, the layers locked before it (the stack's lock order)."""
    order = [int(i) for i in stack.lock_order]
    return [tuple(sorted(order[:r])) for r in range(len(order))]


def regime_responses(geometry, material, stack, options: PartOptions = PartOptions()) -> list[dict]:
    """Per regime: the magnet's motion and the field change per newton at the chip (uT/N)."""
    per_mm = field_per_drop_uT_per_mm(geometry)
    out = []
    for r, locked in enumerate(regime_locked(stack)):
        mo = press(geometry, material, PartOptions(**{**options.__dict__, "locked": locked}))
        out.append({"regime": r + 1, "locked": locked, "motion": mo, "field_uT_per_N": per_mm * mo.drop_mm_per_N})
    return out


def beam_on_two_supports_mm_per_N(
    length_mm: float, thickness_mm: float, span_mm: float, depth_mm: float, material, patch_mm: float, spacing_mm: float
) -> float:
    """The check of the beam closed form (load_path's cap): a TPU rectangle ``length_mm`` x
    ``thickness_mm`` in plane strain on two line supports ``span_mm`` apart on its underside
    (held in z, one also in x), pressed by the centred strip; the deflection per newton (on
    ``depth_mm``) of its centre line at mid-span."""
    # deferred: scikit-fem loads when this rung is asked for
    from skfem import Basis, ElementTriP2, ElementVector, condense, solve
    from skfem import MeshTri as _MeshTri

    w2, s2 = 0.5 * length_mm, 0.5 * span_mm
    region = Region("cap", rect(-w2, w2, 0.0, thickness_mm))
    extra = np.array(
        [
            [-s2, 0.0],
            [s2, 0.0],
            [0.0, 0.5 * thickness_mm],
            [-0.5 * patch_mm, thickness_mm],
            [0.5 * patch_mm, thickness_mm],
        ]
    )
    p, t, tag = mesh_section([region], spacing_mm, extra)
    mesh = _MeshTri(p, t)
    element = ElementVector(ElementTriP2())
    basis = Basis(mesh, element)
    E = np.full(len(TAGS), material.youngs_modulus_MPa)
    K = _stiffness(basis, tag, E, np.full(len(TAGS), material.poisson_ratio))
    geometry_like = _Face(thickness_mm, length_mm, depth_mm)
    f = _load(geometry_like, mesh, element, patch_mm)
    at = lambda x, z: int(np.argmin((mesh.p[0] - x) ** 2 + (mesh.p[1] - z) ** 2))  # noqa: E731
    left, right, centre = at(-s2, 0.0), at(s2, 0.0), at(0.0, 0.5 * thickness_mm)
    held = np.array([basis.nodal_dofs[1][left], basis.nodal_dofs[1][right], basis.nodal_dofs[0][left]])
    u = solve(*condense(K, f, D=held))
    return -float(u[basis.nodal_dofs[1][centre]])


@dataclass(frozen=True)
class _Face:
    """What :func:`_load` reads of a geometry: the top face's height, width and depth."""

    total_height_mm: float
    width_mm: float
    depth_mm: float


OUTSIDE_MEMO_SIZE = 8  # sections whose rows this process keeps (:func:`outside_layers`)
_OUTSIDE_MEMO: dict = {}


def outside_layers(geometry, material, locked_sets, options: PartOptions = PartOptions()) -> list[dict]:
    """Per regime (``locked_sets``: the layers locked before each, closed): the magnet's drop per
    newton in the section as printed (``part_mm_per_N``) and with its members rigid
    (``rigid_mm_per_N``, the layers' own: the control that reproduces L2), and their difference,
    what the members outside the layers add (``outside_mm_per_N``), with the solves' dofs and
    seconds. The 2 x regimes solves run side by side (:func:`mst_cli.parallel.fork_map`)."""
    key = (repr(geometry), repr(material), tuple(tuple(int(j) for j in locked) for locked in locked_sets), options)
    if key in _OUTSIDE_MEMO:  # the same section again (design's last round, then its verification)
        return [dict(row) for row in _OUTSIDE_MEMO[key]]
    kept = rung_keep.stored("outside", key)
    if isinstance(kept, list) and _rows_fit(kept, locked_sets):
        _OUTSIDE_MEMO[key] = kept
        return [dict(row) for row in kept]
    jobs = [(tuple(locked), factor) for locked in locked_sets for factor in (1.0, RIGID_FACTOR)]

    def solve_one(job: tuple) -> MagnetMotion:
        locked, factor = job
        return press(geometry, material, PartOptions(**{**options.__dict__, "locked": locked, "member_factor": factor}))

    rung_keep.solving(len(jobs), "the part's section, each regime as printed and with its members rigid")
    motions = fork_map(solve_one, jobs) or [solve_one(job) for job in jobs]
    rows = []
    for i, locked in enumerate(locked_sets):
        part, rigid = motions[2 * i], motions[2 * i + 1]
        rows.append(
            {
                "regime": i + 1,
                "locked": [int(j) for j in locked],
                "part_mm_per_N": part.drop_mm_per_N,
                "rigid_mm_per_N": rigid.drop_mm_per_N,
                "outside_mm_per_N": part.drop_mm_per_N - rigid.drop_mm_per_N,
                "dofs": part.dofs,
                "seconds": part.seconds + rigid.seconds,
            }
        )
    _OUTSIDE_MEMO[key] = rows
    rung_keep.store("outside", key, rows)
    while len(_OUTSIDE_MEMO) > OUTSIDE_MEMO_SIZE:
        _OUTSIDE_MEMO.pop(next(iter(_OUTSIDE_MEMO)))
    return [dict(row) for row in rows]


def _rows_fit(rows: list, locked_sets) -> bool:
    """Whether ``rows`` (a store's) are :func:`outside_layers`'s rows of ``locked_sets``."""
    numbers = ("part_mm_per_N", "rigid_mm_per_N", "outside_mm_per_N", "dofs", "seconds")
    try:
        return len(rows) == len(locked_sets) and all(
            row["locked"] == [int(j) for j in locked] and all(np.isfinite(float(row[k])) for k in numbers)
            for row, locked in zip(rows, locked_sets)
        )
    except (KeyError, TypeError, ValueError):
        return False


def section_members(geometry, material, laws: tuple, patch_mm: float = FINGERTIP_PATCH_MM, options=None) -> tuple:
    """(the members' closed form (:func:`~mst_cli.model.load_path.members`) carrying, per regime of
    the part, the whole-part rung's correction (:func:`~mst_cli.model.load_path.section_correction`),
    the rung's rows (:func:`outside_layers`)): ``model.load_path: section``. ``laws``: the layers'
    (bottom to top), whose part's lock order sets the regimes."""
    parts = members(geometry, material, patch_mm)
    opts = PartOptions(patch_mm=patch_mm) if options is None else replace(options, patch_mm=patch_mm)
    part = Stack(tuple(capped_units(laws, parts)))  # the part's lock order (model.response.part_stack's)
    rows = outside_layers(geometry, material, regime_locked(part), opts)
    extra = section_correction(Stack(laws), parts, [r["outside_mm_per_N"] for r in rows])
    return replace(parts, regime_extra_mm_per_N=extra), rows


def section_correction(stack, parts: Members, outside_mm_per_N: Sequence[float]) -> tuple[float, ...]:
    """Per regime of the part (``stack``: its layers alone, ``parts``: the closed form), what the
    rung's compliance outside the layers, ``outside_mm_per_N`` (one per regime: the section as
    printed less the same section with its members rigid, the layers locked before the regime
    closed), adds to the closed form's members as the forward model moves them there
    (:func:`~mst_cli.model.load_path.member_band_compliances`): ``Members.regime_extra_mm_per_N``,
    an additive correction (output space mapping: at the design it was measured on, the part's
    compliance in each regime is then the layers' own plus the rung's outside them)."""
    _, _, moving = member_band_compliances(stack, replace(parts, regime_extra_mm_per_N=()))
    closed = np.sum([np.asarray(v, dtype=float) for v in moving.values()], axis=0)
    outside = np.asarray(outside_mm_per_N, dtype=float)
    if outside.shape != closed.shape:
        raise ValueError(f"{outside.size} regimes measured for a part of {closed.size}")
    return tuple(float(v) for v in outside - closed)
