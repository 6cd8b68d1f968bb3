"""mst from Python: the command line's verbs as functions (``from mst_cli import api as mst``).

Each function takes the options of its command (same names, same defaults, same checks: bad
input raises :class:`~mst_cli.errors.InputError` naming the field, the value and what is
allowed) and returns the typed object the command prints and writes from. Units are in the
names: mm, N, MPa, degrees, T (tesla) in arrays, mT/uT where the name says so.

Each verb imports its own modules when it is called (``import mst_cli`` loads none of them), as
the command line loads only the command it runs: a script that calibrates does not pay for the
design solver or the CAD kernel.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, cast

from mst_cli.errors import InputError

if TYPE_CHECKING:
    from mst_cli.cad.checks import Check
    from mst_cli.cad.manifest import Manifest
    from mst_cli.cad.slicing import SliceResult
    from mst_cli.calibrate.calibration import Calibration
    from mst_cli.calibrate.reading import ForceReadings, SerialSamples
    from mst_cli.design.document import DesignResult
    from mst_cli.design.pareto import ParetoDesign
    from mst_cli.model.offcentre import OffCentreResponse, OffsetMap
    from mst_cli.model.response import Response
    from mst_cli.sensor.document import Document

__all__ = [
    "InputError",
    "load",
    "load_design",
    "simulate",
    "simulate_offcentre",
    "offset_map",
    "design",
    "pareto",
    "designed",
    "export",
    "check",
    "slice",
    "parse_params",
    "calibrate",
    "read",
    "read_serial",
]


def __getattr__(name: str):
    # the verbs' own error classes (CalibrationFailed: a fit failed; SlicerError: PrusaSlicer
    # misbehaved), without importing their modules before they are asked for
    if name == "CalibrationFailed":
        # deferred: a verb loads its layer when called ('import mst_cli' stays light)
        from mst_cli.errors import CalibrationFailed

        return CalibrationFailed
    if name == "SlicerError":
        # deferred: a verb loads its layer when called ('import mst_cli' stays light)
        from mst_cli.cad.slicer import SlicerError

        return SlicerError
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _one_of(option: str, value: str | None, allowed: Sequence[str]) -> None:
    """InputError unless ``value`` is None or one of ``allowed`` (click's Choice, for scripts)."""
    if value is not None and value not in allowed:
        raise InputError(option, value, "must be one of " + ", ".join(allowed))


def load(path: str | Path) -> Document:
    """A design or spec file (docs/file-format.md), validated field by field.

    Parameters
    ----------
    path : str or Path
        YAML file: a design (every layer's theta_deg, t_mm, h_mm) or a spec (targets).

    Returns
    -------
    Document
        ``.is_design`` / ``.is_spec`` say which; ``.geometry()`` builds a design's sensor.
    """
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.sensor.document import load_document

    return load_document(path)


def load_design(path: str | Path | Document) -> Document:
    """A design file whose every cell is printable and works (InputError naming the first layer
    that breaks a rule); a Document is checked the same way and returned."""
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.sensor.document import design_geometry, load_design_document

    if isinstance(path, (str, Path)):
        return load_design_document(path)[0]
    design_geometry(path)
    return path


def simulate(
    design: str | Path | Document, *, mechanics: str | None = None, field_model: str | None = None
) -> Response:
    """The forward model of a design (``mst simulate``).

    Parameters
    ----------
    design : str, Path or Document
        A design file (or its Document).
    mechanics : {"spring", "frame", "continuum"}, optional
        Layer mechanics [default: the cheapest rung whose measured error meets the file's
        model.accuracy_rel, else its model.mechanics].
    field_model : {"auto", "dipole", "axial", "cylinder"}, optional
        Magnet field model [default: the file's model.field].

    Returns
    -------
    Response
        ``.force_N`` (m,) in N against ``.displacement_mm``, ``.gap_mm``, ``.B_T`` (m, 3) and
        ``.B_abs_T`` (m,) in T, ``.dB_rel`` (m,); ``.in_range`` (m,) False past the last lock;
        ``.regimes`` with each band's ``sensitivity_secant_per_N`` (S) and ``force_to_N`` (R).
        The part as printed, as the command models it: walls + printer.wall_offset_mm, modulus
        x printer.modulus_factor, gap + printer.gap_offset_mm.
    """
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.model.mechanics import MODELS
    from mst_cli.sensor.as_printed import simulate_as_printed

    _one_of("--mechanics", mechanics, MODELS)
    _one_of("--field-model", field_model, ("auto", "dipole", "axial", "cylinder"))
    return simulate_as_printed(load_design(design), mechanics, field_model)


def simulate_offcentre(
    design: str | Path | Document,
    offset_mm: tuple[float, float],
    *,
    mechanics: str | None = None,
    field_model: str | None = None,
) -> OffCentreResponse:
    """A force pressed at ``offset_mm`` = (x0, y0) on the top face (``mst simulate --load-offset-mm``).

    The part as printed, the mechanics rung as :func:`simulate` picks it, every layer tilting
    with rigid plates (:mod:`mst_cli.model.offcentre`). Returns ``.force_N`` (m,), ``.B_T``
    (m, 3) at the chip, ``.magnet_tilt_deg`` (m, 2), ``.force_read_axial_N`` (what the centred
    model reads from that |B|), ``.read_error_N``, ``.side_lock_N`` (n, 2) and ``.axial`` (the
    centred :class:`Response`). InputError for an offset off the top face.
    """
    from mst_cli.model.offcentre import simulate_offcentre as run  # deferred: as simulate's

    geometry, material, mech, field_choice = _printed_scene(design, mechanics, field_model)
    _on_top_face(geometry, offset_mm)
    return run(geometry, material, offset_mm, mech, field_choice)


def offset_map(
    design: str | Path | Document,
    *,
    mechanics: str | None = None,
    field_model: str | None = None,
    region_mm: tuple[float, float] | None = None,
) -> OffsetMap:
    """The axial reading's relative force error over 80 % of the top face (or +-``region_mm``,
    half extents in mm), at 25, 50 and 75 % of every regime's force band (``mst simulate
    --offset-map``)."""
    from mst_cli.model.offcentre import offset_map as run  # deferred: as simulate's

    geometry, material, mech, field_choice = _printed_scene(design, mechanics, field_model)
    return run(geometry, material, mech, field_choice, region_mm=region_mm)


def _printed_scene(design, mechanics, field_model):
    """(geometry as printed, material as printed, mechanics rung, field model or None for auto)."""
    # deferred: as simulate's
    from mst_cli.model.ladder import choose_mechanics
    from mst_cli.model.mechanics import MODELS
    from mst_cli.sensor.as_printed import as_printed

    _one_of("--mechanics", mechanics, MODELS)
    _one_of("--field-model", field_model, ("auto", "dipole", "axial", "cylinder"))
    doc = load_design(design)
    printed = as_printed(doc)
    choice = field_model or doc.field_model
    if choice == "dipole":
        raise InputError("--field-model", choice, "must be exact off the axis: axial, cylinder or auto")
    mech = choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics).mechanics
    return printed.geometry(), printed.material, mech, None if choice == "auto" else choice


