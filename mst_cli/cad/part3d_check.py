"""The 3D linear check of the part as exported (issue 44; docs/design.md section 4.8).

It reads what a new user's independent model reads, and nothing of mst's own model of the
part: the STL ``mst export`` wrote and export.json. The print frame is undone
(export.json ``print.rotation`` / ``translation_mm``), so the contact face is the body's top
(sensor z = its largest) and the mount its bottom (z = 0). The body is meshed in tetrahedra
(:mod:`~mst_cli.model.mechanics.part3d_mesh`): TPU (export.json ``design.material``); the
insert's slot, a closed void, holds the declared plate (``parts[insert]``: its box and its
material) and the slot's clearance around it stays empty; the magnet's pocket is empty (the
magnet resting on its floor, as printed) or holds an N42 block (``bonded``, the magnet's own
declared material). The bottom face is held, a 6 mm strip centred on the top face is pressed
(:mod:`~mst_cli.model.mechanics.part3d`), and the magnet's motion per newton is the rigid fit of
the pocket floor's nodes under the magnet (resting) or of the magnet's own nodes (bonded). The
field change per newton at the chip (``board_slot.chip_xy_mm``, ``gap0_mm`` under the magnet)
moves the exact cylinder with that pose.

Regime 1 only: no layer is locked, and the linear solve leaves every gap open.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mst_cli.cad.checks import load_mesh, resolve_export
from mst_cli.cad.manifest import Manifest, load_manifest
from mst_cli.cad.measure import to_sensor_frame
from mst_cli.errors import InputError
from mst_cli.io.files import read_input
from mst_cli.model.mechanics import part3d
from mst_cli.model.mechanics.part3d_mesh import BODY, TetMesh, tetrahedralize

MAX_JSON_BYTES = 10_000_000  # export.json is a few kB; anything near this is not one
# TetGen's largest tetrahedron (mm^3) and radius-edge bound: the finest mesh that solved in minutes
# here (75-95 k P2 dofs); not converged on walls under 1 mm (docs/design.md 4.8)
DEFAULT_MAX_VOLUME_MM3 = 4.0
DEFAULT_RADIUS_EDGE = 2.0
MAGNET_SEATS = ("resting", "bonded")
POCKET, SLOT = 1, 2  # the regions seeded inside the magnet's pocket and the insert's slot


@dataclass(frozen=True)
class Check3DOptions:
    """The press (strip width, mm), the mesh (largest tetrahedron, mm^3; TetGen's radius-edge
    bound; element order 1 or 2) and how the magnet sits (:data:`MAGNET_SEATS`)."""

    patch_mm: float = 6.0
    max_volume_mm3: float = DEFAULT_MAX_VOLUME_MM3
    radius_edge_ratio: float = DEFAULT_RADIUS_EDGE
    order: int = 2
    magnet: str = "resting"


@dataclass(frozen=True)
class Elastic:
    """A declared material: Young's modulus (MPa) and Poisson's ratio."""

    name: str
    youngs_modulus_MPa: float
    poisson_ratio: float


@dataclass(frozen=True)
class ExportedScene:
    """The export as the check reads it, in the sensor frame (mm)."""

    name: str
    vertices_mm: np.ndarray
    faces: np.ndarray
    tpu: Elastic
    magnet_box_mm: tuple[np.ndarray, np.ndarray]
    magnet_material: Elastic
    insert_box_mm: tuple[np.ndarray, np.ndarray] | None
    insert_material: Elastic | None
    insert_volume_mm3: float | None
    chip_mm: np.ndarray
    diameter_mm: float
    thickness_mm: float
    remanence_T: float


@dataclass(frozen=True)
class Check3DResult:
    """The magnet's motion and the field change at the chip, per newton of the centred press."""

    name: str
    translation_mm_per_N: np.ndarray  # x y z (z < 0: the magnet drops)
    rotation_rad_per_N: np.ndarray  # rotation vector about the fitted nodes' centroid
    field_uT_per_N: np.ndarray  # dB/dF at the chip, x y z
    tets: int
    dofs: int
    mesh_seconds: float
    solve_seconds: float
    volumes_mm3: dict = field(default_factory=dict)  # meshed: body (TPU), insert; declared insert

    @property
    def drop_mm_per_N(self) -> float:
        return -float(self.translation_mm_per_N[2])


