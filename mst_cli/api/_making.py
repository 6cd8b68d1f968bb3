"""The printable part: ``mst export``, ``mst check``, ``mst slice``.

Part of the api's one door, :mod:`mst_cli.api`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import fields
from pathlib import Path
from typing import TYPE_CHECKING, cast

from mst_cli.api._common import _check_out, load, load_design, refuse_unhoused_chips
from mst_cli.api._designing import designed
from mst_cli.errors import InputError
from mst_cli.io.files import is_machine_fault as is_machine_fault
from mst_cli.io.files import os_error_text as os_error_text
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE
from mst_cli.model.printer import Printer
from mst_cli.sensor.document import Document

if TYPE_CHECKING:
    from mst_cli.cad.checks import CheckResults
    from mst_cli.cad.exporting import ExportedFiles
    from mst_cli.cad.manifest import Manifest
    from mst_cli.cad.slicing import SliceResult
    from mst_cli.design.result import DesignResult


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
        refuse_unhoused_chips(load(design))  # before a spec is designed
        return designed(design, progress)
    if isinstance(design, DesignResult):
        return design.document, design
    return load_design(design), None


def check(
    path: str | Path,
    *,
    nozzle_mm: float | None = None,
    load_path_max: float | None = None,
    whole_part: bool = False,
    progress: Callable[[str], None] | None = None,
    rung_spacing_mm: float | None = None,
) -> CheckResults:
    """Measure an exported mesh against its export.json (``mst check``).

    Parameters
    ----------
    path : str or Path
        The folder ``export`` wrote, or the .stl in it.
    nozzle_mm : float, optional
        Nozzle diameter for the wall checks [default: the design's printer.nozzle_mm].
    load_path_max : float, optional
        Fail when the share of the magnet's motion outside the layers (cap, plates, cover) exceeds
        this in any regime, 0 to 1 [default: reported only].
    whole_part : bool, optional
        Also the ``whole_part`` check: the part's section on the whole-part rung against the
        design's stated field change per newton, per regime (docs/design.md 4.7; seconds to
        minutes). ``progress`` gets a line before its solves; ``rung_spacing_mm`` sets the
        rung's lattice [default: its production mesh].

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
    from mst_cli.cad.checks import CheckResults, run_checks
    from mst_cli.cad.export_files import load_mesh, resolve_export
    from mst_cli.cad.manifest import load_manifest

    _check_options(nozzle_mm, load_path_max)
    found = resolve_export(path)
    # both inputs are validated before anything is measured (every field the checks read, every
    # STL coordinate): past this point a KeyError or TypeError is a bug in a check, not bad input
    manifest = cast("Manifest", load_manifest(found.manifest))  # kind=Manifest by default
    assert found.stl is not None  # resolve_export found one (need_stl)
    checks = run_checks(load_mesh(found.stl), manifest, nozzle_mm, load_path_max)
    if whole_part:
        checks += _whole_part_checks(manifest, found.manifest, progress, rung_spacing_mm)
    return CheckResults(checks, found.stl)


def _check_options(nozzle_mm: float | None, load_path_max: float | None) -> None:
    """Refuse a nozzle outside printer.nozzle_mm's bounds or a share outside 0 to 1."""
    if nozzle_mm is not None:  # one bound: printer.nozzle_mm's in a design file
        lo, hi = next((f.metadata["lo"], f.metadata["hi"]) for f in fields(Printer) if f.name == "nozzle_mm")
        if not lo <= nozzle_mm <= hi:
            raise InputError("--nozzle", nozzle_mm, f"must be a nozzle diameter from {lo:g} to {hi:g} mm")
    if load_path_max is not None and not 0.0 <= load_path_max <= 1.0:
        raise InputError("--load-path-max", load_path_max, "must be a share from 0 to 1")


def _whole_part_checks(manifest, manifest_path, progress, spacing_mm) -> list:
    """``mst check --whole-part``'s check of the design in export.json and its shear report
    (cad.whole_part_check)."""
    if manifest.design is None:
        raise InputError("--whole-part", str(manifest_path), "needs the design in export.json (mst export writes it)")
    # deferred: scikit-fem's rung
    from mst_cli.cad.whole_part_check import check_whole_part, check_whole_part_shear

    return [
        check_whole_part(manifest.design, progress, spacing_mm),
        check_whole_part_shear(manifest.design, progress, spacing_mm),
    ]


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

    Raises
    ------
    InputError
        For an export folder that fails ``mst check``'s rules, a profile that is not a regular
        readable file, or one whose ``post_process`` names scripts without ``allow_post_process``.
    SlicerError
        When PrusaSlicer is missing, fails, or writes nothing or truncated G-code (a machine
        fault, exit 1 from the command).

    Examples
    --------
    >>> mst.export("configs/mohammadi2021-forward.yaml", "print", three_mf=True)  # doctest: +SKIP
    >>> result = mst.slice("print", max_span_mm=2.0)  # doctest: +SKIP
    >>> result.failed  # doctest: +SKIP
    []
    """
    from mst_cli.cad.slicing import slice_export  # deferred: the CAD layer and subprocess, 50 ms measured

    result = slice_export(path, profile, max_span_mm, progress, note, allow_post_process)
    result.write(Path(out) if out is not None else None, plot=plot)
    return result
