"""Geometry checks of an exported sensor body (what ``mst check`` runs).

The mesh is measured once (:func:`mst_cli.cad.measure.measure`); each check is one small
function that compares those measurements with the design's own values in the typed manifest
(:class:`~mst_cli.cad.manifest.Manifest`, from ``export.json``) and returns a :class:`Check`.
:data:`CHECKS` lists them in report order:

* ``watertight``, ``is_volume`` (consistent winding, positive volume), ``manifold3d`` (the mesh
  is accepted as a manifold), ``one_body`` (one shell of positive volume plus the closed
  magnet pocket as the only internal void);
* ``volume`` and ``bbox`` against the analytic sum of the parts;
* ``wall_thickness``, ``web_depth``, ``cavity_gap`` against the nozzle and the minimum
  printable gap, measured in sections through each layer's walls and along rays through its
  cavity;
* ``magnet_pocket``, ``board_slot``, ``footprint`` (the body is the face, every slot inside it) and
  ``magnet_chip_gap`` (the unloaded distance the forward
  model uses, rebuilt from the measured pocket floor and slot floor);
* print orientation: ``overhang`` (every down-facing face at least 45 deg from horizontal, so
  nothing needs support or a bridge), ``layer_grid`` (every horizontal face on a boundary of
  the print layers, so the slicer prints it where it was designed) and ``magnet_pause`` (the
  magnet goes in whole before the layer after the pause, which starts the pocket's roof);
* ``load_path``: each member's share of the magnet's motion under a centred press, from the
  design (:mod:`mst_cli.model.load_path`); fails when the share the closed form leaves
  uncertain exceeds the regime's accuracy budget, or the share over ``--load-path-max``.

The export's files are found and read by :mod:`mst_cli.cad.export_files`. The manifest
validated itself on load, so a KeyError or TypeError in here is a bug.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from mst_cli.cad.export_files import ExportFiles as ExportFiles  # re-exported: the checks' inputs
from mst_cli.cad.export_files import load_mesh as load_mesh
from mst_cli.cad.export_files import resolve_export as resolve_export
from mst_cli.cad.manifest import Manifest
from mst_cli.cad.measure import LAYER_GRID_TOL_MM, Measurements, measure
from mst_cli.cad.mesh_io import Mesh
from mst_cli.io.outputs import finite_or_none
from mst_cli.model.load_path_report import dominant_member, load_path_report, support_uncertainty
from mst_cli.model.mechanics import layer_laws
from mst_cli.model.stack import Stack

# Planar features are exact in the B-rep; the STL stores float32 coordinates, which resolve
# ~2e-6 mm at 20 mm from the origin. Dimensions measured on planar faces must agree to this.
PLANAR_TOL_MM = 1e-4
# per-layer shape dimensions (wall, web depth, cavity) go through a section or a sine
LAYER_TOL_MM = 10 * PLANAR_TOL_MM
OVERHANG_LIMIT_DEG = 45.0


@dataclass(frozen=True)
class Check:
    """One named check: passed, what was measured and what was expected (text with units), a
    note saying what it means or what broke, and the measured numbers (units in the keys)."""

    name: str
    passed: bool
    measured: str
    expected: str
    note: str = ""
    info: bool = False  # report only: never fails
    values: dict = field(default_factory=dict)


# --------------------------------------------------------------------------- the checks
def _fmt(x: float, digits: int = 4) -> str:
    return f"{x:.{digits}g}"


def _per_layer(vals, unit="mm"):
    return ", ".join(_fmt(v) for v in vals) + f" {unit}"


def check_watertight(m: Measurements, x: Manifest) -> Check:
    return Check("watertight", m.watertight, str(m.watertight), "True", "every edge shared by exactly two triangles")


def check_is_volume(m: Measurements, x: Manifest) -> Check:
    return Check("is_volume", m.is_volume, str(m.is_volume), "True", "watertight, consistent winding, outward normals")


def check_manifold3d(m: Measurements, x: Manifest) -> Check:
    return Check(
        "manifold3d",
        m.manifold_status == "NoError" and not m.manifold_empty,
        m.manifold_status,
        "NoError",
        "manifold3d accepts the mesh",
    )


def check_one_body(m: Measurements, x: Manifest) -> Check:
    body = x.body
    return Check(
        "one_body",
        m.bodies == body.bodies and m.voids == body.internal_voids,
        f"{m.bodies} body, {m.voids} void",
        f"{body.bodies} body, {body.internal_voids} void",
        "the closed voids are the magnet pocket" + (" and the insert's slot" if x.body.internal_voids > 1 else ""),
        values={"shell_volumes_mm3": m.shell_volumes_mm3},
    )


def check_volume(m: Measurements, x: Manifest) -> Check:
    vol, vol_exp, vol_tol = m.volume_mm3, x.body.volume_mm3, x.body.volume_tolerance_mm3
    return Check(
        "volume",
        abs(vol - vol_exp) <= vol_tol,
        f"{vol:.3f} mm3",
        f"{vol_exp:.3f} +- {vol_tol:.3f} mm3",
        "analytic sum of base, layers, plates, cap",
        values={"measured_mm3": vol, "expected_mm3": vol_exp, "tolerance_mm3": vol_tol},
    )


def check_bbox(m: Measurements, x: Manifest) -> Check:
    bmin, bmax = m.bbox_min_mm, m.bbox_max_mm
    emin, emax = np.asarray(x.body.bbox_min_mm), np.asarray(x.body.bbox_max_mm)
    err = float(max(np.abs(bmin - emin).max(), np.abs(bmax - emax).max()))
    return Check(
        "bbox",
        err <= PLANAR_TOL_MM,
        " x ".join(_fmt(v) for v in bmax - bmin) + " mm",
        " x ".join(_fmt(v) for v in emax - emin) + " mm",
        f"largest corner error {err:.1e} mm",
        values={"min_mm": bmin.tolist(), "max_mm": bmax.tolist(), "error_mm": err},
    )


def check_wall_thickness(m: Measurements, x: Manifest) -> Check:
    """Every wall at least one nozzle wide -- and every layer's section the designed shape (two
    wall cuts; wall, web depth and cavity as designed), or the wall numbers mean nothing."""
    nozzle = x.printer.nozzle_mm
    walls = [s.wall_mm for s in m.layers]
    shape_errors: list[str] = []
    for i, (s, layer) in enumerate(zip(m.layers, x.layers)):
        if s.wall_cuts != 2:
            shape_errors.append(f"layer {i + 1} section has {s.wall_cuts} wall cuts, design 2")
        for got, want, what in (
            (s.wall_mm, layer.t_mm, "wall t"),
            (s.web_depth_mm, layer.web_depth_mm, "web depth D"),
            (s.cavity_mm, layer.cavity_height_mm, "cavity h - 2t"),
        ):
            if not abs(got - want) <= LAYER_TOL_MM:
                shape_errors.append(f"layer {i + 1} {what} {got:.4f} mm, design {want:g}")
    return Check(
        "wall_thickness",
        min(walls) >= nozzle - PLANAR_TOL_MM and not shape_errors,
        _per_layer(walls),
        f">= nozzle {nozzle:g} mm; design " + _per_layer([la.t_mm for la in x.layers]),
        "; ".join(shape_errors) or "wall normal thickness from sections across the stack",
        values={"per_layer_mm": walls, "nozzle_mm": nozzle},
    )


def check_web_depth(m: Measurements, x: Manifest) -> Check:
    depths = [s.web_depth_mm for s in m.layers]
    return Check(
        "web_depth",
        all(abs(d - la.web_depth_mm) <= LAYER_TOL_MM for d, la in zip(depths, x.layers)),
        _per_layer(depths),
        "design " + _per_layer([la.web_depth_mm for la in x.layers]),
        "every wall runs the whole depth (the print height)",
        values={"per_layer_mm": depths},
    )


def check_cavity_gap(m: Measurements, x: Manifest) -> Check:
    min_gap = x.printer.min_gap_mm
    cavities = [s.cavity_mm for s in m.layers]
    return Check(
        "cavity_gap",
        all(c >= min_gap - PLANAR_TOL_MM for c in cavities),
        _per_layer(cavities),
        f">= min gap {min_gap:g} mm; design " + _per_layer([la.cavity_height_mm for la in x.layers]),
        "vertical ray through each cavity",
        values={"per_layer_mm": cavities},
    )


def check_magnet_pocket(m: Measurements, x: Manifest) -> Check:
    """Pocket depth and floor along the axis, its section area and its void volume."""
    got, want, delta = m.pocket, x.magnet_pocket, x.stl_tolerance_mm
    # the half circle, as a polygon of chord deviation <= delta, loses at most delta x pi r
    area_ok = (
        want.section_area_mm2 - delta * math.pi * want.radius_mm - 1e-3
        <= got.section_area_mm2
        <= want.section_area_mm2 + 1e-3
    )
    depth_ok = abs(got.depth_mm - want.depth_mm) <= PLANAR_TOL_MM
    floor_ok = abs(got.floor_z_mm - want.floor_z_mm) <= PLANAR_TOL_MM
    void_tol = delta * want.curved_area_mm2 + 1e-5 * want.volume_mm3
    void_ok = abs(got.void_volume_mm3 - want.volume_mm3) <= void_tol
    return Check(
        "magnet_pocket",
        area_ok and depth_ok and floor_ok and void_ok,
        f"section {got.section_area_mm2:.3f} mm2, depth {got.depth_mm:.3f}, floor z {got.floor_z_mm:.3f} mm, "
        f"{got.void_volume_mm3:.2f} mm3",
        f"section {want.section_area_mm2:.3f} mm2, depth {want.depth_mm:g}, floor z "
        f"{want.floor_z_mm:.3f} mm, {want.volume_mm3:.2f} mm3",
        "U-shaped pocket open upwards in the print, closed by a 45 deg roof",
        values={
            "section_area_mm2": got.section_area_mm2,
            "depth_mm": got.depth_mm,
            "floor_z_mm": got.floor_z_mm,
            "volume_mm3": got.void_volume_mm3,
        },
    )


def _slot_values(got, slot, prefix: str) -> tuple[dict, dict]:
    """(measured, designed) of one slot: floor height, width, floor along the depth and its
    windows' floors, keyed ``{prefix}x0_mm`` and so on."""
    keys = ("floor_z_mm", "top_z_mm", "floor_y_mm", "x0_mm", "x1_mm")
    meas = {prefix + k: getattr(got, k) for k in keys}
    want = {prefix + k: getattr(slot, k) for k in keys}
    for j, (window, floor_y) in enumerate(zip(slot.cable_windows, got.window_floor_y_mm)):
        meas[f"{prefix}window_{j + 1}_floor_y_mm"] = floor_y
        want[f"{prefix}window_{j + 1}_floor_y_mm"] = window.floor_y_mm
    return meas, want


