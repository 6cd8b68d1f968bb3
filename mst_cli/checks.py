"""Geometry checks of an exported sensor body (what ``mst check`` runs).

Pure functions: a mesh and the ``export.json`` manifest in, a list of :class:`Check` out. The
manifest holds the design's own expected values (computed from the geometry object), so each
check compares a number *measured on the mesh* -- by ray casts, plane sections and face
normals -- with the design:

* ``watertight``, ``is_volume`` (consistent winding, positive volume), ``manifold3d`` (the mesh
  is accepted as a manifold), ``one_body`` (one shell of positive volume plus the closed
  magnet pocket as the only internal void);
* ``volume`` and ``bbox`` against the analytic sum of the parts;
* ``wall_thickness``, ``strut_width``, ``strut_spacing``, ``cavity_gap`` against the nozzle
  and the minimum printable gap, measured in horizontal sections through each layer's walls
  and along vertical rays through its cavity;
* ``magnet_pocket``, ``board_slot`` and ``magnet_chip_gap`` (the unloaded distance the forward
  model uses, rebuilt from the measured pocket floor and slot floor);
* ``overhang`` (report only): the measured inclination of each layer's down-facing walls in
  print orientation against the usual 45 deg limit.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from .schema import InputError

# Planar features are exact in the B-rep; the STL stores float32 coordinates, which resolve
# ~2e-6 mm at 20 mm from the origin. Dimensions measured on planar faces must agree to this.
PLANAR_TOL_MM = 1e-4
OVERHANG_LIMIT_DEG = 45.0
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


def load_manifest(path: Path) -> dict:
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError("export.json", str(path), f"cannot be read as JSON ({type(exc).__name__})") from None
    for key in ("body", "magnet_pocket", "board_slot", "layers", "printer", "gap0_mm", "stl_tolerance_mm"):
        if key not in data:
            raise InputError(f"export.json.{key}", None, "missing: rewrite it with 'mst export'")
    return data


def load_mesh(path: Path):
    """Read an STL into a trimesh (vertices merged); InputError when it is not a mesh."""
    import trimesh
    try:
        mesh = trimesh.load(str(path), file_type="stl", force="mesh")
    except Exception as exc:      # trimesh raises many kinds on garbage; all mean "unreadable"
        raise InputError("PATH", str(path), f"cannot be read as an STL mesh ({type(exc).__name__})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise InputError("PATH", str(path), "holds no triangles")
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


def downward_wall_angles_deg(mesh, z0: float, z1: float) -> np.ndarray:
    """Inclination from horizontal (deg) of the down-facing, non-horizontal faces whose
    centroid lies strictly between z0 and z1. A face at alpha from horizontal has a normal
    alpha from the vertical: n_z = -cos(alpha)."""
    nz = mesh.face_normals[:, 2]
    zc = mesh.triangles_center[:, 2]
    pick = (zc > z0 + 1e-6) & (zc < z1 - 1e-6) & (nz < -1e-9) & (nz > -1 + 1e-9)
    return np.degrees(np.arccos(np.clip(-nz[pick], -1.0, 1.0)))


# --------------------------------------------------------------------------- the checks
def _fmt(x: float, digits: int = 4) -> str:
    return f"{x:.{digits}g}"


def run_checks(mesh, manifest: dict, nozzle_mm: float | None = None) -> list[Check]:
    """Every check of the module docstring, in order. Pure: reads only its arguments."""
    body, pocket, slot = manifest["body"], manifest["magnet_pocket"], manifest["board_slot"]
    printer = manifest["printer"]
    nozzle = float(printer["nozzle_mm"] if nozzle_mm is None else nozzle_mm)
    min_gap = float(printer["min_gap_mm"])
    delta = float(manifest["stl_tolerance_mm"])
    out: list[Check] = []

    # -- mesh validity
    out.append(Check("watertight", bool(mesh.is_watertight), str(bool(mesh.is_watertight)), "True",
                     "every edge shared by exactly two triangles"))
    out.append(Check("is_volume", bool(mesh.is_volume), str(bool(mesh.is_volume)), "True",
                     "watertight, consistent winding, outward normals"))
    manifold, status = to_manifold(mesh)
    ok_manifold = status == "NoError" and not manifold.is_empty()
    out.append(Check("manifold3d", ok_manifold, status, "NoError", "manifold3d accepts the mesh"))
    bodies, voids, shell_volumes = shells(mesh)
    out.append(Check("one_body", bodies == body["bodies"] and voids == body["internal_voids"],
                     f"{bodies} body, {voids} void", f"{body['bodies']} body, {body['internal_voids']} void",
                     "the closed magnet pocket is the only void", values={"shell_volumes_mm3": shell_volumes}))

    # -- volume and bounding box
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

    # -- layers: walls, struts, cavities, overhangs
    walls, widths, spacings, cavities, angles = [], [], [], [], []
    shape_errors: list[str] = []
    for i, layer in enumerate(manifest["layers"]):
        zb, h, t, b = layer["z_bottom_mm"], layer["h_mm"], layer["t_mm"], layer["b_mm"]
        n_struts = len(layer["strut_centres_y_mm"])
        ang = downward_wall_angles_deg(mesh, zb, zb + h)
        theta = float(np.median(ang)) if ang.size else float("nan")
        angles.append(theta)
        if not abs(theta - layer["theta_deg"]) <= 1e-2:
            shape_errors.append(f"layer {i + 1} wall angle {theta:.3f} deg, design {layer['theta_deg']:g}")
        # Horizontal section halfway between the bottom pad's top (z = t) and the side vertex
        # (z = h/2): it cuts only the lower walls, 2 per strut, each t / sin(theta) wide in x.
        boxes = section_boxes(manifold, zb + 0.5 * (t + 0.5 * h))
        if len(boxes) != 2 * n_struts:
            shape_errors.append(f"layer {i + 1} section has {len(boxes)} wall cuts, design {2 * n_struts}")
        if boxes:
            wx = np.array([x1 - x0 for x0, _, x1, _ in boxes])
            wy = np.array([y1 - y0 for _, y0, _, y1 in boxes])
            walls.append(float(wx.min() * math.sin(math.radians(theta))))
            widths.append(float(wy.min()))
            # clear gaps between neighbouring struts on the same side (x > 0)
            right = sorted((y0, y1) for x0, y0, x1, y1 in boxes if x0 > 0)
            spacings += [b0 - a1 for (_, a1), (b0, _) in zip(right[:-1], right[1:])]
        # Vertical ray through the first strut's cavity, near x = 0: the air gap inside the
        # layer's z range is the cavity, h - 2t high.
        y_c = layer["strut_centres_y_mm"][0]
        gaps = [g for g in vertical_gaps(manifold, _RAY_OFFSET_MM[0], y_c + _RAY_OFFSET_MM[1],
                                         body["bbox_max_mm"][2])
                if zb < 0.5 * (g[0] + g[1]) < zb + h]
        cavities.append(gaps[0][1] - gaps[0][0] if len(gaps) == 1 else float("nan"))
        for got, want, what in ((walls[-1] if boxes else float("nan"), t, "wall t"),
                                (widths[-1] if boxes else float("nan"), b, "strut width b"),
                                (cavities[-1], layer["cavity_height_mm"], "cavity h - 2t")):
            if not abs(got - want) <= 10 * PLANAR_TOL_MM:
                shape_errors.append(f"layer {i + 1} {what} {got:.4f} mm, design {want:g}")

    def per_layer(vals, unit="mm"):
        return ", ".join(_fmt(v) for v in vals) + f" {unit}"

    min_wall = min(walls) if walls else float("nan")
    out.append(Check("wall_thickness", min_wall >= nozzle - PLANAR_TOL_MM and not shape_errors,
                     per_layer(walls), f">= nozzle {nozzle:g} mm; design " +
                     per_layer([la["t_mm"] for la in manifest["layers"]]),
                     "; ".join(shape_errors) or "wall normal thickness from horizontal sections",
                     values={"per_layer_mm": walls, "nozzle_mm": nozzle}))
    min_width = min(widths) if widths else float("nan")
    out.append(Check("strut_width", min_width >= nozzle - PLANAR_TOL_MM, per_layer(widths),
                     f">= nozzle {nozzle:g} mm", values={"per_layer_mm": widths}))
    min_spacing = min(spacings) if spacings else math.inf
    out.append(Check("strut_spacing", min_spacing >= min_gap - PLANAR_TOL_MM,
                     "single strut" if not spacings else f"{min_spacing:.4g} mm",
                     f">= min gap {min_gap:g} mm", "clear gap between neighbouring struts",
                     values={"min_mm": min_spacing if spacings else None}))
    out.append(Check("cavity_gap", all(c >= min_gap - PLANAR_TOL_MM for c in cavities),
                     per_layer(cavities), f">= min gap {min_gap:g} mm; design " +
                     per_layer([la["cavity_height_mm"] for la in manifest["layers"]]),
                     "vertical ray through each cavity", values={"per_layer_mm": cavities}))

    # -- magnet pocket: vertical ray on the axis (the pocket is the topmost air gap) and a
    # horizontal section through its cylindrical part.
    z_top = body["bbox_max_mm"][2]
    axis_gaps = vertical_gaps(manifold, *_RAY_OFFSET_MM, z_top)
    p_lo, p_hi = axis_gaps[-1] if axis_gaps else (float("nan"), float("nan"))
    z_mid = pocket["floor_z_mm"] + 0.5 * (pocket["depth_mm"] - pocket["chamfer_mm"])
    hole = section_hole_area(manifold, z_mid, 0.0, 0.0)
    d_meas = 2.0 * math.sqrt(hole / math.pi)
    r = 0.5 * pocket["diameter_mm"]
    # A polygon with chord deviation <= delta lies between circles of radius r - delta and r.
    d_ok = 2 * (r - delta) - PLANAR_TOL_MM <= d_meas <= 2 * r + PLANAR_TOL_MM
    depth_ok = abs((p_hi - p_lo) - pocket["depth_mm"]) <= PLANAR_TOL_MM
    floor_ok = abs(p_lo - pocket["floor_z_mm"]) <= PLANAR_TOL_MM
    void_vol = -min(shell_volumes) if voids else 0.0
    void_tol = delta * pocket["curved_area_mm2"] + 1e-5 * pocket["volume_mm3"]
    void_ok = abs(void_vol - pocket["volume_mm3"]) <= void_tol
    out.append(Check("magnet_pocket", d_ok and depth_ok and floor_ok and void_ok,
                     f"D {d_meas:.3f}, depth {p_hi - p_lo:.3f}, floor z {p_lo:.3f} mm, {void_vol:.2f} mm3",
                     f"D {pocket['diameter_mm']:g}, depth {pocket['depth_mm']:g}, floor z "
                     f"{pocket['floor_z_mm']:.3f} mm, {pocket['volume_mm3']:.2f} mm3",
                     f"pause the print at z = {pocket['pause_height_mm']:.2f} mm to insert the magnet",
                     values={"diameter_mm": d_meas, "depth_mm": p_hi - p_lo, "floor_z_mm": p_lo,
                             "volume_mm3": void_vol}))

    # -- board slot: vertical ray at the chip, horizontal rays across the slot.
    cx, cy = slot["chip_xy_mm"]
    chip_gaps = vertical_gaps(manifold, cx + _RAY_OFFSET_MM[0], cy + _RAY_OFFSET_MM[1], z_top)
    s_lo, s_hi = chip_gaps[0] if chip_gaps else (float("nan"), float("nan"))
    z_s = 0.5 * (slot["floor_z_mm"] + slot["top_z_mm"])
    x_far = body["bbox_max_mm"][0] + 1.0
    y_far = body["bbox_max_mm"][1] + 1.0
    # along +y at the chip: air between the slot's side walls
    y_gaps = [(a - y_far, b - y_far) for a, b in
              air_gaps(manifold, (cx + _RAY_OFFSET_MM[0], -y_far, z_s), (0, 1, 0), 2 * y_far)]
    y0m, y1m = y_gaps[0] if len(y_gaps) == 1 else (float("nan"), float("nan"))
    # along +x beside the cable exit: the slot is open to -x, so the first hit is its end wall
    e0, e1 = slot["cable_exit_y_mm"]
    y_side = 0.5 * (slot["y0_mm"] + e0) if e0 - slot["y0_mm"] > 2 * PLANAR_TOL_MM \
        else 0.5 * (slot["y1_mm"] + e1)
    hits = crossings(manifold, (-x_far, y_side, z_s), (1, 0, 0), 2 * x_far)
    x1m = hits[0][0] - x_far if hits and hits[0][1] else float("nan")
    # along +y through the +x wall: the cable exit
    x_wall = 0.5 * (slot["x1_mm"] + body["bbox_max_mm"][0])
    e_gaps = [(a - y_far, b - y_far) for a, b in
              air_gaps(manifold, (x_wall, -y_far, z_s), (0, 1, 0), 2 * y_far)]
    exit_w = e_gaps[0][1] - e_gaps[0][0] if len(e_gaps) == 1 else 0.0
    meas = {"floor_z_mm": s_lo, "top_z_mm": s_hi, "y0_mm": y0m, "y1_mm": y1m, "x1_mm": x1m,
            "cable_exit_width_mm": exit_w}
    want = {"floor_z_mm": slot["floor_z_mm"], "top_z_mm": slot["top_z_mm"], "y0_mm": slot["y0_mm"],
            "y1_mm": slot["y1_mm"], "x1_mm": slot["x1_mm"], "cable_exit_width_mm": e1 - e0}
    bad = [k for k in meas if not abs(meas[k] - want[k]) <= PLANAR_TOL_MM]
    out.append(Check("board_slot", not bad,
                     f"{y1m - y0m:.3f} wide, end x {x1m:.3f}, z {s_lo:.3f}..{s_hi:.3f}, exit {exit_w:.3f} mm",
                     f"{slot['width_y_mm']:.3f} wide, end x {slot['x1_mm']:.3f}, z {slot['floor_z_mm']:.3f}.."
                     f"{slot['top_z_mm']:.3f}, exit {e1 - e0:.3f} mm",
                     ("mismatch: " + ", ".join(bad)) if bad else f"board {slot['board']}, slides in from -x",
                     values=meas))

    # -- the forward model's magnet-chip distance, rebuilt from what was measured
    gap_meas = p_lo - (s_lo + slot["board_thickness_mm"] + 0.5 * slot["chip_height_mm"])
    out.append(Check("magnet_chip_gap", abs(gap_meas - manifest["gap0_mm"]) <= PLANAR_TOL_MM,
                     f"{gap_meas:.4f} mm", f"{manifest['gap0_mm']:.4f} mm (forward model gap0)",
                     "pocket floor - (slot floor + board + chip/2)", values={"measured_mm": gap_meas}))

    # -- overhangs in print orientation (report only)
    steep = [i + 1 for i, a in enumerate(angles) if a < OVERHANG_LIMIT_DEG]
    out.append(Check("overhang", True, per_layer(angles, "deg"),
                     f"report: limit {OVERHANG_LIMIT_DEG:g} deg from horizontal",
                     (f"layers {', '.join(map(str, steep))} have walls below {OVERHANG_LIMIT_DEG:g} deg: "
                      "short TPU struts usually bridge, print a test layer") if steep
                     else "every wall at or above the limit",
                     info=True, values={"per_layer_deg": angles, "below_limit_layers": steep}))
    return out


def results_dict(checks: list[Check], stl_path: str) -> dict:
    """JSON form (``mst check --json``)."""
    failed = [c.name for c in checks if not c.passed and not c.info]
    return {"path": stl_path, "passed": not failed, "failed": failed,
            "checks": [asdict(c) for c in checks]}


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
