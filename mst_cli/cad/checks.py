"""Geometry checks of an exported sensor body (what ``mst check`` runs).

Pure functions: a mesh and the ``export.json`` manifest in, a list of :class:`Check` out. The
manifest holds the design's own expected values (computed from the geometry object), so each
check compares a number *measured on the mesh* -- by ray casts, plane sections and face
normals -- with the design. The STL lies in print orientation; the manifest's ``print``
section gives the rotation back to the sensor frame, where the design's dimensions live.

* ``watertight``, ``is_volume`` (consistent winding, positive volume), ``manifold3d`` (the mesh
  is accepted as a manifold), ``one_body`` (one shell of positive volume plus the closed
  magnet pocket as the only internal void);
* ``volume`` and ``bbox`` against the analytic sum of the parts;
* ``wall_thickness``, ``web_depth``, ``cavity_gap`` against the nozzle and the minimum
  printable gap, measured in sections through each layer's walls and along rays through its
  cavity;
* ``magnet_pocket``, ``board_slot`` and ``magnet_chip_gap`` (the unloaded distance the forward
  model uses, rebuilt from the measured pocket floor and slot floor);
* print orientation: ``overhang`` (every down-facing face at least 45 deg from horizontal, so
  nothing needs support or a bridge), ``layer_grid`` (every horizontal face on a boundary of
  the print layers, so the slicer prints it where it was designed) and ``magnet_pause`` (the
  magnet goes in whole before the layer after the pause, which starts the pocket's roof).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from mst_cli.errors import InputError

# Planar features are exact in the B-rep; the STL stores float32 coordinates, which resolve
# ~2e-6 mm at 20 mm from the origin. Dimensions measured on planar faces must agree to this.
PLANAR_TOL_MM = 1e-4
OVERHANG_LIMIT_DEG = 45.0
# Mesh heights in print orientation are float32 values up to ~30 mm (~2e-6 mm steps) that went
# through one rotation: a face "on" a layer boundary lies within this of it.
LAYER_GRID_TOL_MM = 1e-4
# Rays are cast slightly off the symmetry lines so they never run exactly along an edge of the
# triangulation (rectangles are split on their diagonals, which cross the axis).
_RAY_OFFSET_MM = (0.0123, 0.0071)


@dataclass(frozen=True)
class Check:
    """One named check: passed, what was measured and what was expected (mm, deg)."""

    name: str
    passed: bool
    measured: str
    expected: str
    note: str = ""
    info: bool = False                    # report only: never fails
    values: dict = field(default_factory=dict)


# --------------------------------------------------------------------------- inputs
def resolve_paths(path: str | Path) -> tuple[Path, Path]:
    """(STL, export.json) for a folder written by ``mst export`` or an STL inside it."""
    path = Path(path)
    if not path.exists():
        raise InputError("PATH", str(path), "does not exist: give the folder 'mst export' wrote "
                                            "or the .stl in it")
    if path.is_dir():
        stl, manifest = path / "sensor.stl", path / "export.json"
    elif path.suffix.lower() == ".stl":
        stl, manifest = path, path.parent / "export.json"
    else:
        raise InputError("PATH", str(path), "must be a folder written by 'mst export' or an .stl in it")
    if not stl.is_file():
        raise InputError("PATH", str(stl), "no such STL file (run 'mst export --stl' first)")
    if not manifest.is_file():
        raise InputError("PATH", str(manifest), "export.json not found next to the STL: "
                                                "run 'mst export' to write it")
    return stl, manifest


# Sizes in export.json and coordinates in the STL: a sensor body is centimetres, so anything
# beyond a metre is no body mst wrote (and 1e37 would overflow the measurements).
MAX_COORD_MM = 1000.0
MAX_MANIFEST_BYTES = 10_000_000
MAX_STL_BYTES = 500_000_000

# What run_checks reads from export.json, with the type of each field: "num" a finite number
# within +-MAX_COORD_MM (bool is not a number), "pos" a size from MIN_SIZE_MM (a finer layer,
# tolerance or nozzle would overflow the layer counts) to MAX_COORD_MM, "vol" an area or volume
# from 0 to MAX_VOLUME, "int", "str", (kind, n) a list of n of kind, [spec] a list of up to
# MAX_LIST entries of spec (layers: at least one), {..} a mapping.
MAX_LIST = 64
MAX_VOLUME = 1e9
MIN_SIZE_MM = 1e-3
_LAYER = {"z_bottom_mm": "num", "h_mm": "pos", "t_mm": "pos", "theta_deg": "num",
          "web_depth_mm": "pos", "cavity_height_mm": "num"}
_WINDOW = {"x_inner_mm": "num", "x_outer_mm": "num", "floor_y_mm": "num"}
MANIFEST_FIELDS = {
    "stl_tolerance_mm": "pos",
    "gap0_mm": "num",
    "print": {"rotation": (("num", 3), 3), "translation_mm": ("num", 3), "layer_height_mm": "pos",
              "height_mm": "pos", "magnet_top_z_mm": "num", "pause": {"after_layer": "int", "z_mm": "num"}},
    "body": {"volume_mm3": "vol", "volume_tolerance_mm3": "vol", "bbox_min_mm": ("num", 3),
             "bbox_max_mm": ("num", 3), "bodies": "int", "internal_voids": "int"},
    "layers": [_LAYER],
    "magnet_pocket": {k: "vol" if k.endswith(("_mm2", "_mm3")) else "num"
                      for k in ("section_z_mm", "radius_mm", "section_area_mm2", "depth_mm",
                                "floor_z_mm", "curved_area_mm2", "volume_mm3", "roof_rise_mm")},
    "board_slot": {"board": "str", "chip_xy_mm": ("num", 2), "floor_z_mm": "num", "top_z_mm": "num",
                   "floor_y_mm": "num", "x0_mm": "num", "x1_mm": "num", "board_thickness_mm": "num",
                   "chip_height_mm": "num", "cable_windows": [_WINDOW]},
    "printer": {"nozzle_mm": "pos", "min_gap_mm": "pos"},
}
_KIND_TEXT = {"num": f"a finite number within +-{MAX_COORD_MM:g}",
              "pos": f"a size from {MIN_SIZE_MM:g} to {MAX_COORD_MM:g}",
              "vol": f"a number from 0 to {MAX_VOLUME:g}", "int": "an integer", "str": "a string"}


def _is_number(v) -> bool:
    # abs(v) <= limit is False for NaN and infinities, and exact for integers of any size
    return isinstance(v, (int, float)) and not isinstance(v, bool) and abs(v) <= MAX_COORD_MM


def _describe(spec) -> str:
    if isinstance(spec, str):
        return _KIND_TEXT[spec]
    if isinstance(spec, tuple):
        return f"a list of {spec[1]} entries, each {_describe(spec[0])}"
    if isinstance(spec, list):
        return f"a list of up to {MAX_LIST} mappings"
    return "a mapping with " + ", ".join(spec)


def validate_manifest(data, spec=None, path: str = "export.json") -> None:
    """InputError naming the first field of export.json that is missing or of the wrong type or
    nesting (``export.json.layers[2].t_mm``): everything :func:`run_checks` reads is checked here,
    so a KeyError or TypeError inside a check is a bug, not a malformed file."""
    spec = MANIFEST_FIELDS if spec is None else spec
    ok = True
    if isinstance(spec, str):
        ok = {"num": _is_number, "pos": lambda v: _is_number(v) and v >= MIN_SIZE_MM,
              "vol": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v <= MAX_VOLUME,
              "int": lambda v: isinstance(v, int) and not isinstance(v, bool) and abs(v) <= 10**9,
              "str": lambda v: isinstance(v, str)}[spec](data)
    elif isinstance(spec, tuple):
        ok = isinstance(data, list) and len(data) == spec[1]
        if ok:
            for i, item in enumerate(data):
                validate_manifest(item, spec[0], f"{path}[{i}]")
    elif isinstance(spec, list):
        ok = isinstance(data, list) and (1 if path.endswith(".layers") else 0) <= len(data) <= MAX_LIST
        if ok:
            for i, item in enumerate(data):
                validate_manifest(item, spec[0], f"{path}[{i}]")
    else:
        ok = isinstance(data, dict)
        if ok:
            for key, sub in spec.items():
                if key not in data:
                    raise InputError(f"{path}.{key}", None, "missing: rewrite it with 'mst export'")
                validate_manifest(data[key], sub, f"{path}.{key}")
    if not ok:
        shown = data if not isinstance(data, (dict, list)) else type(data).__name__
        raise InputError(path, shown, f"must be {_describe(spec)}: rewrite it with 'mst export'")


def load_manifest(path: Path) -> dict:
    """export.json, validated field by field (:func:`validate_manifest`)."""
    try:
        if Path(path).stat().st_size > MAX_MANIFEST_BYTES:
            raise InputError("export.json", str(path), f"is larger than {MAX_MANIFEST_BYTES} bytes: "
                                                       "rewrite it with 'mst export'")
        data = json.loads(Path(path).read_text(), parse_constant=_refuse_constant)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise InputError("export.json", str(path), f"cannot be read as JSON ({type(exc).__name__})") from None
    except ValueError as exc:                       # NaN / Infinity, which JSON does not have
        raise InputError("export.json", str(path), f"cannot be read as JSON ({exc})") from None
    validate_manifest(data)
    rotation = np.asarray(data["print"]["rotation"], dtype=float)
    if not (np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6) and np.linalg.det(rotation) > 0):
        raise InputError("export.json.print.rotation", data["print"]["rotation"],
                         "must be a rotation matrix (orthonormal, determinant +1): rewrite it with 'mst export'")
    return data


def _refuse_constant(name: str):
    raise ValueError(f"{name} is not a JSON number")


def load_mesh(path: Path):
    """Read an STL into a trimesh (vertices merged); InputError when it is not a mesh, or when
    a coordinate is not finite or beyond +-MAX_COORD_MM (nothing is measured on such a mesh)."""
    import trimesh
    try:
        size = Path(path).stat().st_size
    except OSError as exc:
        raise InputError("PATH", str(path), f"cannot be read ({exc.strerror})") from None
    if size > MAX_STL_BYTES:
        raise InputError("PATH", str(path), f"is larger than {MAX_STL_BYTES} bytes: no body mst exports")
    try:
        with np.errstate(all="ignore"):
            mesh = trimesh.load(str(path), file_type="stl", force="mesh", process=False)
    except Exception as exc:      # trimesh raises many kinds on garbage; all mean "unreadable"
        raise InputError("PATH", str(path), f"cannot be read as an STL mesh ({type(exc).__name__})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError("PATH", str(path), "holds no triangles")
    vertices = np.asarray(mesh.vertices)
    bad = ~np.isfinite(vertices).all(axis=1) | (np.abs(np.nan_to_num(vertices, nan=0.0)) > MAX_COORD_MM).any(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InputError("PATH", str(path), f"vertex {i} at {vertices[i].tolist()} mm: every coordinate "
                                            f"must be finite and within +-{MAX_COORD_MM:g} mm")
    mesh.process()                # what trimesh.load(process=True) does, now on finite coordinates
    return mesh


# --------------------------------------------------------------------------- measurements
def to_manifold(mesh):
    """manifold3d view of the mesh and its status name ("NoError" when it is a manifold)."""
    import manifold3d as mf
    m = mf.Manifold(mf.Mesh(vert_properties=np.ascontiguousarray(mesh.vertices, dtype=np.float32),
                            tri_verts=np.ascontiguousarray(mesh.faces, dtype=np.uint32)))
    return m, m.status().name


def crossings(manifold, origin, direction, length_mm: float) -> list[tuple[float, bool]]:
    """Surface crossings along a ray: (distance from origin in mm, entering the solid?).

    A hit on a face whose outward normal opposes the ray enters the solid. Hits that repeat
    (a ray through a shared edge) are merged.
    """
    o = np.asarray(origin, dtype=float)
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    hits = manifold.ray_cast(tuple(o), tuple(o + length_mm * d))
    out: list[tuple[float, bool]] = []
    for hit in hits:
        s = hit.distance * length_mm
        entering = float(np.dot(hit.normal, d)) < 0.0
        if out and abs(out[-1][0] - s) < 1e-7 and out[-1][1] == entering:
            continue
        out.append((s, entering))
    return out


def air_gaps(manifold, origin, direction, length_mm: float) -> list[tuple[float, float]]:
    """Closed air intervals (start, end) along a ray that starts and ends outside the body:
    each runs from leaving the solid to entering it again (distances in mm)."""
    gaps, left = [], None
    for s, entering in crossings(manifold, origin, direction, length_mm):
        if entering and left is not None:
            gaps.append((left, s))
            left = None
        elif not entering:
            left = s
    return gaps


def vertical_gaps(manifold, x: float, y: float, z_top: float, z_bottom: float = 0.0) -> list[tuple[float, float]]:
    """Air intervals (z_low, z_high) in mm along the vertical line through (x, y), for a body
    between z_bottom and z_top."""
    start = z_bottom - 1.0
    return [(start + a, start + b)
            for a, b in air_gaps(manifold, (x, y, start), (0, 0, 1), z_top - z_bottom + 2.0)]


def section_boxes(manifold, z_mm: float) -> list[tuple[float, float, float, float]]:
    """Bounds (x0, y0, x1, y1) of every connected region of the horizontal section at z."""
    return [tuple(part.bounds()) for part in manifold.slice(z_mm).decompose()]


def section_hole_area(manifold, z_mm: float, x: float, y: float) -> float:
    """Area (mm^2) of the smallest hole of the horizontal section at z that encloses (x, y)."""
    best = math.inf
    for ring in manifold.slice(z_mm).to_polygons():
        rx, ry = ring[:, 0], ring[:, 1]
        area = 0.5 * float(np.sum(rx * np.roll(ry, -1) - np.roll(rx, -1) * ry))
        if area < 0.0 and rx.min() < x < rx.max() and ry.min() < y < ry.max():
            best = min(best, -area)
    return best if math.isfinite(best) else 0.0


def shells(mesh) -> tuple[int, int, list[float]]:
    """(bodies, internal voids, signed shell volumes): a closed shell of negative volume is a
    cavity inside another shell.

    Shells are the connected components of the triangles (sharing vertices); each one's
    signed volume is the divergence-theorem sum of det(a, b, c) / 6 over its triangles.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    faces = np.asarray(mesh.faces)
    n_vertices = len(mesh.vertices)
    edges = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n_vertices, n_vertices))
    _, labels = connected_components(graph, directed=False)
    face_label = np.unique(labels[faces[:, 0]], return_inverse=True)[1].reshape(-1)
    tri = np.asarray(mesh.vertices)[faces]
    signed = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
    volumes = np.bincount(face_label, weights=signed).tolist()
    return sum(v > 0 for v in volumes), sum(v < 0 for v in volumes), volumes