def _on_top_face(geometry, offset_mm) -> None:
    """InputError unless (x0, y0) lies on the top face, |x0| <= W/2 and |y0| <= D/2."""
    half_w, half_d = 0.5 * geometry.width_mm, 0.5 * geometry.depth_mm
    x0, y0 = offset_mm
    if not (abs(x0) <= half_w and abs(y0) <= half_d):
        raise InputError(
            "--load-offset-mm",
            f"{x0:g},{y0:g}",
            f"must lie on the top face: |x| <= {half_w:g} mm, |y| <= {half_d:g} mm",
        )


def design(
    spec: str | Path | Document,
    *,
    seed: int | None = None,
    max_evaluations: int | None = None,
    refine: str | None = None,
    calibration: str | Path | None = None,
    progress: Callable | None = None,
) -> DesignResult:
    """Inverse design from target S_i and R_i to theta, t, h per layer (``mst design``).

    Parameters
    ----------
    spec : str, Path or Document
        A spec file (per layer target_sensitivity_per_N and target_range_N).
    seed : int, optional
        Same spec and seed give the same design.
    max_evaluations : int, optional
        The solver's budget of forward-model evaluations.
    refine : {"frame", "continuum"}, optional
        Polish the L0 optimum for a dearer model by space mapping (default: the spec's
        model.accuracy_rel pick, else model.mechanics if not spring).
    calibration : str or Path, optional
        An earlier print's calibration.json: its fitted wall offset, modulus factor, gap offset
        and remanence go into the spec's ``printer`` keys and magnet (held ones are not used).
    progress : callable(done, total, phase, worst_error_rel), optional
        Called as the solver spends its budget.

    Returns
    -------
    DesignResult
        ``.document`` (the design), ``.geometry``, ``.response`` (the forward model on it),
        ``.status`` ("met" / "not met", ``.binding`` and ``.reasons`` say why), ``.targets``
        (per layer target against achieved), ``.table()``, ``.design_yaml_dict()``.
    """
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.design import design_document
    from mst_cli.model.ladder import choose_mechanics

    _one_of("--refine", refine, ("frame", "continuum"))
    doc = load(spec) if isinstance(spec, (str, Path)) else spec
    if calibration is not None:
        # deferred: a verb loads its layer when called ('import mst_cli' stays light)
        from mst_cli.calibrate.calibration_json import apply_calibration, read_calibration

        doc = apply_calibration(doc, read_calibration(calibration, doc))
    choice = choose_mechanics(refine, doc.accuracy_rel, doc.mechanics)
    if choice.mechanics == "spring":
        result = design_document(
            replace(doc, mechanics="spring"), seed=seed, max_evaluations=max_evaluations, progress=progress
        )
    else:
        # deferred: a verb loads its layer when called ('import mst_cli' stays light)
        from mst_cli.design.refine import refine_document

        result = refine_document(doc, choice.mechanics, seed=seed, max_evaluations=max_evaluations, progress=progress)
    return _with_offcentre_figure(result, doc.design.get("offcentre_region_mm"))


