"""One ``mst slice`` run: the export sliced with PrusaSlicer twice (as the profile says: the
G-code that is written and measured; and with automatic support on, to prove none would be
generated), judged by :mod:`mst_cli.cad.print_check`, with slice.json, sensor.gcode and
print.png written atomically by :meth:`SliceResult.write`.

PrusaSlicer is run through :mod:`mst_cli.cad.slicer` (looked up on the module at each call, so
a test can stand in for it); the G-code kernels are :mod:`mst_cli.cad.gcode`.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mst_cli.cad import gcode as G
from mst_cli.cad import layer_measure as M
from mst_cli.cad import slicer as S
from mst_cli.cad.checks import Check
from mst_cli.cad.export_files import ExportFiles, resolve_export
from mst_cli.cad.manifest import SliceManifest, load_manifest
from mst_cli.cad.print_check import (
    cavity_gaps,
    check_free_span,
    check_pause,
    check_support,
    pause_text,
    walls_as_sliced,
)
from mst_cli.cad.print_plot import plot_print
from mst_cli.cad.sliced_model import predict
from mst_cli.errors import InputError
from mst_cli.io.outputs import finite_or_none, staged

DEFAULT_MAX_SPAN_MM = 5.0
GCODE_FILE, REPORT_FILE, PLOT_FILE = "sensor.gcode", "slice.json", "print.png"


def fmt_duration(seconds: float | None) -> str:
    """'1h 24m 05s' or '3m 07s' ('unknown' for None)."""
    if seconds is None:
        return "unknown"
    s = int(round(seconds))
    return f"{s // 3600}h {s % 3600 // 60:02d}m {s % 60:02d}s" if s >= 3600 else f"{s // 60}m {s % 60:02d}s"


def _number(text: str | None, default: float) -> float:
    if text is None:
        return default
    try:
        return float(text)
    except (TypeError, ValueError):
        return default


@dataclass
class SliceResult:
    """A sliced export: slice.json's content (``report``), the G-code and the Checks it came from."""

    report: dict
    gcode_text: str
    checks: list[Check]  # free_span, pause, support, cavity_gaps (info)
    folder: Path  # the export's folder (the default output folder)
    triangles: np.ndarray  # (n, 3, 3) the mesh sliced, print frame, mm
    bed_centre_mm: tuple[float, float]
    shift_xyz_mm: tuple[float, float, float]  # G-code = print frame + shift
    gcode: G.GCode
    spans: M.SpanReport
    written: tuple[str, ...] = ()  # the files :meth:`write` wrote

    @property
    def failed(self) -> list[str]:
        return self.report["failed"]

    def write(self, out: Path | None = None, plot: bool = True) -> list[str]:
        """sensor.gcode, slice.json and (``plot``) print.png into ``out`` (default: the export's
        folder), atomically; without ``plot`` an old print.png is removed. The names written."""
        names = (GCODE_FILE, REPORT_FILE) + ((PLOT_FILE,) if plot else ())
        with staged(out or self.folder) as st:
            st.write_text(GCODE_FILE, self.gcode_text)
            st.write_json(REPORT_FILE, self.report)
            if plot:
                plot_print(
                    st.path(PLOT_FILE),
                    self.triangles,
                    self.bed_centre_mm,
                    self.shift_xyz_mm,
                    self.gcode,
                    self.spans,
                    str(self.report["name"] or self.folder.name),
                )
            else:
                st.remove(PLOT_FILE)
        self.written = names
        return list(names)

    def summary(self) -> str:
        return summary_table(self.report)


