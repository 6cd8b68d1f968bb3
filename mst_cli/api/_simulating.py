"""The forward model: ``mst simulate`` and its off-centre presses.

Part of the api's one door, :mod:`mst_cli.api`."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from mst_cli.api._common import FIELD_MODELS, _check_out, _design_and_geometry, _one_of, load_design
from mst_cli.errors import InputError
from mst_cli.io.files import is_machine_fault as is_machine_fault
from mst_cli.io.files import os_error_text as os_error_text
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE
from mst_cli.model.general_load import SHEAR_RATIO_MAX, loaded_stack
from mst_cli.model.ladder import choose_mechanics
from mst_cli.model.load_bound import bound_report
from mst_cli.model.load_path import FINGERTIP_PATCH_MM
from mst_cli.model.mechanics import MODELS
from mst_cli.model.offcentre import OffCentreResponse, OffsetMap, section_members_pose
from mst_cli.model.offcentre import offset_map as run_offset_map
from mst_cli.model.offcentre import simulate_offcentre as run_offcentre
from mst_cli.model.response import Response
from mst_cli.sensor.as_printed import simulate_as_printed
from mst_cli.sensor.document import Document
from mst_cli.simulation.run import Simulation, check_on_top_face, printed_scene

if TYPE_CHECKING:
    pass


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
        _check_models(mechanics, field_model)
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
    shear_ratio: tuple[float, float] | None = None,
    press_width_mm: float = FINGERTIP_PATCH_MM,
) -> Simulation:
    """The whole ``mst simulate`` run: the response, the off-centre press and the offset map asked
    for, written together (report.json's ``off_centre`` and ``load_path`` included).

    Parameters
    ----------
    design, mechanics, field_model
        As :func:`simulate`.
    load_offset_mm, shear_ratio : (float, float), optional
        Press at (x, y) mm on the top face as well (:func:`simulate_offcentre`), with a tangential
        force shear_ratio x the normal one, each |ratio| <= 1 (centred without x, y).
    offset_map : bool; out : str or Path, optional
        Map the axial reading's error over the top face as well (:func:`offset_map`, ~10 s); the
        folder for report.json, response, offcentre, offset_map .csv/.png [default: none written].
    note : callable(str), optional
        Gets the rung picked and the print parameters that differ from nominal.
    press_width_mm : float, optional
        The press's width across the depth, 0 < w <= the face's, for ``load_path`` [default: 6 mm].

    Returns
    -------
    Simulation
        ``.response``, ``.off_centre``, ``.offset_map`` (None unless asked), ``.report``, ``.table()``.

    Raises
    ------
    InputError
        A bad file, option, offset or output folder (refused before any work).

    Examples
    --------
    >>> print(mst.run_simulate("configs/mohammadi2021-forward.yaml", load_offset_mm=(5, 0)).table())  # doctest: +SKIP
    """
    _check_models(mechanics, field_model)
    doc, geometry = _design_and_geometry(design)
    _check_out(out)  # a bad output path is refused before any work
    load_offset_mm = _press(load_offset_mm, shear_ratio)
    run = Simulation(doc, geometry, choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics), press_width_mm)
    if note is not None:
        list(map(note, run.model_lines()))
    run.response = simulate_as_printed(doc, mechanics, field_model)
    models = (mechanics, field_model)
    run.off_centre = None if load_offset_mm is None else _offcentre(doc, load_offset_mm, *models, shear_ratio)
    run.shear_bound = None if shear_ratio is None else _shear_bound(doc, *models, shear_ratio)
    run.offset_map = _offset_map(doc, *models, None) if offset_map else None
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
    shear_ratio: tuple[float, float] | None = None,
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
    shear_ratio : (float, float), optional
        Tangential force (Fx, Fy) = ratio x the normal force, each |ratio| <= 1 [default: none].
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
            design, mechanics=mechanics, field_model=field_model, load_offset_mm=offset_mm, out=out, plot=plot,
            shear_ratio=shear_ratio,
        )  # fmt: skip
        assert run.off_centre is not None  # asked for
        return run.off_centre
    _one_of("--mechanics", mechanics, MODELS)
    _one_of("--field-model", field_model, FIELD_MODELS)
    if shear_ratio is not None:
        check_shear_ratio(shear_ratio)
    return _offcentre(load_design(design), offset_mm, mechanics, field_model, shear_ratio)


def _shear_bound(doc: Document, mechanics: str | None, field_model: str | None, shear_ratio) -> dict:
    """report.json's shear_bound: each estimate's 1-sigma CRB for the file's chips (one: a centred
    press's Fz, Fx, Fy; more: all five over the middle 60 % of the face)."""
    scene = printed_scene(doc, mechanics, field_model)
    g, m = scene.geometry, scene.material
    members = section_members_pose(g, m, scene.mechanics, doc.whole_part and doc.section_rung)
    stack = loaded_stack(g, m, scene.mechanics, whole_part=doc.whole_part, members=members)
    return bound_report(stack, doc.chips_mm, shear_ratio, doc.noise_uT_rms)


def _press(load_offset_mm, shear_ratio):
    """The off-centre press asked for: at the axis when only a shear ratio is given (checked)."""
    if shear_ratio is None:
        return load_offset_mm
    check_shear_ratio(shear_ratio)
    return load_offset_mm or (0.0, 0.0)


def _check_models(mechanics: str | None, field_model: str | None) -> None:
    """InputError naming --mechanics or --field-model when it is not one of the rungs or field models."""
    _one_of("--mechanics", mechanics, MODELS)
    _one_of("--field-model", field_model, FIELD_MODELS)


def check_shear_ratio(ratio: tuple[float, float]) -> None:
    """InputError unless both tangential ratios are finite and within the model's friction cone."""
    if not all(math.isfinite(r) and abs(r) <= SHEAR_RATIO_MAX for r in ratio):
        raise InputError(
            "--shear-ratio",
            ",".join(f"{r:g}" for r in ratio),
            f"must be two ratios RX,RY of the tangential to the normal force, each |r| <= {SHEAR_RATIO_MAX:g}",
        )


def _offcentre(
    doc: Document, offset_mm, mechanics: str | None, field_model: str | None, shear_ratio=None
) -> OffCentreResponse:
    scene = printed_scene(doc, mechanics, field_model)
    check_on_top_face(scene.geometry, offset_mm)
    return run_offcentre(
        scene.geometry,
        scene.material,
        offset_mm,
        scene.mechanics,
        scene.field_model,
        shear_ratio=shear_ratio or (0.0, 0.0),
        whole_part=doc.whole_part,
        section=doc.section_rung,
    )


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
    return run_offset_map(
        scene.geometry,
        scene.material,
        scene.mechanics,
        scene.field_model,
        region_mm=region_mm,
        whole_part=doc.whole_part,
        section=doc.section_rung,
    )