def _with_offcentre_figure(result: DesignResult, region: Sequence[float] | None) -> DesignResult:
    """``result`` with design.offcentre_region_mm's figure filled in (when the spec sets one)."""
    if region is not None:
        from mst_cli.model.offcentre import worst_read_errors  # deferred: as simulate's

        omap = offset_map(result.document, mechanics=result.response.mechanics, region_mm=(region[0], region[1]))
        result.off_centre = worst_read_errors(omap) | {"mechanics": result.response.mechanics}
    return result


def pareto(
    spec: str | Path | Document,
    count: int,
    *,
    seed: int | None = None,
    max_evaluations: int | None = None,
    progress: Callable | None = None,
) -> tuple[DesignResult, list[ParetoDesign]]:
    """The trade among designs that meet every target (``mst design --pareto N``), mapped with
    L0 (the spring rung) whatever the spec's model section asks.

    Returns
    -------
    (DesignResult, list of ParetoDesign)
        The chosen design (design.objective's weights) and up to ``count`` non-dominated
        designs, each with ``.height_mm``, ``.worst_force_resolution_N``,
        ``.print_robustness_rms`` and its ``.result``.
    """
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.design.pareto import pareto_front

    if not 2 <= count <= 60:
        raise InputError("--pareto", count, "must be an integer from 2 to 60")
    doc = load(spec) if isinstance(spec, (str, Path)) else spec
    return pareto_front(
        replace(doc, mechanics="spring"), count, seed=seed, max_evaluations=max_evaluations, progress=progress
    )


def designed(path: str | Path, progress: Callable[[str], None] | None = None) -> tuple[Document, DesignResult | None]:
    """A design file as it is, or a spec designed first (as ``mst export SPEC`` does): the
    design's Document and, for a spec, the DesignResult it came from. InputError when a cell
    breaks a rule."""
    doc = load(path)
    if doc.is_design:
        return load_design(path), None
    if not doc.is_spec:
        doc.require_geometry()  # names the first missing key
    if progress is not None:
        progress(f"{path} is a spec: designing theta, t, h first (as 'mst design' does)")
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.design import design_document

    result = design_document(doc)
    geometry = result.geometry
    for v in geometry.violations(result.document.printer):
        raise v.input_error("the designed cell is invalid")
    if progress is not None:
        progress(f"designed: targets {result.status}")
    return result.document, result