def slice_export(
    path: str | Path,
    profile: str | Path | None = None,
    max_span_mm: float = DEFAULT_MAX_SPAN_MM,
    progress: Callable[[str], None] | None = None,
    note: Callable[[str], None] | None = None,
    allow_post_process: bool = False,
) -> SliceResult:
    """Slice the export at ``path`` (its folder, or a mesh in it) with ``profile`` (default: the
    bundled TPU 85A one) and judge it. InputError for bad input (checked before slicing), and for
    a profile whose post_process names scripts unless ``allow_post_process`` (PrusaSlicer would
    run them); SlicerError when PrusaSlicer misbehaves. ``progress`` gets a line per step,
    ``note`` the profile's post_process scripts when they run."""
    say = progress or (lambda message: None)
    if not 0 < max_span_mm <= 1000:
        raise InputError("--max-span", max_span_mm, "must be a length from 0 to 1000 mm")
    job = _SliceJob.prepare(path, profile, note, say, allow_post_process)
    sliced = _slice_twice(job, say)
    g = sliced.gcode
    spans = M.free_spans(g)
    joined = M.free_spans(g, join_moves=True)
    say("measured the free spans")
    layer_h = _number(job.settings.get("layer_height"), g.layers[min(1, len(g.layers) - 1)].height_mm)
    if not (isinstance(layer_h, float) and math.isfinite(layer_h) and layer_h > 0):
        raise S.SlicerError(f"prusa-slicer wrote G-code with a layer height of {layer_h} mm")
    checks = [
        check_free_span(spans, joined, max_span_mm, job.shift_xy),
        check_pause(g.pauses, job.manifest, layer_h),
        check_support(sliced.with_support),
        cavity_gaps(g, job.manifest, job.shift_xy, job.z_shift),
        walls_as_sliced(g, job.manifest, job.shift_xy, job.z_shift),
    ]
    report = _report(job, sliced, checks, layer_h, say)
    shift = (job.shift_xy[0], job.shift_xy[1], job.z_shift)
    return SliceResult(
        finite_or_none(report), sliced.text, checks, job.files.folder, job.triangles, job.centre, shift, g, spans
    )


@dataclass
class _SliceJob:
    """What is sliced, checked before any slicing: PrusaSlicer, the profile, the export, its mesh
    and where the mesh goes on the bed (G-code = print frame + shift)."""

    exe: str
    profile: Path
    settings: dict[str, str]
    files: ExportFiles
    manifest: SliceManifest
    scripts: list[str]
    model: Path
    triangles: np.ndarray  # (n, 3, 3) print frame, mm
    version: str
    carries_pause: bool
    centre: tuple[float, float]

    @classmethod
    def prepare(
        cls,
        path: str | Path,
        profile: str | Path | None,
        note: Callable[[str], None] | None,
        say: Callable[[str], None],
        allow_post_process: bool = False,
    ) -> _SliceJob:
        exe = S.find_prusa_slicer()
        profile = Path(profile) if profile is not None else S.bundled_profile()
        settings = S.check_profile(profile, exe)
        files = resolve_export(path, need_stl=False)
        manifest = load_manifest(files.manifest, SliceManifest)  # before any slicing: exit 2 naming the key
        scripts = S.post_process_scripts(settings)
        if scripts and not allow_post_process:  # a profile's scripts run only with the user's consent
            raise InputError(
                "--profile",
                str(profile),
                f"its post_process would make PrusaSlicer run {', '.join(map(repr, scripts))} on the "
                "G-code: give --allow-post-process to run the profile's scripts, or remove them from it",
            )
        if scripts and note is not None:
            note(
                f"the profile's post_process runs {', '.join(map(repr, scripts))} on each G-code "
                "(your script; what is measured is its output)"
            )
        model = files.three_mf or files.stl
        assert model is not None  # resolve_export found one of them
        triangles = S.read_stl(files.stl) if files.stl is not None else S.read_3mf(model)
        if len(triangles) == 0:
            raise InputError("PATH", str(model), "holds no triangles: run 'mst export' again")
        version = S.slicer_version(exe)
        say(f"{version} at {exe}; profile {profile}")
        carries_pause = bool(files.three_mf is not None and S.has_prusa_pause(files.three_mf))
        if files.three_mf is not None and not carries_pause:
            say(f"note: {files.three_mf.name} carries no PrusaSlicer pause (an older export)")
        centre = S.bed_centre(settings)
        return cls(exe, profile, settings, files, manifest, scripts, model, triangles, version, carries_pause, centre)

    @property
    def lo(self) -> np.ndarray:
        return self.triangles.reshape(-1, 3).min(0)

    @property
    def hi(self) -> np.ndarray:
        return self.triangles.reshape(-1, 3).max(0)

    @property
    def shift_xy(self) -> tuple[float, float]:
        """G-code x, y minus print frame x, y: the part centred on the bed."""
        lo, hi, centre = self.lo, self.hi, self.centre
        return (centre[0] - (lo[0] + hi[0]) / 2, centre[1] - (lo[1] + hi[1]) / 2)

    @property
    def z_shift(self) -> float:
        return -float(self.lo[2]) + 0.0  # + 0.0: a part already on the bed shifts by 0.0, not -0.0


@dataclass
class _Sliced:
    """The G-code as the profile slices it (text and parsed), the one with automatic support on
    and the seconds the first slicing took."""

    text: str
    gcode: G.GCode
    with_support: G.GCode
    seconds: float