# --------------------------------------------------------------------------- the checks
def _fmt(x: float, digits: int = 4) -> str:
    return f"{x:.{digits}g}"


def to_sensor_frame(mesh, manifest: dict):
    """A copy of the print-oriented mesh in the sensor frame (the manifest's rotation undone)."""
    pr = manifest["print"]
    rot = np.asarray(pr["rotation"], dtype=float)
    shift = np.asarray(pr["translation_mm"], dtype=float)
    out = mesh.copy()
    out.vertices = (np.asarray(mesh.vertices) - shift) @ rot      # R^T (p - T), row vectors
    return out


def _mesh_checks(mesh, manifold, status, manifest) -> tuple[list[Check], list[float]]:
    body = manifest["body"]
    out = [Check("watertight", bool(mesh.is_watertight), str(bool(mesh.is_watertight)), "True",
                 "every edge shared by exactly two triangles"),
           Check("is_volume", bool(mesh.is_volume), str(bool(mesh.is_volume)), "True",
                 "watertight, consistent winding, outward normals")]
    ok_manifold = status == "NoError" and not manifold.is_empty()
    out.append(Check("manifold3d", ok_manifold, status, "NoError", "manifold3d accepts the mesh"))
    bodies, voids, shell_volumes = shells(mesh)
    out.append(Check("one_body", bodies == body["bodies"] and voids == body["internal_voids"],
                     f"{bodies} body, {voids} void", f"{body['bodies']} body, {body['internal_voids']} void",
                     "the closed magnet pocket is the only void", values={"shell_volumes_mm3": shell_volumes}))
    vol, vol_exp, vol_tol = float(mesh.volume), float(body["volume_mm3"]), float(body["volume_tolerance_mm3"])
    out.append(Check("volume", abs(vol - vol_exp) <= vol_tol, f"{vol:.3f} mm3",
                     f"{vol_exp:.3f} +- {vol_tol:.3f} mm3", "analytic sum of base, layers, plates, cap",
                     values={"measured_mm3": vol, "expected_mm3": vol_exp, "tolerance_mm3": vol_tol}))
    bmin, bmax = mesh.bounds
    emin, emax = np.asarray(body["bbox_min_mm"]), np.asarray(body["bbox_max_mm"])
    bb_err = float(max(np.abs(bmin - emin).max(), np.abs(bmax - emax).max()))
    size, esize = bmax - bmin, emax - emin
    out.append(Check("bbox", bb_err <= PLANAR_TOL_MM, " x ".join(_fmt(v) for v in size) + " mm",
                     " x ".join(_fmt(v) for v in esize) + " mm", f"largest corner error {bb_err:.1e} mm",
                     values={"min_mm": bmin.tolist(), "max_mm": bmax.tolist(), "error_mm": bb_err}))
    return out, shell_volumes