def _slot_text(size, n_windows: int) -> str:
    return (
        f"{size.x1_mm - size.x0_mm:.3f} wide, floor y {size.floor_y_mm:.3f}, "
        f"z {size.floor_z_mm:.3f}..{size.top_z_mm:.3f}, {n_windows} windows"
    )


def check_board_slot(m: Measurements, x: Manifest) -> Check:
    """Every chip's slot: floor height, width and floor along the depth, and the cable windows'
    floors. The first chip's keys are unprefixed (as a one-chip export has them), chip k's
    (from 2) start ``chip_k_``."""
    meas, want, got_text, want_text = {}, {}, [], []
    for k, (got, slot) in enumerate(zip(m.slots, x.slots)):
        prefix, label = (f"chip_{k + 1}_", f"chip {k + 1}: ") if k else ("", "")
        mk, wk = _slot_values(got, slot, prefix)
        meas.update(mk)
        want.update(wk)
        got_text.append(label + _slot_text(got, len(slot.cable_windows)))
        want_text.append(label + _slot_text(slot, len(slot.cable_windows)))
    bad = [k for k in meas if not abs(meas[k] - want[k]) <= PLANAR_TOL_MM]
    n = len(x.slots)
    slides = f"board {x.board_slot.board} slides in" if n == 1 else f"{n} boards slide in side by side"
    return Check(
        "board_slot",
        not bad,
        "; ".join(got_text),
        "; ".join(want_text),
        ("mismatch: " + ", ".join(bad)) if bad else f"{slides} through the face on top in the print (+y)",
        values=meas,
    )