def _slice_twice(job: _SliceJob, say: Callable[[str], None]) -> _Sliced:
    """PrusaSlicer as the profile says, then with automatic support on (to prove none is made)."""
    with tempfile.TemporaryDirectory(prefix="mst-slice-") as tmp:
        run1 = S.slice_model(job.exe, job.model, job.profile, Path(tmp) / GCODE_FILE, job.centre)
        say(f"sliced {job.model.name} in {run1.seconds:.2f} s")
        auto_support = ("--support-material", "--support-material-auto")
        run2 = S.slice_model(job.exe, job.model, job.profile, Path(tmp) / "support.gcode", job.centre, auto_support)
        say(f"sliced again with automatic support in {run2.seconds:.2f} s")
        gtext = S.read_gcode(run1.gcode_path)
        g = G.parse_gcode(gtext)
        gs = G.parse_gcode(S.read_gcode(run2.gcode_path))
    say(f"read {len(g.layers)} layers")
    if not any(lay.of_part().any() for lay in g.layers):
        raise S.SlicerError("prusa-slicer wrote G-code without one extrusion of the part")
    return _Sliced(gtext, g, gs, run1.seconds)


def _frame_residual(job: _SliceJob, g: G.GCode) -> list[float]:
    """How far the part's paths sit inside the shifted mesh's box (x lo, y lo, x hi, y hi), mm:
    a check of the frame (G-code = print frame + shift)."""
    lo, hi, shift = job.lo, job.hi, job.shift_xy
    part = np.concatenate([lay.segments[lay.of_part()] for lay in g.layers])
    gmin = np.minimum(part[:, [0, 1]].min(0), part[:, [2, 3]].min(0))
    gmax = np.maximum(part[:, [0, 1]].max(0), part[:, [2, 3]].max(0))
    return [
        float(gmin[0] - (lo[0] + shift[0])),
        float(gmin[1] - (lo[1] + shift[1])),
        float((hi[0] + shift[0]) - gmax[0]),
        float((hi[1] + shift[1]) - gmax[1]),
    ]


def _report(job: _SliceJob, sliced: _Sliced, checks: list[Check], layer_h: float, say: Callable[[str], None]) -> dict:
    """slice.json's content (non-finite numbers not yet replaced)."""
    g = sliced.gcode
    span_check, pause_check, support_check, gaps, walls = checks
    walls_report = {
        "layers": walls.values["layers"],
        "predicted": _predicted(job.manifest.design, walls.values["layers"]),
    }
    if isinstance(walls_report["predicted"], dict):
        say("simulated the walls as sliced")
    pause_report = dict(
        pause_check.values,
        pause_print_gcode=g.config.get("pause_print_gcode", job.settings.get("pause_print_gcode")),
        model_carries_pause=job.carries_pause,
    )
    shift = job.shift_xy
    failed = [c for c in checks if not c.passed and not c.info]
    return {
        "format": 1,
        "name": job.manifest.name,
        "slicer": job.version,
        "profile": str(job.profile),
        "post_process": job.scripts,
        "post_process_run": job.scripts,  # what ran: they run only with consent (else refused before)
        "model_sliced": job.model.name,
        "slice_time_s": round(sliced.seconds, 3),
        "print_time_s": g.print_time_s,
        "print_time": fmt_duration(g.print_time_s),
        "filament_mm": g.filament_mm,
        "filament_cm3": g.filament_cm3,
        "filament_g": g.filament_g,
        "layers": len(g.layers),
        "layer_height_mm": layer_h,
        "first_layer_height_mm": round(g.layers[0].height_mm, 4),
        "height_mm": round(g.layers[-1].z_mm, 4),
        "frame": {
            "gcode_minus_print_xy_mm": [round(shift[0], 4), round(shift[1], 4)],
            "gcode_minus_print_z_mm": round(job.z_shift, 4),
            "bed_centre_mm": list(job.centre),
            "path_inset_from_bbox_mm": [round(r, 3) for r in _frame_residual(job, g)],
        },
        "free_span": span_check.values,
        "pause": pause_report,
        "support": support_check.values,
        "cavity_gaps": gaps.values["lines"],
        "walls_as_sliced": walls_report,
        "failed": [c.name for c in failed],
        "reasons": [c.note for c in failed],
    }


def _predicted(design, layers) -> dict | str:
    """S_i and R_i as designed and as sliced (:mod:`mst_cli.cad.sliced_model`), or why not."""
    if layers == "not given":
        return "not given: export.json has no print.wall_lines (an older export: run 'mst export' again)"
    if design is None:
        return "not given: export.json has no design (an older export: run 'mst export' again)"
    if len(layers) != len(design.layers) or any(r["sliced_t_mm"] is None for r in layers):
        return "not given: export.json's wall lines do not cover every layer of its design"
    return predict(design, [r["sliced_t_mm"] for r in layers])