def _per_layer(vals, unit="mm"):
    return ", ".join(_fmt(v) for v in vals) + f" {unit}"


def _layer_checks(mesh, manifold, manifest, nozzle: float, min_gap: float) -> list[Check]:
    """Walls, web depth and cavities of every layer, measured in the sensor frame."""
    z_top = manifest["body"]["bbox_max_mm"][2]
    walls, depths, cavities = [], [], []
    shape_errors: list[str] = []
    for i, layer in enumerate(manifest["layers"]):
        zb, h, t = layer["z_bottom_mm"], layer["h_mm"], layer["t_mm"]
        theta = math.radians(layer["theta_deg"])
        # Section halfway between the bottom pad's top (z = t) and the side vertex (z = h/2):
        # it cuts only the two lower walls, each t / sin(theta) wide in x, D deep in y.
        boxes = section_boxes(manifold, zb + 0.5 * (t + 0.5 * h))
        if len(boxes) != 2:
            shape_errors.append(f"layer {i + 1} section has {len(boxes)} wall cuts, design 2")
        wall = float(min(x1 - x0 for x0, _, x1, _ in boxes) * math.sin(theta)) if boxes else math.nan
        depth = float(min(y1 - y0 for _, y0, _, y1 in boxes)) if boxes else math.nan
        # Vertical ray through the cavity near x = y = 0: the air gap inside the layer's z range
        gaps = [g for g in vertical_gaps(manifold, *_RAY_OFFSET_MM, z_top) if zb < 0.5 * (g[0] + g[1]) < zb + h]
        cavity = gaps[0][1] - gaps[0][0] if len(gaps) == 1 else math.nan
        walls.append(wall)
        depths.append(depth)
        cavities.append(cavity)
        for got, want, what in ((wall, t, "wall t"), (depth, layer["web_depth_mm"], "web depth D"),
                                (cavity, layer["cavity_height_mm"], "cavity h - 2t")):
            if not abs(got - want) <= 10 * PLANAR_TOL_MM:
                shape_errors.append(f"layer {i + 1} {what} {got:.4f} mm, design {want:g}")
    layers = manifest["layers"]
    return [
        Check("wall_thickness", min(walls) >= nozzle - PLANAR_TOL_MM and not shape_errors,
              _per_layer(walls), f">= nozzle {nozzle:g} mm; design " + _per_layer([la["t_mm"] for la in layers]),
              "; ".join(shape_errors) or "wall normal thickness from sections across the stack",
              values={"per_layer_mm": walls, "nozzle_mm": nozzle}),
        Check("web_depth", all(abs(d - la["web_depth_mm"]) <= 10 * PLANAR_TOL_MM for d, la in zip(depths, layers)),
              _per_layer(depths), "design " + _per_layer([la["web_depth_mm"] for la in layers]),
              "every wall runs the whole depth (the print height)", values={"per_layer_mm": depths}),
        Check("cavity_gap", all(c >= min_gap - PLANAR_TOL_MM for c in cavities),
              _per_layer(cavities), f">= min gap {min_gap:g} mm; design " +
              _per_layer([la["cavity_height_mm"] for la in layers]),
              "vertical ray through each cavity", values={"per_layer_mm": cavities}),
    ]