def check_footprint(m: Measurements, x: Manifest) -> Check:
    """The body is the face (W wide along x, as the spec says) and every board slot, with the
    design's side wall outside it, lies within it: a layout that needed a wider body fails here
    (exports before 0.18 widened the base instead), naming the slot."""
    width = next((layer.width_mm for layer in x.layers if layer.width_mm is not None), None)
    if width is None and x.design is not None:
        width = x.design.family.width_mm
    span = float(m.bbox_max_mm[0] - m.bbox_min_mm[0])
    if width is None:
        return Check("footprint", True, f"body {span:.4g} mm along x", "face width not in export.json", info=True)
    wall = x.design.housing.side_wall_mm if x.design is not None else 0.0
    half, tol = 0.5 * width, PLANAR_TOL_MM
    bad = [] if abs(span - width) <= tol else [f"the body is {span:.4g} mm wide, not the face's {width:g} mm"]
    for k, got in enumerate(m.slots):
        if got.x0_mm - wall < -half - tol or got.x1_mm + wall > half + tol:
            bad.append(
                f"chip {k + 1}'s slot x {got.x0_mm:.4g}..{got.x1_mm:.4g} mm leaves less than {wall:g} mm of wall"
            )
    slots = ", ".join(f"{got.x0_mm:.3f}..{got.x1_mm:.3f}" for got in m.slots)
    return Check(
        "footprint",
        not bad,
        f"body {span:.4g} mm along x; slots x {slots} mm",
        f"body {width:g} mm (the face); slots within |x| <= {half - wall:g} mm",
        "; ".join(bad) if bad else "every board slot lies inside the face, a side wall outside it",
        values={"body_width_mm": span, "face_width_mm": width, "side_wall_mm": wall},
    )


