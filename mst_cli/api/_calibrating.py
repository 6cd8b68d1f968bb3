"""From a printed sensor: ``mst calibrate`` and ``mst read``.

Part of the api's one door, :mod:`mst_cli.api`."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mst_cli.api._common import _check_out, _one_of, load_design
from mst_cli.errors import InputError
from mst_cli.io.files import is_machine_fault as is_machine_fault
from mst_cli.io.files import os_error_text as os_error_text
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.io.outputs import staged
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE
from mst_cli.model.ladder import choose_mechanics
from mst_cli.model.mechanics import MODELS
from mst_cli.sensor.document import Document

if TYPE_CHECKING:
    from mst_cli.calibrate.calibration import Calibration
    from mst_cli.calibrate.reading import ForceReadings, SerialSamples


def parse_params(text: str) -> tuple[str, ...]:
    """The parameter names of ``--params`` ("modulus_factor,gap_offset_mm")."""
    from mst_cli.calibrate.calibration import parse_params as parse  # deferred: scipy.optimize, 330 ms measured

    return parse(text)


_CSV_HEADER_WORDS = ("force_N", "Bx_uT", "Bx_code_lsb")


def _looks_like_readings(path: Path) -> bool:
    """The first line of ``path`` (a regular file) that is not blank or a comment is a readings
    CSV's header: it names force_N, Bx_uT or Bx_code_lsb."""
    try:
        if not path.is_file():
            return False
        with path.open("rb") as fh:
            head = fh.read(4096).decode("utf-8-sig", errors="replace")
    except OSError:
        return False
    for line in head.splitlines():
        if line.strip() and not line.lstrip().startswith("#"):
            cells = {c.strip().strip('"') for c in line.replace(";", ",").replace("\t", ",").split(",")}
            return any(w in cells for w in _CSV_HEADER_WORDS)
    return False