def _elastic(entry, where: str) -> Elastic:
    """A ``material`` entry of export.json, checked: E > 0 and finite, -1 < nu < 0.5."""
    if not isinstance(entry, dict):
        raise InputError(where, entry, "must be a mapping with youngs_modulus_MPa and poisson_ratio")
    E, nu = entry.get("youngs_modulus_MPa"), entry.get("poisson_ratio")
    if not isinstance(E, (int, float)) or not np.isfinite(E) or E <= 0:
        raise InputError(f"{where}.youngs_modulus_MPa", E, "must be a finite Young's modulus > 0 MPa")
    if not isinstance(nu, (int, float)) or not -1.0 < nu < 0.5:
        raise InputError(f"{where}.poisson_ratio", nu, "must be a Poisson's ratio between -1 and 0.5 (exclusive)")
    return Elastic(str(entry.get("name", "")), float(E), float(nu))


def _box(part) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(part.sensor_box_min_mm, dtype=float), np.asarray(part.sensor_box_max_mm, dtype=float)


def read_scene(path: str | Path) -> ExportedScene:
    """The export at ``path`` (the folder or its sensor.stl), validated: an InputError names the
    first field or file that is missing or wrong."""
    found = resolve_export(path)
    manifest: Manifest = load_manifest(found.manifest)  # type: ignore[assignment]
    assert found.stl is not None
    mesh = to_sensor_frame(load_mesh(found.stl), manifest)
    raw = json.loads(read_input(found.manifest, MAX_JSON_BYTES, field="PATH", what="export.json"))
    parts = {p.get("name"): (i, p) for i, p in enumerate(raw.get("parts", [])) if isinstance(p, dict)}
    if "magnet" not in parts or manifest.design is None:
        raise InputError(
            "export.json", str(found.manifest), "has no parts.magnet or design: rewrite it with 'mst export'"
        )
    magnet = next(p for p in manifest.parts if p.name == "magnet")
    insert = manifest.insert
    i_ins, ins_raw = parts.get("insert", (None, {}))
    doc = manifest.design
    lo, hi = _box(magnet)
    return ExportedScene(
        name=manifest.name,
        vertices_mm=mesh.vertices,
        faces=mesh.faces,
        tpu=_elastic(raw["design"].get("material"), "export.json.design.material"),
        magnet_box_mm=(lo, hi),
        magnet_material=_elastic(
            parts["magnet"][1].get("material"), f"export.json.parts[{parts['magnet'][0]}].material"
        ),
        insert_box_mm=_box(insert) if insert is not None else None,
        insert_material=_elastic(ins_raw.get("material"), f"export.json.parts[{i_ins}].material") if insert else None,
        insert_volume_mm3=float(ins_raw["volume_mm3"]) if insert is not None and "volume_mm3" in ins_raw else None,
        chip_mm=np.array([*manifest.slots[0].chip_xy_mm, lo[2] - manifest.gap0_mm]),
        diameter_mm=doc.magnet.diameter_mm,
        thickness_mm=doc.magnet.thickness_mm,
        remanence_T=doc.magnet.remanence_T,
    )