def check_load_path(m: Measurements, x: Manifest, share_max: float | None = None) -> Check:
    """Where a centred press's motion of the magnet goes (docs/design.md 4.6): the layers (L0)
    against the cap, plates and cover in closed form, each in the part's regimes while the
    forward model moves it (load_path.motion_shares), from the design in export.json. Fails,
    naming the member, when the share outside the layers in some regime exceeds ``share_max``
    (``--load-path-max``) or, without it, when the share the closed form leaves uncertain
    (the beams' ends held at the soft and at the stiff bound of what restrains them) exceeds the
    regime's accuracy budget
    (5 % before the first lock, 8 % after one, 20 % after two: load_path.support_uncertainty)."""
    if x.design is None:
        return Check("load_path", True, "no design in export.json", "the design's members", info=True)
    doc = x.design
    g = doc.geometry()
    report = load_path_report(g, doc.material, Stack(layer_laws(g.layers, doc.material, "spring")))
    rows = report["regimes"]
    got = ", ".join(f"{100 * r['outside_layers']:.0f} %" for r in rows)
    if share_max is None:
        budget = support_uncertainty(report)
        over = [b for b in budget if b["uncertain_share"] > b["budget"]]
        worst = max(over or budget, key=lambda b: b["uncertain_share"] / b["budget"])
        name, row = worst["member"], rows[worst["regime"] - 1]
        bound = "uncertain share <= " + " / ".join(f"{100 * b['budget']:.0f}" for b in budget) + " % per regime"
        note = (
            f"regime {row['regime']}: {100 * row['outside_layers']:.0f} % of the magnet's motion is outside the "
            f"layers, {100 * worst['uncertain_share']:.0f} % uncertain between its supports' soft and stiff bounds "
            f"(budget {100 * worst['budget']:.0f} %), most of that in the {name}'s supports"
        )
        bad = bool(over)
    else:
        row = max(rows, key=lambda r: r["outside_layers"])
        name, share = dominant_member(row)
        bound = f"<= {100 * share_max:.0f} % in every regime (--load-path-max)"
        note = (
            f"regime {row['regime']}: {100 * row['outside_layers']:.0f} % of the magnet's motion is outside "
            f"the layers, {100 * share:.0f} % in the {name} ({report['cap_mm_per_N']:.3g} mm/N cap; clamped bound "
            f"{100 * row['outside_layers_clamped']:.0f} %)"
        )
        bad = row["outside_layers"] > share_max
    return Check(
        "load_path",
        not bad,
        f"outside the layers per regime: {got}",
        bound,
        ("the " + name + " is too soft: " + note) if bad else note,
        values={"outside_layers": [r["outside_layers"] for r in rows], "dominant_member": name},
    )