def check_argument_order(design: str | Path | Document, data: str | Path | None, verb: str) -> None:
    """InputError in one line when the design argument is the readings CSV (the two arguments
    swapped): ``mst calibrate loadtest.csv design.yaml``."""
    if isinstance(design, Document) or not _looks_like_readings(Path(design)):
        return
    second = "LOAD_TEST.csv" if verb == "calibrate" else "READINGS.csv"
    swapped = data is not None and not _looks_like_readings(Path(data))
    raise InputError(
        "DESIGN_FILE" if verb == "calibrate" else "MODEL_FILE",
        str(design),
        "is a CSV of readings, not a design"
        + (f" ({data} is the design?): the arguments are swapped" if swapped else "")
        + f"; the order is mst {verb} {'DESIGN' if verb == 'calibrate' else 'MODEL'}.yaml {second}",
    )


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
    use_branches: bool = True,
    offset_table: bool = False,
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
        Folder for calibrated.yaml, calibration.json, residuals.csv, lookup.csv, force_table.h,
        (``plot``) calibration.png and (``offset_table``) inverse_table.npz, which
        ``read(estimate="offset")`` reads, and offset_table.h, written atomically [default: none].
    mechanics : {"spring", "frame", "continuum"}
        Layer mechanics of the fit; frame and continuum by space mapping on spring.
    params : sequence of str or str, optional
        Parameters to fit (of :data:`mst_cli.sensor.as_printed.PARAMETERS`, or "a,b") [default: all four].
    gain_sel, res, table_size, use_branches : int, int, int, bool, optional
        The MLX90393 setting the load test was read at (0-7, 0-3); entries of lookup.csv
        (16-4096); fit the loading rows (True) or every row as loading.
    offset_table : bool
        Write the offset tables into ``out`` too (a minute or two).

    Returns
    -------
    Calibration
        ``.fit.values`` (units in the names) and ``.fit.std`` (1 sigma), ``.calibrated`` (the
        design as printed), ``.inverse_map`` (|B| T -> force N), ``.record`` (calibration.json),
        ``.summary()``. Raises InputError (bad file or option) or CalibrationFailed (why).
    """
    from mst_cli.calibrate.calibration import calibrate as run_calibration  # deferred: scipy.optimize, 330 ms measured

    params = _checked_fit_options(mechanics, params, table_size)
    check_argument_order(design, load_test, "calibrate")
    doc = load_design(design)
    _check_out(out)  # a bad output path is refused before any work
    name = design_file or (design if isinstance(design, (str, Path)) else design.name)
    options: dict[str, Any] = {"gain_sel": gain_sel, "res": res, "table_size": table_size, "progress": progress}
    result = run_calibration(
        doc, name, load_test, mechanics=mechanics, params=params, use_branches=use_branches, **options
    )
    if out is not None:
        result.write(Path(out), plot=plot)
        if offset_table:
            _write_offset_tables(Path(out), result, progress)
    return result


def _write_offset_tables(out: Path, result: Calibration, progress: Callable[[str], None] | None) -> None:
    """inverse_table.npz beside the calibrated.yaml just written (current: hashed with it and its
    calibration.json) and, with a chip setting, offset_table.h from its every other node."""
    # deferred: the calibrate layer, as calibrate's
    from mst_cli.calibrate.calibration_json import CALIBRATED_YAML
    from mst_cli.calibrate.offset_header import OFFSET_HEADER_FILE, offset_header
    from mst_cli.calibrate.reading import ForceReader
    from mst_cli.calibrate.table_reader import tables_for

    model = out / CALIBRATED_YAML
    doc = load_design(model)
    mech = choose_mechanics(None, doc.accuracy_rel, doc.mechanics).mechanics
    reader = ForceReader.open(doc, model, mech, result.header_setting)
    if progress is not None:
        progress("building the offset table (inverse_table.npz: the tilt rung at every node)")
    lever = reader.record.lever_factor() if reader.record is not None else 1.0
    table, coarse = tables_for(model, doc, reader.inverse_map, lever, mech)
    with staged(out) as st:
        table.save(st.path(table.file_name))
        if result.header_setting is not None:
            text = offset_header(
                coarse,
                reader.inverse_map,
                result.header_setting,
                doc.name,
                f"{CALIBRATED_YAML} ({mech}, lever factor {lever:.4g})",
                ["what the tilt rung leaves out (docs/design.md section 4.2); the table's own error between nodes"],
            )
            st.write_text(OFFSET_HEADER_FILE, text)


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
    from mst_cli.calibrate.loadtest import check_field_unit, parse_readings, read_text, setting_of
    from mst_cli.calibrate.reading import ForceReader

    _one_of("--mechanics", mechanics, MODELS)
    check_argument_order(design, readings, "read")
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
    if rd is not None:
        check_field_unit(rd, float(reader.inverse_map.B_abs_T[0]), float(reader.inverse_map.B_abs_T[-1]))
    if reader.warning and warn is not None:
        warn(reader.warning)
    return reader, rd, setting


# what ``mst read --estimate`` can add to the force; a new estimate is one entry here and one
# branch in :func:`_estimator`
ESTIMATES = ("none", "offset")


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
    estimate: str = "none",
    estimate_offset: bool = False,
    polish: bool = False,
    max_offset_sigma_mm: float = 1.0,
    tare: int = 0,
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
    estimate : {"none", "offset"}
        "offset": estimate where each reading was pressed from Bx, By, Bz (the tilt rung's
        inverse, from the model's table: inverse_table.npz beside the model, built on first use
        and then written to ``out``) and correct its force; ``.offset`` holds x, y and their
        Cramer-Rao 1-sigma, and a reading whose press the data cannot tell keeps the centred
        force, flagged (``.offset.flag``): not_identifiable (offset less certain than
        ``max_offset_sigma_mm``), ambiguous (two presses give it: every root of the table is
        found) or no_fit (none does); thousands of readings a second.
    estimate_offset : bool
        The same as ``estimate="offset"``.
    polish : bool
        Polish each table root by the model's exact Gauss-Newton (about 0.1 s a reading).
    tare : int
        Take the first ``tare`` readings as no load and re-zero the unloaded field on them.

    Returns
    -------
    ForceReadings
        ``.force_N`` (n,) in N, NaN where flagged (never extrapolated); ``.regime`` (n,),
        ``.flag`` (n,) one of ok, above_calibrated, below_range, above_range, saturated;
        ``.force_resolution_N`` (n,); ``.summary()``, ``.csv()``.
    """
    estimate = _checked_estimate("offset" if estimate_offset else estimate, max_offset_sigma_mm)
    reader, rd, _ = _reader(model, model_file, mechanics, gain_sel, res, False, readings, out, warn)
    offsets, built = _estimator(reader, estimate, mechanics, model_file or model, max_offset_sigma_mm, polish, warn)
    if isinstance(tare, bool) or not isinstance(tare, int) or tare < 0:
        raise InputError("--tare", tare, "a whole number of readings at no load (0: no tare)")
    result = reader.read(rd, offsets, tare)
    if out is not None:
        with staged(Path(out)) as st:
            st.write_text("forces.csv", result.csv())
            if built is not None:
                built.save(st.path(built.file_name))
    return result


