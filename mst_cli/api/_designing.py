"""Inverse design: ``mst design`` and ``--pareto``.

Part of the api's one door, :mod:`mst_cli.api`."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from mst_cli.api._common import _check_out, _one_of, load, load_design, refuse_unhoused_chips
from mst_cli.errors import InputError
from mst_cli.io.files import is_machine_fault as is_machine_fault
from mst_cli.io.files import os_error_text as os_error_text
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE
from mst_cli.sensor.document import Document

if TYPE_CHECKING:
    from mst_cli.calibration.calibration_json import PrinterCalibration
    from mst_cli.design.pareto import ParetoDesign
    from mst_cli.design.result import DesignResult
    from mst_cli.design.run import DesignRun


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
    >>> result = mst.design("configs/mohammadi2021.yaml", seed=0, out="mst-out/spec")  # doctest: +SKIP
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
    >>> chosen, front = mst.pareto("configs/mohammadi2021.yaml", 8)  # doctest: +SKIP
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
    warn: Callable[[str], None] | None = None,
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
    warn : callable(str), optional
        Gets one line when the design's rung is not the calibration's (and how far apart they are).

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
    >>> run = mst.run_design("configs/mohammadi2021.yaml", pareto=8, out="mst-out/front")  # doctest: +SKIP
    """
    from mst_cli.design.run import DesignRun, design_choice  # deferred: the design layer, 25 ms measured

    doc, cal = _calibrated(refuse_unhoused_chips(load(spec) if isinstance(spec, (str, Path)) else spec), calibration)
    _check_out(out)  # a bad output path: refused before any work
    if pareto_designs and pareto is None:
        raise InputError("--pareto-designs", True, "needs --pareto N")
    choice = design_choice(doc, refine, None if any_rung else pareto)
    run = DesignRun(doc, choice, cal, pareto)
    _other_rung(cal, choice.mechanics, warn)
    if note is not None:
        for line in run.choice_lines():
            note(line)
    run.solve(seed, max_evaluations, progress)
    if out is not None:
        run.write(Path(out), pareto_designs, plot)
    return run


def _calibrated(doc: Document, calibration: str | Path | None) -> tuple[Document, PrinterCalibration | None]:
    """``doc`` with the printer a calibration.json measured (and that record), or as it is."""
    if calibration is None:
        return doc, None
    from mst_cli.calibration.calibration_json import apply_calibration, read_calibration  # deferred: 7 ms measured

    cal = read_calibration(calibration, doc)
    return apply_calibration(doc, cal), cal


def _other_rung(cal: PrinterCalibration | None, mechanics: str, warn: Callable[[str], None] | None) -> None:
    """``warn`` one line when ``mechanics`` is not the calibration's rung, with how far apart the
    two read forces on the calibrated design (calibrated.yaml beside calibration.json, when it loads)."""
    if cal is None or warn is None or cal.mechanics is None or cal.mechanics == mechanics:
        return
    from mst_cli.calibration.calibration_json import CALIBRATED_YAML  # deferred: the calibrate layer
    from mst_cli.calibration.rung_check import rung_warning  # deferred: the calibrate layer

    try:
        calibrated: Document | None = load_design(Path(cal.path).with_name(CALIBRATED_YAML))
    except InputError:
        calibrated = None
    line = rung_warning(cal.mechanics, mechanics, calibrated, cal.calibrated_to_N, "mst design")
    if line is not None:
        warn(line)


def designed(path: str | Path, progress: Callable[[str], None] | None = None) -> tuple[Document, DesignResult | None]:
    """A design file as it is, or a spec designed first (as ``mst export SPEC`` does).

    Parameters
    ----------
    path : str or Path
        A design file (every layer's theta_deg, t_mm, h_mm) or a spec file (targets).
    progress : callable(str), optional
        Gets a line before a spec is designed and one with the targets' status after.

    Returns
    -------
    (Document, DesignResult or None)
        The design's Document and, for a spec, the DesignResult it came from (None for a design).

    Raises
    ------
    InputError
        For a file that is neither, or a cell that breaks a rule (naming the layer and the key).

    Examples
    --------
    >>> doc, result = mst.designed("configs/mohammadi2021-forward.yaml")  # doctest: +SKIP
    >>> result is None  # a design file: nothing was designed  # doctest: +SKIP
    True
    """
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
