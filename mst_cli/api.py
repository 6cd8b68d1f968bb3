"""mst from Python: the command line's verbs as functions (``from mst_cli import api as mst``).

Each function takes the options of its command (same names, same defaults, same checks: bad
input raises :class:`~mst_cli.errors.InputError` naming the field, the value and what is
allowed) and returns the typed object the command prints and writes from; given ``out=`` it
writes the files the command writes, atomically. Units are in the names: mm, N, MPa, degrees,
T (tesla) in arrays, mT/uT where the name says so.

The command line imports this module, :mod:`mst_cli.errors` and its own modules only: this is
the one door. The layers ``mst simulate`` needs (the sensor, the model, the simulation's files)
are imported here; a verb whose layer costs start-up time ``mst simulate`` should not pay
imports it when called, with the reason and the cost measured (``python -X importtime``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import fields
from pathlib import Path
from typing import TYPE_CHECKING, cast

from mst_cli.errors import CalibrationFailed, InputError
from mst_cli.io.files import is_machine_fault as is_machine_fault
from mst_cli.io.files import os_error_text as os_error_text
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.io.outputs import check_out_dir, staged
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE
from mst_cli.model.ladder import choose_mechanics
from mst_cli.model.mechanics import MODELS
from mst_cli.model.offcentre import OffCentreResponse, OffsetMap
from mst_cli.model.offcentre import offset_map as run_offset_map
from mst_cli.model.offcentre import simulate_offcentre as run_offcentre
from mst_cli.model.printer import Printer
from mst_cli.model.response import Response
from mst_cli.sensor.as_printed import simulate_as_printed
from mst_cli.sensor.document import Document, design_geometry, load_design_document, load_document
from mst_cli.simulation.run import Simulation, check_on_top_face, printed_scene

if TYPE_CHECKING:
    from mst_cli.bench.ladder_bench import BenchResult
    from mst_cli.cad.checks import CheckResults
    from mst_cli.cad.exporting import ExportedFiles
    from mst_cli.cad.manifest import Manifest
    from mst_cli.cad.slicing import SliceResult
    from mst_cli.calibrate.calibration import Calibration
    from mst_cli.calibrate.reading import ForceReadings, SerialSamples
    from mst_cli.design.document import DesignResult
    from mst_cli.design.pareto import ParetoDesign
    from mst_cli.design.run import DesignRun

__all__ = [
    "InputError",
    "CalibrationFailed",
    "load",
    "load_design",
    "simulate",
    "simulate_offcentre",
    "offset_map",
    "run_simulate",
    "design",
    "pareto",
    "run_design",
    "designed",
    "export",
    "check",
    "slice",
    "parse_params",
    "calibrate",
    "read",
    "read_serial",
    "bench",
]
# also here for the command line, which imports nothing else of the package: Interrupted (a
# signal ended a run), SEED_RANGE (--seed's bounds), is_machine_fault and os_error_text
FIELD_MODELS = ("auto", "dipole", "axial", "cylinder")


def __getattr__(name: str):
    # SlicerError (PrusaSlicer misbehaved) without importing the slicer before it is asked for
    if name == "SlicerError":
        from mst_cli.cad.slicer import SlicerError  # deferred: the CAD layer, 30 ms measured

        return SlicerError
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _one_of(option: str, value: str | None, allowed: Sequence[str]) -> None:
    """InputError unless ``value`` is None or one of ``allowed`` (click's Choice, for scripts)."""
    if value is not None and value not in allowed:
        raise InputError(option, value, "must be one of " + ", ".join(allowed))


def _check_out(out: str | Path | None) -> None:
    """InputError when ``out`` (unless None) cannot be an output folder."""
    if out is not None:
        check_out_dir(Path(out))


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

    Raises
    ------
    InputError
        The file is unreadable or a field breaks its rule (named, with what is allowed).

    Examples
    --------
    >>> doc = mst.load("configs/mohammadi2021-forward.yaml")  # doctest: +SKIP
    >>> doc.is_design  # doctest: +SKIP
    True
    """
    return load_document(path)


def load_design(path: str | Path | Document) -> Document:
    """A design file whose every cell is printable and works; a Document is checked the same way.

    Parameters
    ----------
    path : str, Path or Document
        A design file, or a Document loaded earlier.

    Returns
    -------
    Document
        The design, its cells checked.

    Raises
    ------
    InputError
        Naming the first layer that breaks a rule.

    Examples
    --------
    >>> mst.load_design("configs/mohammadi2021-forward.yaml").name  # doctest: +SKIP
    """
    return _design_and_geometry(path)[0]


def _design_and_geometry(design):
    """(a valid design's Document, its sensor as drawn), the file read once."""
    if isinstance(design, (str, Path)):
        return load_design_document(design)
    return design, design_geometry(design)


def simulate(
    design: str | Path | Document,
    *,
    mechanics: str | None = None,
    field_model: str | None = None,
    out: str | Path | None = None,
    plot: bool = True,
) -> Response:
    """The forward model of a design (``mst simulate``).

    The part as printed, as the command models it: walls + printer.wall_offset_mm, modulus
    x printer.modulus_factor, gap + printer.gap_offset_mm.

    Parameters
    ----------
    design : str, Path or Document
        A design file (or its Document).
    mechanics : {"spring", "frame", "continuum"}, optional
        Layer mechanics [default: the cheapest rung whose measured error meets the file's
        model.accuracy_rel, else its model.mechanics].
    field_model : {"auto", "dipole", "axial", "cylinder"}, optional
        Magnet field model [default: the file's model.field].
    out : str or Path, optional
        Folder for report.json, response.csv and (``plot``) response.png, written atomically as
        the command writes them [default: nothing written].
    plot : bool
        Draw response.png (matplotlib) when writing.

    Returns
    -------
    Response
        ``.force_N`` (m,) in N against ``.displacement_mm`` (m,), ``.gap_mm``, ``.B_T`` (m, 3)
        and ``.B_abs_T`` (m,) in T, ``.dB_rel`` (m,); ``.in_range`` (m,) False past the last
        lock; ``.regimes`` with each band's ``sensitivity_secant_per_N`` (S, 1/N) and
        ``force_to_N`` (R, N).

    Raises
    ------
    InputError
        A bad file, option or output folder.

    Examples
    --------
    >>> resp = mst.simulate("configs/mohammadi2021-forward.yaml", out="mst-out/forward")  # doctest: +SKIP
    >>> [r.force_to_N for r in resp.regimes]  # doctest: +SKIP
    """
    if out is None:
        _one_of("--mechanics", mechanics, MODELS)
        _one_of("--field-model", field_model, FIELD_MODELS)
        return simulate_as_printed(load_design(design), mechanics, field_model)
    run = run_simulate(design, mechanics=mechanics, field_model=field_model, out=out, plot=plot)
    assert run.response is not None  # run_simulate simulates
    return run.response


def run_simulate(
    design: str | Path | Document,
    *,
    mechanics: str | None = None,
    field_model: str | None = None,
    load_offset_mm: tuple[float, float] | None = None,
    offset_map: bool = False,
    out: str | Path | None = None,
    plot: bool = True,
    note: Callable[[str], None] | None = None,
) -> Simulation:
    """The whole ``mst simulate`` run: the response, the off-centre press and the offset map asked
    for, written together (report.json's ``off_centre`` included).

    Parameters
    ----------
    design, mechanics, field_model
        As :func:`simulate`.
    load_offset_mm : (float, float), optional
        Press at (x, y) mm on the top face as well (:func:`simulate_offcentre`).
    offset_map : bool
        Map the axial reading's error over the top face as well (:func:`offset_map`, ~10 s).
    out : str or Path, optional
        Folder for report.json, response.csv/png and offcentre/offset_map .csv/.png [default:
        nothing written].
    note : callable(str), optional
        Gets the rung picked and the print parameters that differ from nominal, before the work.

    Returns
    -------
    Simulation
        ``.response``, ``.off_centre``, ``.offset_map`` (None unless asked for), ``.report`` (the
        report written), ``.table()`` (the terminal's), ``.file_names(plot)``.

    Raises
    ------
    InputError
        A bad file, option, offset or output folder (refused before any work).

    Examples
    --------
    >>> run = mst.run_simulate("configs/mohammadi2021-forward.yaml", load_offset_mm=(5, 0), out="o")  # doctest: +SKIP
    >>> print(run.table())  # doctest: +SKIP
    """
    _one_of("--mechanics", mechanics, MODELS)
    _one_of("--field-model", field_model, FIELD_MODELS)
    doc, geometry = _design_and_geometry(design)
    _check_out(out)  # a bad output path is refused before any work
    run = Simulation(doc, geometry, choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics))
    if note is not None:
        for line in run.model_lines():
            note(line)
    run.response = simulate_as_printed(doc, mechanics, field_model)
    if load_offset_mm is not None:
        run.off_centre = _offcentre(doc, load_offset_mm, mechanics, field_model)
    if offset_map:
        run.offset_map = _offset_map(doc, mechanics, field_model, None)
    if out is not None:
        run.write(Path(out), plot)
    return run


def simulate_offcentre(
    design: str | Path | Document,
    offset_mm: tuple[float, float],
    *,
    mechanics: str | None = None,
    field_model: str | None = None,
    out: str | Path | None = None,
    plot: bool = True,
) -> OffCentreResponse:
    """A force pressed at ``offset_mm`` = (x0, y0) on the top face (``mst simulate --load-offset-mm``).

    The part as printed, the mechanics rung as :func:`simulate` picks it, every layer tilting
    with rigid plates (:mod:`mst_cli.model.offcentre`).

    Parameters
    ----------
    design, mechanics, field_model
        As :func:`simulate` (the dipole is refused: it is not exact off the axis).
    offset_mm : (float, float)
        Where the force presses, mm: x across the width, y along the depth.
    out : str or Path, optional
        Folder for what the command writes: report.json (with ``off_centre``), response.csv,
        offcentre.csv and (``plot``) their pictures [default: nothing written].

    Returns
    -------
    OffCentreResponse
        ``.force_N`` (m,), ``.B_T`` (m, 3) at the chip, ``.magnet_tilt_deg`` (m, 2),
        ``.force_read_axial_N`` (what the centred model reads from that |B|), ``.read_error_N``,
        ``.side_lock_N`` (n, 2) and ``.axial`` (the centred :class:`Response`).

    Raises
    ------
    InputError
        An offset off the top face, or a bad file or option.

    Examples
    --------
    >>> off = mst.simulate_offcentre("configs/mohammadi2021-forward.yaml", (5.0, 0.0))  # doctest: +SKIP
    """
    if out is not None:
        run = run_simulate(
            design, mechanics=mechanics, field_model=field_model, load_offset_mm=offset_mm, out=out, plot=plot
        )
        assert run.off_centre is not None  # asked for
        return run.off_centre
    _one_of("--mechanics", mechanics, MODELS)
    _one_of("--field-model", field_model, FIELD_MODELS)
    return _offcentre(load_design(design), offset_mm, mechanics, field_model)


def _offcentre(doc: Document, offset_mm, mechanics: str | None, field_model: str | None) -> OffCentreResponse:
    scene = printed_scene(doc, mechanics, field_model)
    check_on_top_face(scene.geometry, offset_mm)
    return run_offcentre(scene.geometry, scene.material, offset_mm, scene.mechanics, scene.field_model)


def offset_map(
    design: str | Path | Document,
    *,
    mechanics: str | None = None,
    field_model: str | None = None,
    region_mm: tuple[float, float] | None = None,
    out: str | Path | None = None,
    plot: bool = True,
) -> OffsetMap:
    """The axial reading's relative force error over the top face (``mst simulate --offset-map``).

    Parameters
    ----------
    design, mechanics, field_model
        As :func:`simulate_offcentre`.
    region_mm : (float, float), optional
        Half extents (x, y) of the map, mm [default: 80 % of the top face].
    out : str or Path, optional
        Folder for what the command writes: report.json, response.csv, offset_map.csv and
        (``plot``) their pictures [default: nothing written]; the command's region only.

    Returns
    -------
    OffsetMap
        The error at 25, 50 and 75 % of every regime's force band on a grid of presses.

    Raises
    ------
    InputError
        A bad file or option, or ``out`` with a ``region_mm``.

    Examples
    --------
    >>> omap = mst.offset_map("configs/mohammadi2021-forward.yaml", region_mm=(4.0, 4.0))  # doctest: +SKIP
    """
    if out is not None:
        if region_mm is not None:
            raise InputError("region_mm", region_mm, "must be None with out= (the command maps 80 % of the face)")
        run = run_simulate(design, mechanics=mechanics, field_model=field_model, offset_map=True, out=out, plot=plot)
        assert run.offset_map is not None  # asked for
        return run.offset_map
    _one_of("--mechanics", mechanics, MODELS)
    _one_of("--field-model", field_model, FIELD_MODELS)
    return _offset_map(load_design(design), mechanics, field_model, region_mm)


def _offset_map(doc: Document, mechanics: str | None, field_model: str | None, region_mm) -> OffsetMap:
    scene = printed_scene(doc, mechanics, field_model)
    return run_offset_map(scene.geometry, scene.material, scene.mechanics, scene.field_model, region_mm=region_mm)


def design(
    spec: str | Path | Document,
    *,
    seed: int | None = None,
    max_evaluations: int | None = None,
    refine: str | None = None,
    calibration: str | Path | None = None,
    progress: Callable | None = None,
    out: str | Path | None = None,
    plot: bool = True,
) -> DesignResult:
    """Inverse design from target S_i and R_i to theta, t, h per layer (``mst design``).

    Parameters
    ----------
    spec : str, Path or Document
        A spec file (per layer target_sensitivity_per_N in 1/N and target_range_N in N).
    seed, max_evaluations : int, optional
        Same spec and seed give the same design; the solver's budget of model evaluations.
    refine : {"frame", "continuum"}, optional
        Polish the L0 optimum for a dearer model by space mapping [default: the spec's pick].
    calibration : str or Path, optional
        An earlier print's calibration.json: its fitted wall offset, modulus factor, gap offset
        and remanence go into the spec's ``printer`` keys and magnet (held ones are not used).
    progress : callable(done, total, phase, worst_error_rel), optional
        Called as the solver spends its budget.
    out : str or Path, optional
        Folder for design.yaml, report.json, response.csv and (``plot``) response.png, written
        atomically as the command writes them [default: nothing written].

    Returns
    -------
    DesignResult
        ``.document`` (the design), ``.geometry``, ``.response`` (the forward model on it),
        ``.status`` ("met" / "not met", ``.binding`` and ``.reasons`` say why), ``.targets``
        (per layer target against achieved), ``.table()``, ``.design_yaml_dict()``.

    Raises
    ------
    InputError
        A bad spec, option, calibration.json or output folder (before any work).

    Examples
    --------
    >>> result = mst.design("configs/mohammadi2021-spec.yaml", seed=0, out="mst-out/spec")  # doctest: +SKIP
    """
    _one_of("--refine", refine, ("frame", "continuum"))
    run = run_design(
        spec,
        seed=seed,
        max_evaluations=max_evaluations,
        refine=refine,
        calibration=calibration,
        out=out,
        plot=plot,
        progress=progress,
    )
    assert run.result is not None  # run_design solves
    return run.result


def pareto(
    spec: str | Path | Document,
    count: int,
    *,
    seed: int | None = None,
    max_evaluations: int | None = None,
    calibration: str | Path | None = None,
    progress: Callable | None = None,
    out: str | Path | None = None,
    plot: bool = True,
    designs: bool = False,
) -> tuple[DesignResult, list[ParetoDesign]]:
    """The trade among designs that meet every target (``mst design --pareto N``), mapped with
    L0 (the spring rung) whatever the spec's model section asks.

    Parameters
    ----------
    spec, seed, max_evaluations, calibration, progress
        As :func:`design`.
    count : int
        Designs on the front, 2 to 60.
    out : str or Path, optional
        Folder for what ``mst design --pareto`` writes: the chosen design's files, pareto.csv
        and (``plot``) pareto.png [default: nothing written].
    designs : bool
        With ``out``: every front design as pareto/design-NN.yaml too (``--pareto-designs``).

    Returns
    -------
    (DesignResult, list of ParetoDesign)
        The chosen design (design.objective's weights) and up to ``count`` non-dominated
        designs, each with ``.height_mm``, ``.worst_force_resolution_N``,
        ``.print_robustness_rms`` and its ``.result``.

    Raises
    ------
    InputError
        A bad spec, count, option or output folder.

    Examples
    --------
    >>> chosen, front = mst.pareto("configs/mohammadi2021-spec.yaml", 8)  # doctest: +SKIP
    """
    if not 2 <= count <= 60:
        raise InputError("--pareto", count, "must be an integer from 2 to 60")
    run = run_design(
        spec,
        pareto=count,
        pareto_designs=designs,
        any_rung=True,
        seed=seed,
        max_evaluations=max_evaluations,
        calibration=calibration,
        out=out,
        plot=plot,
        progress=progress,
    )
    assert run.result is not None and run.front is not None  # run_design maps the front
    return run.result, run.front


def run_design(
    spec: str | Path | Document,
    *,
    pareto: int | None = None,
    pareto_designs: bool = False,
    any_rung: bool = False,
    seed: int | None = None,
    max_evaluations: int | None = None,
    refine: str | None = None,
    calibration: str | Path | None = None,
    out: str | Path | None = None,
    plot: bool = True,
    progress: Callable | None = None,
    note: Callable[[str], None] | None = None,
) -> DesignRun:
    """The whole ``mst design`` run: spec loaded, calibrated and its rung chosen once; solved; written.

    Parameters
    ----------
    spec, seed, max_evaluations, refine, calibration, progress, out, plot
        As :func:`design`.
    pareto, pareto_designs : int (optional), bool
        Map a front of this many designs with spring (:func:`pareto`; a dearer rung is refused
        unless ``any_rung``) and write each as pareto/design-NN.yaml.
    note : callable(str), optional
        Gets the rung picked and the calibration taken, before the solver starts.

    Returns
    -------
    DesignRun
        ``.result``, ``.front`` (or None), ``.calibration``, ``.report`` (once written), ``.summary()``.

    Raises
    ------
    InputError
        As :func:`design`.

    Examples
    --------
    >>> run = mst.run_design("configs/mohammadi2021-spec.yaml", pareto=8, out="mst-out/front")  # doctest: +SKIP
    """
    from mst_cli.design.run import DesignRun, design_choice  # deferred: the design layer, 25 ms measured

    doc = load(spec) if isinstance(spec, (str, Path)) else spec
    cal = None
    if calibration is not None:
        from mst_cli.calibrate.calibration_json import apply_calibration, read_calibration  # deferred: 7 ms measured

        doc = apply_calibration(doc, cal := read_calibration(calibration, doc))
    _check_out(out)  # a bad output path: refused before any work
    if pareto_designs and pareto is None:
        raise InputError("--pareto-designs", True, "needs --pareto N")
    choice = design_choice(doc, refine, None if any_rung else pareto)
    run = DesignRun(doc, choice, cal, pareto)
    if note is not None:
        for line in run.choice_lines():
            note(line)
    run.solve(seed, max_evaluations, progress)
    if out is not None:
        run.write(Path(out), pareto_designs, plot)
    return run


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
    from mst_cli.design import design_document  # deferred: the design layer, 25 ms measured

    result = design_document(doc)
    geometry = result.geometry
    for v in geometry.violations(result.document.printer):
        raise v.input_error("the designed cell is invalid")
    if progress is not None:
        progress(f"designed: targets {result.status}")
    return result.document, result


def export(
    design: str | Path | Document | DesignResult,
    out: str | Path | None = None,
    *,
    stl: bool = True,
    three_mf: bool = False,
    step: bool = False,
    stl_tolerance_mm: float = 0.01,
    progress: Callable[[str], None] | None = None,
) -> ExportedFiles:
    """The printable body of a design (a spec is designed first) into ``out`` (``mst export``).

    Parameters
    ----------
    design : str, Path, Document or DesignResult
        A design or spec file, a design's Document, or a design result (its design.yaml too).
    out : str or Path, optional
        Folder for sensor.stl/.3mf (print orientation, mm), sensor.step (sensor frame), export.json
        and a spec's design.yaml [default: ./mst-out/<name>/, as the command].
    stl, three_mf, step : bool; stl_tolerance_mm : float
        The formats to write; the mesh's largest chord deviation from curved surfaces, mm (1e-4 to 1).

    Returns
    -------
    ExportedFiles
        The files written (list of Path, export.json last); ``.geometry``, ``.designed`` (a spec's
        DesignResult), ``.summary(three_mf)``.

    Raises
    ------
    InputError
        A bad file, tolerance or output folder (before any work), or an invalid designed cell.

    Examples
    --------
    >>> mst.export("configs/mohammadi2021-forward.yaml", "mst-out/body", three_mf=True)  # doctest: +SKIP
    """
    # deferred: the CAD layer, 30 ms measured; the design layer, 25 ms (mst simulate pays neither)
    from mst_cli.cad.exporting import ExportedFiles, check_stl_tolerance, write_export

    check_stl_tolerance(stl_tolerance_mm)  # one bound, shared with check
    _check_out(out)  # a bad output path is refused before any work
    doc, result = _to_export(design, progress)
    geometry = result.geometry if result is not None else doc.geometry()
    _check_out(folder := Path(out) if out is not None else Path("mst-out") / doc.name)
    if progress is not None:
        progress(f"loaded {design if isinstance(design, (str, Path)) else doc.name} ({len(geometry.layers)} layers)")
    yaml = result.design_yaml_dict() if result is not None else None
    names = write_export(
        doc,
        geometry,
        folder,
        stl=stl,
        step=step,
        three_mf=three_mf,
        stl_tolerance_mm=stl_tolerance_mm,
        design_yaml=yaml,
        progress=progress,
    )
    return ExportedFiles([folder / n for n in names], geometry, result)


def _to_export(design, progress):
    """(the design's Document, the DesignResult a spec became or None)."""
    from mst_cli.design import DesignResult  # deferred: the design layer, 25 ms measured

    if isinstance(design, (str, Path)):
        return designed(design, progress)
    if isinstance(design, DesignResult):
        return design.document, design
    return load_design(design), None


def check(path: str | Path, *, nozzle_mm: float | None = None) -> CheckResults:
    """Measure an exported mesh against its export.json (``mst check``).

    Parameters
    ----------
    path : str or Path
        The folder ``export`` wrote, or the .stl in it.
    nozzle_mm : float, optional
        Nozzle diameter for the wall checks [default: the design's printer.nozzle_mm].

    Returns
    -------
    CheckResults
        A list of Check, in report order: ``.name``, ``.passed``, ``.measured`` and
        ``.expected`` (text with units), ``.note``, ``.values`` (numbers, units in the keys);
        ``.failed`` (names), ``.to_dict()`` (``--json``'s form), ``.table()``.

    Raises
    ------
    InputError
        A missing or malformed export, mesh or export.json, or a bad nozzle.

    Examples
    --------
    >>> results = mst.check("mst-out/body")  # doctest: +SKIP
    >>> results.failed  # doctest: +SKIP
    []
    """
    # deferred: the CAD layer, 30 ms measured (mst simulate does not pay it)
    from mst_cli.cad.checks import CheckResults, load_mesh, resolve_export, run_checks
    from mst_cli.cad.manifest import load_manifest

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
    return CheckResults(run_checks(load_mesh(found.stl), manifest, nozzle_mm), found.stl)


def slice(
    path: str | Path,
    *,
    profile: str | Path | None = None,
    out: str | Path | None = None,
    max_span_mm: float = 5.0,
    plot: bool = False,
    progress: Callable[[str], None] | None = None,
    note: Callable[[str], None] | None = None,
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

    Returns
    -------
    SliceResult
        ``.report`` (slice.json: print time s, filament g, layers, the longest free span mm,
        the pause found against the one asked for, support, cavity gaps mm), ``.checks``,
        ``.failed`` (names of the broken limits), ``.summary()``.
    """
    from mst_cli.cad.slicing import slice_export  # deferred: the CAD layer and subprocess, 50 ms measured

    result = slice_export(path, profile, max_span_mm, progress, note)
    result.write(Path(out) if out is not None else None, plot=plot)
    return result


def parse_params(text: str) -> tuple[str, ...]:
    """The parameter names of ``--params`` ("modulus_factor,gap_offset_mm")."""
    from mst_cli.calibrate.calibration import parse_params as parse  # deferred: scipy.optimize, 330 ms measured

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
    from mst_cli.calibrate.calibration import calibrate as run_calibration  # deferred: scipy.optimize, 330 ms measured

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


def _checked_fit_options(mechanics: str, params: Sequence[str] | str | None, table_size: int) -> tuple[str, ...]:
    """The parameter names to fit, after the rules of --mechanics, --params (known names, each
    once) and --table-size."""
    from mst_cli.calibrate.fit import DEFAULT_PARAMETERS  # deferred: the calibrate layer, 5 ms measured

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
    # deferred: the calibrate layer, 30 ms measured (mst simulate does not pay it)
    from mst_cli.calibrate.loadtest import parse_readings, read_text, setting_of
    from mst_cli.calibrate.reading import ForceReader

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
    if not (max_offset_sigma_mm > 0 and math.isfinite(max_offset_sigma_mm)):
        raise InputError("--max-offset-sigma-mm", max_offset_sigma_mm, "must be a positive number of mm")
    reader, rd, _ = _reader(model, model_file, mechanics, gain_sel, res, False, readings, out, warn)
    offsets = None
    if estimate_offset:
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
    reader, _, setting = _reader(model, model_file, mechanics, gain_sel, res, raw, None, out, warn)
    if status is not None:
        status(f"{reader.document.name}: reading {port} at {baud} baud (Ctrl-C to stop)")
    samples = reader.stream(port, baud, count, timeout_s, raw, setting, show)
    if out is not None:
        with staged(Path(out)) as st:
            st.write_text("forces.csv", samples.csv(reader.inverse_map))
    return samples


def bench(
    *, samples: int = 24, seed: int = 0, quick: bool = False, out: str | Path | None = None, plot: bool = True
) -> BenchResult:
    """Measure the model ladder against its references (``mst bench``).

    Parameters
    ----------
    samples : int
        Seeded valid designs across the bounds (1 to 500).
    seed : int
        Seed of the sample.
    quick : bool
        Skip the continuum mesh-convergence study and the tilt rung's check against L2.
    out : str or Path, optional
        Folder for bench.json, bench.md and (``plot``) bench.png, written atomically
        [default: nothing written].

    Returns
    -------
    BenchResult
        bench.json's dict: per rung (spring, frame) the stiffness and lock-force errors against
        continuum FE and the time per layer, per field model the error against magpylib, the
        mesh convergence and the tilt rung's error; ``.markdown()`` is bench.md.

    Raises
    ------
    InputError
        A bad sample count or output folder.

    Examples
    --------
    >>> print(mst.bench(samples=4, quick=True).markdown())  # doctest: +SKIP
    """
    from mst_cli.bench.ladder_bench import BenchResult, run_bench  # deferred: scipy and scikit-fem, 160 ms measured

    if not 1 <= samples <= 500:
        raise InputError("--samples", samples, "must be an integer from 1 to 500")
    _check_out(out)
    result = BenchResult(run_bench(samples=samples, seed=seed, quick=quick))
    if out is not None:
        result.write(Path(out), plot)
    return result