def export(
    design: str | Path | Document,
    out: str | Path,
    *,
    stl: bool = True,
    three_mf: bool = False,
    step: bool = False,
    stl_tolerance_mm: float = 0.01,
    progress: Callable[[str], None] | None = None,
) -> list[Path]:
    """The printable body of a design (a spec is designed first) into ``out`` (``mst export``).

    Parameters
    ----------
    design : str, Path or Document
        A design or spec file, or a design's Document.
    out : str or Path
        Folder for sensor.stl / sensor.3mf (print orientation: lying on its side, mm),
        sensor.step (sensor frame) and export.json (the design's expected dimensions).
    stl_tolerance_mm : float
        Largest chord deviation of the mesh from the curved surfaces, mm (1e-4 to 1).

    Returns
    -------
    list of Path
        The files written, export.json last.
    """
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.cad.exporting import check_stl_tolerance, write_export

    check_stl_tolerance(stl_tolerance_mm)
    if isinstance(design, (str, Path)):
        doc, result = designed(design, progress)
    else:
        doc, result = load_design(design), None
    names = write_export(
        doc,
        doc.geometry(),
        Path(out),
        stl=stl,
        step=step,
        three_mf=three_mf,
        stl_tolerance_mm=stl_tolerance_mm,
        design_yaml=result.design_yaml_dict() if result is not None else None,
        progress=progress,
    )
    return [Path(out) / n for n in names]


def check(path: str | Path, *, nozzle_mm: float | None = None) -> list[Check]:
    """Measure an exported mesh against its export.json (``mst check``).

    Parameters
    ----------
    path : str or Path
        The folder ``export`` wrote, or the .stl in it.
    nozzle_mm : float, optional
        Nozzle diameter for the wall checks [default: the design's printer.nozzle_mm].

    Returns
    -------
    list of Check
        One per check, in report order: ``.name``, ``.passed``, ``.measured`` and
        ``.expected`` (text with units), ``.note``, ``.values`` (numbers, units in the keys).
    """
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.cad.checks import load_mesh, resolve_export, run_checks
    from mst_cli.cad.manifest import load_manifest
    from mst_cli.model.printer import Printer

    if nozzle_mm is not None:  # one bound: printer.nozzle_mm's in a design file
        lo, hi = next((f.metadata["lo"], f.metadata["hi"]) for f in fields(Printer) if f.name == "nozzle_mm")
        if not lo <= nozzle_mm <= hi:
            raise InputError("--nozzle", nozzle_mm, f"must be a nozzle diameter from {lo:g} to {hi:g} mm")
    found = resolve_export(path)
    # both inputs are validated before anything is measured: every field the checks read (type,
    # nesting, finite and sane size) and every STL coordinate (finite, within a metre). Past
    # this point a KeyError or TypeError is a bug in a check, not bad input.
    manifest = cast("Manifest", load_manifest(found.manifest))  # kind=Manifest by default
    assert found.stl is not None  # resolve_export found one (need_stl)
    return run_checks(load_mesh(found.stl), manifest, nozzle_mm)


def slice(
    path: str | Path,
    *,
    profile: str | Path | None = None,
    out: str | Path | None = None,
    max_span_mm: float = 5.0,
    plot: bool = False,
    progress: Callable[[str], None] | None = None,
    note: Callable[[str], None] | None = None,
    allow_post_process: bool = False,
) -> SliceResult:
    """Slice an export with PrusaSlicer and judge whether it prints (``mst slice``; the
    command's name, so it shadows the builtin ``slice`` inside this module, which never uses it).

    Parameters
    ----------
    path : str or Path
        The folder ``export`` wrote (sensor.3mf, else sensor.stl, and export.json).
    profile : str or Path, optional
        PrusaSlicer config [default: the bundled TPU 85A profile].
    out : str or Path, optional
        Folder for sensor.gcode, slice.json and (``plot``) print.png [default: ``path``].
    max_span_mm : float
        Longest free span allowed (extrusion with nothing under it), mm.
    allow_post_process : bool
        Let PrusaSlicer run the scripts the profile's ``post_process`` names [default: False:
        such a profile is refused (InputError) before anything is sliced or written].

    Returns
    -------
    SliceResult
        ``.report`` (slice.json: print time s, filament g, layers, the longest free span mm,
        the pause found against the one asked for, support, cavity gaps mm), ``.checks``,
        ``.failed`` (names of the broken limits), ``.summary()``.
    """
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.cad.slicing import slice_export

    result = slice_export(path, profile, max_span_mm, progress, note, allow_post_process)
    result.write(Path(out) if out is not None else None, plot=plot)
    return result


def parse_params(text: str) -> tuple[str, ...]:
    """The parameter names of ``--params`` ("modulus_factor,gap_offset_mm")."""
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.calibrate.calibration import parse_params as parse

    return parse(text)