def _pocket_check(manifold, manifest, shell_volumes, voids) -> tuple[Check, float]:
    """Pocket depth and floor along the axis, its section area and its void volume."""
    pocket, body = manifest["magnet_pocket"], manifest["body"]
    delta = float(manifest["stl_tolerance_mm"])
    axis_gaps = vertical_gaps(manifold, *_RAY_OFFSET_MM, body["bbox_max_mm"][2])
    p_lo, p_hi = axis_gaps[-1] if axis_gaps else (math.nan, math.nan)
    area = section_hole_area(manifold, pocket["section_z_mm"], 0.0, 0.0)
    r = pocket["radius_mm"]
    # the half circle, as a polygon of chord deviation <= delta, loses at most delta x pi r
    area_ok = pocket["section_area_mm2"] - delta * math.pi * r - 1e-3 <= area <= pocket["section_area_mm2"] + 1e-3
    depth_ok = abs((p_hi - p_lo) - pocket["depth_mm"]) <= PLANAR_TOL_MM
    floor_ok = abs(p_lo - pocket["floor_z_mm"]) <= PLANAR_TOL_MM
    void_vol = -min(shell_volumes) if voids else 0.0
    void_tol = delta * pocket["curved_area_mm2"] + 1e-5 * pocket["volume_mm3"]
    void_ok = abs(void_vol - pocket["volume_mm3"]) <= void_tol
    return Check("magnet_pocket", area_ok and depth_ok and floor_ok and void_ok,
                 f"section {area:.3f} mm2, depth {p_hi - p_lo:.3f}, floor z {p_lo:.3f} mm, {void_vol:.2f} mm3",
                 f"section {pocket['section_area_mm2']:.3f} mm2, depth {pocket['depth_mm']:g}, floor z "
                 f"{pocket['floor_z_mm']:.3f} mm, {pocket['volume_mm3']:.2f} mm3",
                 "U-shaped pocket open upwards in the print, closed by a 45 deg roof",
                 values={"section_area_mm2": area, "depth_mm": p_hi - p_lo, "floor_z_mm": p_lo,
                         "volume_mm3": void_vol}), p_lo