def _checked_estimate(estimate: str, max_offset_sigma_mm: float) -> str:
    _one_of("--estimate", estimate, ESTIMATES)
    if not (max_offset_sigma_mm > 0 and math.isfinite(max_offset_sigma_mm)):
        raise InputError("--max-offset-sigma-mm", max_offset_sigma_mm, "must be a positive number of mm")
    return estimate


def _estimator(reader, estimate: str, mechanics: str | None, model_file, max_sigma_mm: float, polish: bool, warn):
    """(the reader of ``estimate``, or None; the table it built, to be written, or None).
    InputError when the layout cannot identify the estimate anywhere in its range."""
    from mst_cli.calibrate.table_reader import offset_table_reader  # deferred: the calibrate layer, as _reader

    if estimate == "none":
        return None, None
    if not isinstance(model_file, (str, Path)):
        raise InputError("model_file", None, "name the model file: its offset table stands beside it")
    doc = reader.document
    mech = choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics).mechanics
    lever = reader.record.lever_factor() if reader.record is not None else 1.0
    offsets, note = offset_table_reader(doc, reader.inverse_map, lever, Path(model_file), mech, max_sigma_mm, polish)
    if note is not None and warn is not None:
        warn(note)
    return offsets, (offsets.table if note is not None else None)


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
    estimate: str = "none",
    max_offset_sigma_mm: float = 1.0,
) -> SerialSamples:
    """A live MLX90393 stream to forces (``mst read --serial PORT``): one line per sample goes to
    ``show``; stops when the port closes, after ``count`` samples, ``timeout_s`` seconds of
    silence or Ctrl-C; ``status`` gets a line when reading starts. ``out``: forces.csv of every
    sample (time s, the three values, force N, regime, flag, resolution N; with an ``estimate``,
    its columns as :func:`read` writes them). ``estimate``: as :func:`read`'s, live (the table;
    the table is built before the port is opened when none stands beside the model)."""
    _checked_estimate(estimate, max_offset_sigma_mm)
    reader, _, setting = _reader(model, model_file, mechanics, gain_sel, res, raw, None, out, warn)
    offsets, built = _estimator(reader, estimate, mechanics, model_file or model, max_offset_sigma_mm, False, warn)
    if status is not None:
        status(f"{reader.document.name}: reading {port} at {baud} baud (Ctrl-C to stop)")
    samples = reader.stream(port, baud, count, timeout_s, raw, setting, show, offsets)
    if out is not None:
        with staged(Path(out)) as st:
            st.write_text("forces.csv", samples.csv(reader.inverse_map))
            if built is not None:
                built.save(st.path(built.file_name))
    return samples