def check_magnet_chip_gap(m: Measurements, x: Manifest) -> Check:
    """The forward model's unloaded gap, rebuilt from the measured pocket and slot floors, under
    every chip (chip k's, from 2, keyed ``chip_k_measured_mm``)."""
    gaps = [
        m.pocket.floor_z_mm - (got.floor_z_mm + slot.board_thickness_mm + 0.5 * slot.chip_height_mm)
        for got, slot in zip(m.slots, x.slots)
    ]
    values = {(f"chip_{k + 1}_" if k else "") + "measured_mm": gap for k, gap in enumerate(gaps)}
    bad = [k + 1 for k, gap in enumerate(gaps) if not abs(gap - x.gap0_mm) <= PLANAR_TOL_MM]
    note = "pocket floor - (slot floor + board + chip/2)"
    if len(gaps) > 1:
        note += f", under each of {len(gaps)} chips" + (f"; off under chip {', '.join(map(str, bad))}" if bad else "")
    return Check(
        "magnet_chip_gap",
        not bad,
        ", ".join(f"{gap:.4f}" for gap in gaps) + " mm",
        f"{x.gap0_mm:.4f} mm (forward model gap0)",
        note,
        values=values,
    )


def check_overhang(m: Measurements, x: Manifest) -> Check:
    """No down-facing face flatter than the limit: it would need support or a bridge."""
    incl = m.down_inclination_deg
    steep = incl < OVERHANG_LIMIT_DEG - 1e-3
    worst = float(incl.min()) if incl.size else 90.0
    below = float(m.down_area_mm2[steep].sum())
    return Check(
        "overhang",
        not steep.any(),
        f"min {worst:.2f} deg, {below:.3f} mm2 below",
        f">= {OVERHANG_LIMIT_DEG:g} deg from horizontal for every down-facing face",
        "in print orientation: nothing needs support or a bridge",
        values={"min_inclination_deg": worst, "area_below_limit_mm2": below},
    )


def _off_grid(z_mm: float, layer_height_mm: float) -> bool:
    return abs(z_mm / layer_height_mm - round(z_mm / layer_height_mm)) * layer_height_mm > LAYER_GRID_TOL_MM


def check_layer_grid(m: Measurements, x: Manifest) -> Check:
    lh = x.print.layer_height_mm
    heights = m.flat_heights_mm
    off = [float(z) for z in heights if _off_grid(z, lh)]
    return Check(
        "layer_grid",
        not off,
        f"{len(heights)} heights, {len(off)} off the grid",
        f"every horizontal face on a multiple of {lh:g} mm",
        ("off: " + ", ".join(f"{z:.4f}" for z in off[:5]))
        if off
        else "the slicer prints every horizontal face where it was designed",
        values={"heights_mm": heights.tolist(), "off_grid_mm": off},
    )


def check_magnet_pause(m: Measurements, x: Manifest) -> Check:
    """The pause on a layer boundary, above the magnet, at or below where the roof starts."""
    pr, lh = x.print, x.print.layer_height_mm
    pause, z_pause = pr.pause, pr.pause.z_mm
    # the roof starts its rise below the ridge
    roof_start = m.pocket.ridge_z_mm - x.magnet_pocket.roof_rise_mm
    ok = (
        not _off_grid(z_pause, lh)
        and pause.after_layer == round(z_pause / lh)
        and pr.magnet_top_z_mm <= z_pause + 1e-9
        and roof_start >= z_pause - PLANAR_TOL_MM
    )
    return Check(
        "magnet_pause",
        ok,
        f"roof starts at z {roof_start:.3f} mm",
        f"pause after layer {pause.after_layer} at z {z_pause:.2f} mm, magnet top {pr.magnet_top_z_mm:.2f} mm",
        f"pause after layer {pause.after_layer} (z = {z_pause:.2f} mm) to drop the magnet in",
        values={"roof_start_z_mm": roof_start, "pause_z_mm": z_pause},
    )