def _slot_check(manifold, manifest) -> tuple[Check, float]:
    """Slot floor height, width and floor along the depth, and the cable windows' floors."""
    slot, body = manifest["board_slot"], manifest["body"]
    z_top = body["bbox_max_mm"][2]
    x_far, y_far = body["bbox_max_mm"][0] + 1.0, body["bbox_max_mm"][1] + 1.0
    cx, cy = slot["chip_xy_mm"]
    chip_gaps = vertical_gaps(manifold, cx + _RAY_OFFSET_MM[0], cy + _RAY_OFFSET_MM[1], z_top)
    s_lo, s_hi = chip_gaps[0] if chip_gaps else (math.nan, math.nan)
    z_s = 0.5 * (slot["floor_z_mm"] + slot["top_z_mm"])

    def first_exit_y(x):
        """y where a ray up the depth first leaves the solid (the floor of an open slot)."""
        hits = crossings(manifold, (x, -y_far, z_s), (0, 1, 0), 2 * y_far)
        leave = [s for s, entering in hits if not entering]
        return leave[0] - y_far if leave else math.nan

    floor_y = first_exit_y(cx + _RAY_OFFSET_MM[0])
    # across the slot below the windows: the one closed air gap is the slot's width
    windows = slot["cable_windows"]
    y_across = 0.5 * (slot["floor_y_mm"] + min([w["floor_y_mm"] for w in windows], default=slot["floor_y_mm"] + 2.0))
    x_gaps = [(a - x_far, b - x_far) for a, b in air_gaps(manifold, (-x_far, y_across, z_s), (1, 0, 0), 2 * x_far)]
    x0m, x1m = x_gaps[0] if len(x_gaps) == 1 else (math.nan, math.nan)
    meas = {"floor_z_mm": s_lo, "top_z_mm": s_hi, "floor_y_mm": floor_y, "x0_mm": x0m, "x1_mm": x1m}
    want = {k: slot[k] for k in meas}
    for j, w in enumerate(windows):
        x_mid = 0.5 * (w["x_inner_mm"] + w["x_outer_mm"])
        meas[f"window_{j + 1}_floor_y_mm"] = first_exit_y(x_mid)
        want[f"window_{j + 1}_floor_y_mm"] = w["floor_y_mm"]
    bad = [k for k in meas if not abs(meas[k] - want[k]) <= PLANAR_TOL_MM]
    return Check("board_slot", not bad,
                 f"{x1m - x0m:.3f} wide, floor y {floor_y:.3f}, z {s_lo:.3f}..{s_hi:.3f}, {len(windows)} windows",
                 f"{slot['x1_mm'] - slot['x0_mm']:.3f} wide, floor y {slot['floor_y_mm']:.3f}, z "
                 f"{slot['floor_z_mm']:.3f}..{slot['top_z_mm']:.3f}, {len(windows)} windows",
                 ("mismatch: " + ", ".join(bad)) if bad else
                 f"board {slot['board']} slides in through the face on top in the print (+y)",
                 values=meas), s_lo