def _inside(points: np.ndarray, box: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    return np.all((points >= box[0]) & (points <= box[1]), axis=1)


def mesh_scene(scene: ExportedScene, options: Check3DOptions) -> tuple[TetMesh, np.ndarray, np.ndarray]:
    """(the kept tetrahedra, E per tetrahedron, nu per tetrahedron): the body in TPU, the
    plate's tetrahedra (centroid inside its declared box) in its material, the slot's clearance
    dropped, the pocket dropped (resting) or N42 (bonded)."""
    if options.magnet not in MAGNET_SEATS:
        raise ValueError(f"magnet must be one of {MAGNET_SEATS}, not {options.magnet!r}")
    seeds = [0.5 * (scene.magnet_box_mm[0] + scene.magnet_box_mm[1])]
    if scene.insert_box_mm is not None:
        seeds.append(0.5 * (scene.insert_box_mm[0] + scene.insert_box_mm[1]))
    mesh = tetrahedralize(scene.vertices_mm, scene.faces, seeds, options.max_volume_mm3, options.radius_edge_ratio)
    plate = (mesh.region == SLOT) & _inside(mesh.centroids_mm(), scene.insert_box_mm) if scene.insert_box_mm else None
    keep = (mesh.region == BODY) | ((mesh.region == POCKET) & (options.magnet == "bonded"))
    if plate is not None:
        keep |= plate
    mesh = mesh.kept(keep)
    E = np.full(len(mesh.tets), scene.tpu.youngs_modulus_MPa)
    nu = np.full(len(mesh.tets), scene.tpu.poisson_ratio)
    for region, material in ((POCKET, scene.magnet_material), (SLOT, scene.insert_material)):
        if material is not None:
            E[mesh.region == region], nu[mesh.region == region] = material.youngs_modulus_MPa, material.poisson_ratio
    return mesh, E, nu


def _magnet_nodes(scene: ExportedScene, mesh: TetMesh, options: Check3DOptions) -> np.ndarray:
    """The vertices whose rigid fit is the magnet's motion: the magnet's own (bonded) or the
    pocket floor's under the magnet's disc (resting)."""
    if options.magnet == "bonded":
        return np.unique(mesh.tets[mesh.region == POCKET])
    lo, hi = scene.magnet_box_mm
    centre = 0.5 * (lo + hi)
    p = mesh.points_mm
    on_floor = np.abs(p[:, 2] - lo[2]) < part3d.FACE_TOL_MM
    under = np.hypot(p[:, 0] - centre[0], p[:, 1] - centre[1]) <= 0.5 * scene.diameter_mm + part3d.FACE_TOL_MM
    nodes = np.flatnonzero(on_floor & under)
    if nodes.size < 3:
        raise ValueError(f"the pocket floor at z = {lo[2]} mm has {nodes.size} mesh nodes under the magnet; need 3")
    return nodes


def press_exported(path: str | Path, options: Check3DOptions = Check3DOptions()) -> Check3DResult:
    """The 3D check of the export at ``path`` (module docstring)."""
    scene = read_scene(path)
    t0 = time.perf_counter()
    mesh, E, nu = mesh_scene(scene, options)
    t_mesh = time.perf_counter() - t0
    z = mesh.points_mm[:, 2]
    solution = part3d.press(
        mesh.points_mm, mesh.tets, E, nu, held_z_mm=float(z.min()), top_z_mm=float(z.max()),
        width_mm=options.patch_mm, order=options.order,
    )  # fmt: skip
    nodes = _magnet_nodes(scene, mesh, options)
    motion = part3d.rigid_fit(mesh.points_mm[nodes], part3d.node_displacements(solution, nodes))
    lo, hi = scene.magnet_box_mm
    dB = part3d.field_change_uT_per_N(
        motion, 0.5 * (lo + hi), scene.chip_mm, scene.diameter_mm, scene.thickness_mm, scene.remanence_T
    )
    vol = mesh.volumes_mm3()
    volumes = {"body": float(vol[mesh.region == BODY].sum()), "insert": float(vol[mesh.region == SLOT].sum())}
    if scene.insert_volume_mm3 is not None:
        volumes["insert_declared"] = scene.insert_volume_mm3
    return Check3DResult(
        scene.name, motion.translation_mm_per_N, motion.rotation_rad_per_N, dB, len(mesh.tets), solution.dofs,
        t_mesh, solution.seconds, volumes,
    )  # fmt: skip