def check_insert_slot(m: Measurements, x: Manifest) -> Check:
    """The insert's slot where export.json declares it (width, floor, thickness, the gable's
    ridge) and its pause at the slot's top, on the grid, above the plate (info without one)."""
    part = x.insert
    if part is None or part.sensor_slot_min_mm is None or part.sensor_slot_max_mm is None:
        return Check("insert_slot", True, "no insert", "no insert", "", info=True)
    lo, hi = np.asarray(part.sensor_slot_min_mm), np.array(part.sensor_slot_max_mm)
    hi[1] += part.slot_roof_rise_mm or 0.0  # along y the ray ends at the ridge
    got_lo, got_hi = np.asarray(m.insert_slot.lo_mm), np.asarray(m.insert_slot.hi_mm)
    err = float(np.max(np.abs(np.concatenate([got_lo - lo, got_hi - hi]))))
    pause, lh = part.placed_at_pause, x.print.layer_height_mm
    z_top = part.sensor_slot_max_mm[1] + 0.5 * x.print.height_mm  # the slot's top, print height
    pause_ok = not _off_grid(pause.z_mm, lh) and pause.after_layer == round(pause.z_mm / lh)
    pause_ok &= abs(pause.z_mm - z_top) < 1e-6 and part.sensor_box_max_mm[1] + 0.5 * x.print.height_mm <= pause.z_mm
    return Check(
        "insert_slot",
        bool(err <= PLANAR_TOL_MM and pause_ok),
        _insert_slot_text(got_lo, got_hi),
        _insert_slot_text(lo, hi) + f"; pause z {pause.z_mm:.2f}",
        f"the plate drops in at the pause after layer {pause.after_layer} (z = {pause.z_mm:.2f} mm)",
        values={"largest_error_mm": err, "pause_z_mm": pause.z_mm, "pause_ok": bool(pause_ok)},
    )


def _insert_slot_text(lo: np.ndarray, hi: np.ndarray) -> str:
    return f"{hi[0] - lo[0]:.3f} x {hi[2] - lo[2]:.3f} mm, floor y {lo[1]:.3f}, ridge y {hi[1]:.3f}"


CHECKS = (
    check_watertight,
    check_is_volume,
    check_manifold3d,
    check_one_body,
    check_volume,
    check_bbox,
    check_wall_thickness,
    check_web_depth,
    check_cavity_gap,
    check_magnet_pocket,
    check_board_slot,
    check_footprint,
    check_magnet_chip_gap,
    check_overhang,
    check_layer_grid,
    check_magnet_pause,
    check_insert_slot,
    check_load_path,
)


def run_checks(
    mesh: Mesh | Any, manifest: Manifest | dict, nozzle_mm: float | None = None, load_path_max: float | None = None
) -> list[Check]:
    """Every check of :data:`CHECKS`, in order. Pure: reads only its arguments.

    ``mesh`` is the STL as written (print orientation); ``manifest`` the loaded export.json
    (a dict, as :func:`~mst_cli.cad.manifest.export_manifest` returns it, is validated first);
    ``nozzle_mm`` overrides the design's nozzle for the wall check; ``load_path_max`` bounds the
    share of the magnet's motion outside the layers (:func:`check_load_path`)."""
    if not isinstance(manifest, Manifest):
        manifest = Manifest.from_dict(manifest)
    if nozzle_mm is not None:
        manifest = replace(manifest, printer=replace(manifest.printer, nozzle_mm=float(nozzle_mm)))
    measured = measure(mesh, manifest)
    bounds: dict[Any, dict] = {check_load_path: {"share_max": load_path_max}}
    return [check(measured, manifest, **bounds.get(check, {})) for check in CHECKS]


def results_dict(checks: list[Check], stl_path: str) -> dict:
    """JSON form (``mst check --json``); a value that could not be measured (NaN) is null."""

    failed = [c.name for c in checks if not c.passed and not c.info]
    return finite_or_none(
        {"path": stl_path, "passed": not failed, "failed": failed, "checks": [asdict(c) for c in checks]}
    )


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


class CheckResults(list[Check]):
    """:func:`mst_cli.api.check`'s answer: the checks in report order (a list) and the mesh they
    measured, with the two forms ``mst check`` prints."""

    def __init__(self, checks: list[Check], stl: Path):
        super().__init__(checks)
        self.stl = stl

    @property
    def failed(self) -> list[str]:
        """Names of the checks that failed (an info check never fails)."""
        return [c.name for c in self if not c.passed and not c.info]

    def to_dict(self) -> dict:
        """``mst check --json``'s form (:func:`results_dict`)."""
        return results_dict(self, str(self.stl))

    def table(self) -> str:
        """``mst check``'s terminal table (:func:`results_table`)."""
        return results_table(self)