def _print_checks(mesh, sensor_manifold, manifest) -> list[Check]:
    """Overhangs, layer grid and magnet pause, measured on the mesh as it lies on the bed."""
    pr, pocket = manifest["print"], manifest["magnet_pocket"]
    lh = float(pr["layer_height_mm"])
    z0 = float(mesh.bounds[0][2])
    nz = mesh.face_normals[:, 2]
    zc = mesh.triangles_center[:, 2] - z0
    area = mesh.area_faces
    # down-facing faces off the bed: material above air. Inclination from horizontal alpha has
    # n_z = -cos(alpha); alpha < 45 deg needs support or a bridge.
    down = (nz < -1e-9) & (zc > LAYER_GRID_TOL_MM)
    incl = np.degrees(np.arccos(np.clip(-nz[down], -1.0, 1.0)))
    steep = incl < OVERHANG_LIMIT_DEG - 1e-3
    worst = float(incl.min()) if incl.size else 90.0
    out = [Check("overhang", not steep.any(), f"min {worst:.2f} deg, {float(area[down][steep].sum()):.3f} mm2 below",
                 f">= {OVERHANG_LIMIT_DEG:g} deg from horizontal for every down-facing face",
                 "in print orientation: nothing needs support or a bridge",
                 values={"min_inclination_deg": worst, "area_below_limit_mm2": float(area[down][steep].sum())})]
    # horizontal faces must lie on layer boundaries -- but for the chord of the pocket's round
    # bottom, which the mesher may leave flat (the slicer draws a curve as a staircase anyway)
    flat = np.abs(np.abs(nz) - 1.0) < 1e-9
    c = mesh.triangles_center
    r, floor_z = pocket["radius_mm"], pocket["floor_z_mm"]
    in_round_bottom = ((np.abs(c[:, 0]) <= r + 1e-6) & (c[:, 1] <= -floor_z + 1e-6)
                       & (c[:, 1] >= -(floor_z + pocket["depth_mm"]) - 1e-6)
                       & (zc >= 0.5 * pr["height_mm"] - r - 1e-6) & (zc < 0.5 * pr["height_mm"]))
    flat &= ~in_round_bottom
    heights = np.unique(np.round(zc[flat], 6))
    off = [float(z) for z in heights if abs(z / lh - round(z / lh)) * lh > LAYER_GRID_TOL_MM]
    out.append(Check("layer_grid", not off, f"{len(heights)} heights, {len(off)} off the grid",
                     f"every horizontal face on a multiple of {lh:g} mm",
                     ("off: " + ", ".join(f"{z:.4f}" for z in off[:5])) if off else
                     "the slicer prints every horizontal face where it was designed",
                     values={"heights_mm": heights.tolist(), "off_grid_mm": off}))
    # the magnet pause: on a layer boundary, above the magnet, at or below the roof's start
    pause = pr["pause"]
    z_pause = float(pause["z_mm"])
    d = float(pocket["depth_mm"])
    # the pocket along the build direction (sensor +y), through its mid-depth: from the U's
    # bottom up to the roof's ridge; the roof starts its rise below the ridge
    half = 0.5 * float(pr["height_mm"])
    cols = air_gaps(sensor_manifold, (0.0123, -half - 1.0, pocket["floor_z_mm"] + 0.5 * d), (0, 1, 0),
                    2.0 * half + 2.0)
    roof_start = cols[-1][1] - 1.0 - float(pocket["roof_rise_mm"]) if cols else math.nan
    ok = (abs(z_pause / lh - round(z_pause / lh)) * lh <= LAYER_GRID_TOL_MM
          and pause["after_layer"] == round(z_pause / lh)
          and pr["magnet_top_z_mm"] <= z_pause + 1e-9 and roof_start >= z_pause - PLANAR_TOL_MM)
    out.append(Check("magnet_pause", ok, f"roof starts at z {roof_start:.3f} mm",
                     f"pause after layer {pause['after_layer']} at z {z_pause:.2f} mm, magnet top "
                     f"{pr['magnet_top_z_mm']:.2f} mm",
                     f"pause after layer {pause['after_layer']} (z = {z_pause:.2f} mm) to drop the magnet in",
                     values={"roof_start_z_mm": roof_start, "pause_z_mm": z_pause}))
    return out