def calibrate(
    design: str | Path | Document,
    load_test: str | Path,
    *,
    out: str | Path | None = None,
    plot: bool = False,
    design_file: str | Path | None = None,
    mechanics: str = "spring",
    params: Sequence[str] | str | None = None,
    gain_sel: int | None = None,
    res: int | None = None,
    table_size: int = 256,
    progress: Callable[[str], None] | None = None,
) -> Calibration:
    """Fit a design's print parameters to a load test of the printed sensor (``mst calibrate``).

    Parameters
    ----------
    design : str, Path or Document
        The design file the sensor was printed from (a Document: ``design_file`` names it).
    load_test : str or Path
        CSV, one row per sample: force_N (N) and Bx_uT, By_uT, Bz_uT (uT), or Bx_code_lsb,
        By_code_lsb, Bz_code_lsb (raw LSB, with ``gain_sel`` and ``res``).
    out : str or Path, optional
        Folder for calibrated.yaml, calibration.json, residuals.csv, lookup.csv, force_table.h
        and (``plot``) calibration.png, written atomically [default: none written].
    mechanics : {"spring", "frame", "continuum"}
        Layer mechanics of the fit; frame and continuum by space mapping on spring.
    params : sequence of str or str, optional
        Parameters to fit (of :data:`mst_cli.sensor.as_printed.PARAMETERS`, or "a,b") [default: all four].
    gain_sel, res, table_size : int, optional
        The MLX90393 setting the load test was read at (0-7, 0-3); entries of lookup.csv (16-4096).

    Returns
    -------
    Calibration
        ``.fit.values`` (units in the names) and ``.fit.std`` (1 sigma), ``.calibrated`` (the
        design as printed), ``.inverse_map`` (|B| T -> force N), ``.record`` (calibration.json),
        ``.summary()``. Raises InputError (bad file or option) or CalibrationFailed (why).
    """
    from mst_cli.calibrate.calibration import calibrate as run_calibration  # deferred: loads its layer when called

    params = _checked_fit_options(mechanics, params, table_size)
    doc = load_design(design)
    _check_out(out)  # a bad output path is refused before any work
    result = run_calibration(
        doc,
        design_file or (design if isinstance(design, (str, Path)) else design.name),
        load_test,
        mechanics=mechanics,
        params=params,
        gain_sel=gain_sel,
        res=res,
        table_size=table_size,
        progress=progress,
    )
    if out is not None:
        result.write(Path(out), plot=plot)
    return result


def _check_out(out: str | Path | None) -> None:
    """InputError when ``out`` (unless None) cannot be an output folder."""
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.io.outputs import check_out_dir

    if out is not None:
        check_out_dir(Path(out))


def _checked_fit_options(mechanics: str, params: Sequence[str] | str | None, table_size: int) -> tuple[str, ...]:
    """The parameter names to fit, after the rules of --mechanics, --params (known names, each
    once) and --table-size."""
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.calibrate.fit import DEFAULT_PARAMETERS
    from mst_cli.model.mechanics import MODELS

    _one_of("--mechanics", mechanics, MODELS)
    if params is None:
        names = DEFAULT_PARAMETERS
    else:
        names = parse_params(params if isinstance(params, str) else ",".join(params))
    if not 16 <= table_size <= 4096:
        raise InputError("--table-size", table_size, "must be an integer from 16 to 4096")
    return names


def _reader(
    design: str | Path | Document,
    model_file: str | Path | None,
    mechanics: str | None,
    gain_sel: int | None,
    res: int | None,
    raw: bool,
    readings: str | Path | None,
    out: str | Path | None,
    warn: Callable[[str], None] | None,
):
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.calibrate.loadtest import parse_readings, read_text, setting_of
    from mst_cli.calibrate.reading import ForceReader
    from mst_cli.model.ladder import choose_mechanics
    from mst_cli.model.mechanics import MODELS

    _one_of("--mechanics", mechanics, MODELS)
    doc = load_design(design)
    if model_file is None:
        if not isinstance(design, (str, Path)):
            raise InputError(
                "model_file", None, "name the file the Document was loaded from (its calibration.json stands beside it)"
            )
        model_file = design
    if (gain_sel is None) != (res is None):
        raise InputError("--gain-sel/--res", f"{gain_sel}/{res}", "give both GAIN_SEL and RES, or neither")
    setting = setting_of(gain_sel, res) if gain_sel is not None and res is not None else None
    if raw and setting is None:
        raise InputError("--gain-sel/--res", None, "--raw codes need the chip setting: give --gain-sel and --res")
    _check_out(out)
    choice = choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics)
    rd = None
    if readings is not None:
        rd = parse_readings(read_text(readings), str(readings), need_force=False, gain_sel=gain_sel, res=res)
        if len(rd) == 0:
            raise InputError(str(readings), "(no rows)", "has a header but no readings")
        setting = setting or rd.setting
    reader = ForceReader.open(doc, model_file, choice.mechanics, setting)
    if reader.warning and warn is not None:
        warn(reader.warning)
    return reader, rd, setting