def summary_table(r: dict) -> str:
    """The terminal table of a slice.json."""
    lines = [
        f"{r['slicer']}, profile {Path(r['profile']).name}, sliced {r['model_sliced']} in {r['slice_time_s']:.2f} s"
    ]
    fil = (
        f"{r['filament_mm']:.0f} mm, {r['filament_cm3']:.2f} cm3, {r['filament_g']:.2f} g"
        if r["filament_mm"] is not None
        else "unknown"
    )
    lines.append(f"print time        {r['print_time']}; filament {fil}")
    lines.append(
        f"layers            {r['layers']} x {r['layer_height_mm']:g} mm (first "
        f"{r['first_layer_height_mm']:g} mm), height {r['height_mm']:.2f} mm"
    )
    s = r["free_span"]["longest"]
    ok = lambda name: "FAIL" if name in r["failed"] else "ok"  # noqa: E731
    if s is None:
        lines.append("free span         none (one layer)")
    else:
        lines.append(
            f"free span         {s['length_mm']:.2f} mm (max {r['free_span']['max_allowed_mm']:g}) "
            f"at layer {s['layer']}, z {s['z_mm']:.2f} mm, x {s['x_mm']:.2f}, y {s['y_mm']:.2f} "
            f"(print frame), {s['type']}  [{ok('free_span')}]"
        )
    p = r["pause"]
    found = (
        ", ".join(
            f"after layer {f['after_layer']} (z {f['z_mm']:.2f} mm{', mid-layer' if f['mid_layer'] else ''}) "
            f"{f['command']}"
            for f in p["found"]
        )
        or "none"
    )
    exp_s = ", ".join(pause_text(e) for e in p["expected_all"]) or "not given"
    lines.append(f"pause             found {found}; export.json asks {exp_s}  [{ok('pause')}]")
    sup = r["support"]
    support = f"needed: {sup['volume_mm3']:.0f} mm3" if sup["needed"] else "none generated"
    lines.append(f"support           {support}  [{ok('support')}]")
    gaps = r["cavity_gaps"]
    if gaps == "not given":
        lines.append("cavity gaps       not given in export.json")
    else:
        for c in gaps:
            sl = "-" if c.get("sliced_gap_mm") is None else f"{c['sliced_gap_mm']:.2f}"
            dg = c.get("designed_gap_mm")
            lines.append(
                f"cavity gap L{c.get('layer')}     designed {'-' if dg is None else f'{float(dg):.2f}'} mm, "
                f"as sliced {sl} mm (x {c['x_mm']}, z {c['z_mm']})"
            )
    lines += _walls_lines(r.get("walls_as_sliced"))
    return "\n".join(lines)


def _change_text(designed: float | None, sliced: float | None, rel: float | None, unit: str, fmt: str) -> str:
    if designed is None or sliced is None:
        return "-"
    change = "" if rel is None else f" ({100 * rel:+.1f} %)"
    return f"{designed:{fmt}} -> {sliced:{fmt}}{unit}{change}"


def _walls_lines(w: dict | None) -> list[str]:
    """The walls as sliced and their predicted S and R, for the terminal table."""
    if w is None or w["layers"] == "not given":
        return ["walls as sliced   not given in export.json (an older export: run 'mst export' again)"]
    out = []
    for la in w["layers"]:
        walls = ", ".join("-" if x["sliced_t_mm"] is None else f"{x['sliced_t_mm']:.3f}" for x in la["walls"])
        t = "-" if la["sliced_t_mm"] is None else f"{la['sliced_t_mm']:.3f}"
        out.append(
            f"wall L{la['layer']}           designed {la['designed_t_mm']:.3f} mm, as sliced {t} mm "
            f"(walls {walls}; {'/'.join(map(str, la['n_lines']))} line(s) across)"
        )
    p = w["predicted"]
    if isinstance(p, str):
        out.append(f"predicted S, R    {p}")
    elif "error" in p:
        out.append(f"predicted S, R    {p['error']}")
    else:
        for g in p["regimes"]:
            s_text = _change_text(g["S_designed_per_N"], g["S_sliced_per_N"], g["S_change_rel"], " /N", ".4f")
            r_text = _change_text(g["R_designed_N"], g["R_sliced_N"], g["R_change_rel"], " N", ".3f")
            out.append(
                f"predicted regime {g['regime']}  S {s_text}, R {r_text} (designed -> as sliced, {p['mechanics']})"
            )
    return out