def run_checks(mesh, manifest: dict, nozzle_mm: float | None = None) -> list[Check]:
    """Every check of the module docstring, in order. Pure: reads only its arguments.

    ``mesh`` is the STL as written (print orientation)."""
    printer = manifest["printer"]
    nozzle = float(printer["nozzle_mm"] if nozzle_mm is None else nozzle_mm)
    min_gap = float(printer["min_gap_mm"])
    sensor = to_sensor_frame(mesh, manifest)
    manifold, status = to_manifold(sensor)
    out, shell_volumes = _mesh_checks(sensor, manifold, status, manifest)
    voids = sum(v < 0 for v in shell_volumes)
    out += _layer_checks(sensor, manifold, manifest, nozzle, min_gap)
    pocket_check, pocket_floor = _pocket_check(manifold, manifest, shell_volumes, voids)
    slot_check, slot_floor = _slot_check(manifold, manifest)
    out += [pocket_check, slot_check]
    slot = manifest["board_slot"]
    gap_meas = pocket_floor - (slot_floor + slot["board_thickness_mm"] + 0.5 * slot["chip_height_mm"])
    out.append(Check("magnet_chip_gap", abs(gap_meas - manifest["gap0_mm"]) <= PLANAR_TOL_MM,
                     f"{gap_meas:.4f} mm", f"{manifest['gap0_mm']:.4f} mm (forward model gap0)",
                     "pocket floor - (slot floor + board + chip/2)", values={"measured_mm": gap_meas}))
    out += _print_checks(mesh, manifold, manifest)
    return out


def results_dict(checks: list[Check], stl_path: str) -> dict:
    """JSON form (``mst check --json``); a value that could not be measured (NaN) is null."""
    from mst_cli.io.outputs import finite_or_none
    failed = [c.name for c in checks if not c.passed and not c.info]
    return finite_or_none({"path": stl_path, "passed": not failed, "failed": failed,
                           "checks": [asdict(c) for c in checks]})


def results_table(checks: list[Check]) -> str:
    """Terminal table: check, PASS/FAIL/info, measured, expected, note."""
    rows = [("check", "result", "measured", "expected")]
    for c in checks:
        rows.append((c.name, "info" if c.info else ("PASS" if c.passed else "FAIL"), c.measured, c.expected))
    widths = [max(len(r[i]) for r in rows) for i in range(4)]
    lines = []
    for j, r in enumerate(rows):
        lines.append("  ".join(cell.ljust(w) for cell, w in zip(r, widths)).rstrip())
        if j == 0:
            lines.append("  ".join("-" * w for w in widths))
    notes = [f"  {c.name}: {c.note}" for c in checks if c.note]
    return "\n".join(lines + ["notes:"] + notes)