def read(
    model: str | Path | Document,
    readings: str | Path,
    *,
    out: str | Path | None = None,
    model_file: str | Path | None = None,
    mechanics: str | None = None,
    gain_sel: int | None = None,
    res: int | None = None,
    warn: Callable[[str], None] | None = None,
    estimate_offset: bool = False,
    max_offset_sigma_mm: float = 1.0,
) -> ForceReadings:
    """MLX90393 readings to forces with a calibrated model (``mst read READINGS.csv``).

    Parameters
    ----------
    model : str, Path or Document
        calibrated.yaml (or any design file: then forces are the design's, not the print's, and
        ``warn`` is told so).
    readings : str or Path
        CSV with Bx_uT, By_uT, Bz_uT (or raw codes with ``gain_sel``/``res``); a force_N column
        is kept as the reference the summary compares with.
    out : str or Path, optional
        Folder to write forces.csv into.
    warn : callable, optional
        Gets a sentence when the model has no matching calibration.json beside it, or when the
        model no longer gives the curve recorded at calibration.
    estimate_offset : bool
        Estimate where each reading was pressed from Bx, By, Bz (the tilt rung's inverse) and
        correct its force; ``.offset`` holds x, y and their 1-sigma, and a reading whose press
        the data cannot tell keeps the centred force, flagged (``.offset.flag``):
        not_identifiable (offset less certain than ``max_offset_sigma_mm``), ambiguous (two
        presses give it) or no_fit (none does); about 0.3 s a reading.

    Returns
    -------
    ForceReadings
        ``.force_N`` (n,) in N, NaN where flagged (never extrapolated); ``.regime`` (n,),
        ``.flag`` (n,) one of ok, above_calibrated, below_range, above_range, saturated;
        ``.force_resolution_N`` (n,); ``.summary()``, ``.csv()``.
    """
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.io.outputs import staged

    if not (max_offset_sigma_mm > 0 and math.isfinite(max_offset_sigma_mm)):
        raise InputError("--max-offset-sigma-mm", max_offset_sigma_mm, "must be a positive number of mm")
    reader, rd, _ = _reader(model, model_file, mechanics, gain_sel, res, False, readings, out, warn)
    offsets = None
    if estimate_offset:
        from mst_cli.model.ladder import choose_mechanics  # deferred: as _reader's

        mech = choose_mechanics(mechanics, reader.document.accuracy_rel, reader.document.mechanics).mechanics
        offsets = reader.offset_estimator(mech, max_offset_sigma_mm)
    result = reader.read(rd, offsets)
    if out is not None:
        with staged(Path(out)) as st:
            st.write_text("forces.csv", result.csv())
    return result


def read_serial(
    model: str | Path | Document,
    port: str,
    *,
    out: str | Path | None = None,
    model_file: str | Path | None = None,
    baud: int = 115200,
    count: int | None = None,
    timeout_s: float | None = None,
    raw: bool = False,
    mechanics: str | None = None,
    gain_sel: int | None = None,
    res: int | None = None,
    warn: Callable[[str], None] | None = None,
    status: Callable[[str], None] | None = None,
    show: Callable[[str], None] = print,
) -> SerialSamples:
    """A live MLX90393 stream to forces (``mst read --serial PORT``): one line per sample goes to
    ``show``; stops when the port closes, after ``count`` samples, ``timeout_s`` seconds of
    silence or Ctrl-C; ``status`` gets a line when reading starts. ``out``: forces.csv of every
    sample (time s, the three values, force N, regime, flag, resolution N)."""
    # deferred: a verb loads its layer when called ('import mst_cli' stays light)
    from mst_cli.io.outputs import staged

    reader, _, setting = _reader(model, model_file, mechanics, gain_sel, res, raw, None, out, warn)
    if status is not None:
        status(f"{reader.document.name}: reading {port} at {baud} baud (Ctrl-C to stop)")
    samples = reader.stream(port, baud, count, timeout_s, raw, setting, show)
    if out is not None:
        with staged(Path(out)) as st:
            st.write_text("forces.csv", samples.csv(reader.inverse_map))
    return samples
