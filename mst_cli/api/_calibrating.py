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
from mst_cli.io.line_columns import column_map
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.io.outputs import staged
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE
from mst_cli.model.ladder import choose_mechanics
from mst_cli.model.mechanics import MODELS
from mst_cli.sensor.document import Document

if TYPE_CHECKING:
    from mst_cli.calibration.calibration import Calibration
    from mst_cli.readout.live import SerialSamples
    from mst_cli.readout.reading import ForceReadings


def parse_params(text: str) -> tuple[str, ...]:
    """The parameter names of ``--params``.

    Parameters
    ----------
    text : str
        Comma-separated names of :data:`mst_cli.sensor.as_printed.PARAMETERS`.

    Returns
    -------
    tuple of str
        The names, in the order given.

    Raises
    ------
    InputError
        For none, an unknown or a repeated name.

    Examples
    --------
    >>> mst.parse_params("modulus_factor,gap_offset_mm")  # doctest: +SKIP
    ('modulus_factor', 'gap_offset_mm')
    """
    from mst_cli.calibration.calibration import parse_params as parse  # deferred: scipy.optimize, 330 ms measured

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
    """Refuse a design argument that is a CSV of readings (the two arguments swapped).

    Parameters
    ----------
    design, data : str, Path or Document; str, Path or None
        The design (or model) argument and the CSV argument, as given.
    verb : {"calibrate", "read"}
        The command, for the order the message states.

    Returns
    -------
    None

    Raises
    ------
    InputError
        One line naming the file, and that the arguments are swapped when they are.

    Examples
    --------
    >>> mst.check_argument_order("loadtest.csv", "design.yaml", "calibrate")  # doctest: +SKIP
    Traceback (most recent call last):
    InputError: DESIGN_FILE = 'loadtest.csv': is a CSV of readings, not a design ...
    """
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
    shear_table: bool = False,
    missing_force: float | None = None,
) -> Calibration:
    """Fit a design's print parameters to a load test of the printed sensor (``mst calibrate``).

    Parameters
    ----------
    design, load_test : str, Path or Document; str or Path
        The design the sensor was printed from (a Document: ``design_file`` names it); a CSV of
        force_N (N) and Bx_uT, By_uT, Bz_uT (uT) or raw codes (with ``gain_sel``, ``res``).
    out, offset_table, shear_table : str or Path; bool; bool
        The files' folder, with inverse_table.npz, offset_table.h; shear_table.npz, shear_table.h.
    mechanics, params : str; sequence of str or "a,b", optional
        The fit's rung (frame, continuum by space mapping on spring); the parameters fitted.
    gain_sel, res, table_size, use_branches, missing_force : int, int, int, bool, float, optional
        Raw codes' chip setting; lookup.csv's entries; fit the loading rows (or every row); a
        logger's mark for a row without a force (-1; NaN: empty, nan cells): skipped, counted.

    Returns
    -------
    Calibration
        ``.fit.values``, ``.fit.std``, ``.calibrated``, ``.inverse_map``, ``.record``, ``.summary()``.

    Raises
    ------
    InputError, CalibrationFailed
        A bad file or option (naming it); a fit that failed (saying why).

    Examples
    --------
    >>> cal = mst.calibrate("configs/mohammadi2021-forward.yaml", "loadtest.csv", out="cal")  # doctest: +SKIP
    """
    from mst_cli.calibration.calibration import calibrate as run_calibration  # deferred: scipy.optimize, 330 ms

    params = _checked_fit_options(mechanics, params, table_size)
    check_argument_order(design, load_test, "calibrate")
    doc = load_design(design)
    _check_out(out)  # a bad output path is refused before any work
    name = design_file or (design if isinstance(design, (str, Path)) else design.name)
    options: dict[str, Any] = {"gain_sel": gain_sel, "res": res, "table_size": table_size, "progress": progress}
    options.update(mechanics=mechanics, params=params, use_branches=use_branches, missing_force=missing_force)
    result = run_calibration(doc, name, load_test, **options)
    if out is not None:
        _write_calibration(Path(out), result, plot, {"offset": offset_table, "shear": shear_table}, progress)
    return result


def _write_calibration(
    out: Path, result: Calibration, plot: bool, tables: dict[str, bool], progress: Callable[[str], None] | None
) -> None:
    """Every file of a calibration into ``out``, then the tables asked for."""
    result.write(out, plot=plot)
    _write_tables(out, result, [k for k, asked in tables.items() if asked], progress)


# what each table's C header says it cannot know
TABLE_LIMITS = {
    "offset": "what the tilt rung leaves out (docs/design.md section 4.2); the table's own error between nodes",
    "shear": "what the general-load model leaves out (docs/design.md sections 4.4, 4.5: the press taken as "
    "centred, friction cone |Fx|, |Fy| <= 0.5 Fz); the table's own error between nodes",
}


def _write_tables(out: Path, result: Calibration, kinds: Sequence[str], progress: Callable[[str], None] | None) -> None:
    """The tables of ``kinds`` beside the calibrated.yaml just written (inverse_table.npz,
    shear_table.npz: current, hashed with it and its calibration.json) and, with a chip setting,
    their C headers from every other node."""
    if not kinds:
        return
    # deferred: the calibrate layer, as calibrate's
    from mst_cli.calibration.calibration_json import CALIBRATED_YAML
    from mst_cli.estimation.table_reader import tables_for
    from mst_cli.firmware.table_header import KIND_TEXT, table_header
    from mst_cli.readout.reading import ForceReader

    model = out / CALIBRATED_YAML
    doc = load_design(model)
    mech = choose_mechanics(None, doc.accuracy_rel, doc.mechanics).mechanics
    reader = ForceReader.open(doc, model, mech, result.header_setting)
    lever = reader.record.lever_factor() if reader.record is not None else 1.0
    for kind in kinds:
        if progress is not None:
            progress(f"building the {kind} table (the model at every node)")
        table, coarse = tables_for(model, doc, reader.inverse_map, lever, mech, kind)
        with staged(out) as st:
            table.save(st.path(table.file_name))
            if result.header_setting is not None:
                sources = f"{CALIBRATED_YAML} ({mech}, lever factor {lever:.4g})"
                text = table_header(
                    coarse, reader.inverse_map, result.header_setting, doc.name, sources, [TABLE_LIMITS[kind]]
                )
                st.write_text(str(KIND_TEXT[kind]["file"]), text)


def _checked_fit_options(mechanics: str, params: Sequence[str] | str | None, table_size: int) -> tuple[str, ...]:
    """The parameter names to fit, after the rules of --mechanics, --params (known names, each
    once) and --table-size."""
    from mst_cli.calibration.fit import DEFAULT_PARAMETERS  # deferred: the calibrate layer, 5 ms measured

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
    estimate: str = "none",
):
    # deferred: the calibrate layer, 30 ms measured (mst simulate does not pay it)
    from mst_cli.calibration.chip_columns import check_chips_match
    from mst_cli.calibration.loadtest import check_field_unit, parse_readings, read_text, setting_of
    from mst_cli.readout.reading import ForceReader

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
        check_chips_match(str(readings), rd.chips, len(doc.chips_mm), estimate)
        setting = setting or rd.setting
    reader = ForceReader.open(doc, model_file, choice.mechanics, setting)
    if rd is not None:
        check_field_unit(rd, float(reader.inverse_map.B_abs_T[0]), float(reader.inverse_map.B_abs_T[-1]))
    if reader.warning and warn is not None:
        warn(reader.warning)
    return reader, rd, setting


# what ``mst read --estimate`` can add to the force; a new estimate is one entry here and one
# branch in :func:`_estimator`
ESTIMATES = ("none", "offset", "shear")


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
    track_zero: bool = False,
) -> ForceReadings:
    """MLX90393 readings to forces with a calibrated model (``mst read READINGS.csv``).

    Parameters
    ----------
    model, readings : str, Path or Document; str or Path
        calibrated.yaml (or any design file: then forces are the design's, not the print's, and
        ``warn`` is told so); a CSV with Bx_uT, By_uT, Bz_uT (or raw codes with ``gain_sel``/
        ``res``); force_N, the reference; time_s, cycle, branch, T_C read too.
    out, warn : str or Path; callable, optional
        Folder to write forces.csv into (and a table ``estimate`` built); gets a sentence when the
        model does not match calibration.json beside it (docs/calibration.md).
    estimate, estimate_offset, polish, tare, track_zero : {"none", "offset", "shear"}, bool, bool, int, bool
        "offset" (or ``estimate_offset``): x, y, the force corrected (docs/design.md 4.2);
        "shear": Fx, Fy of a press taken as centred (4.5); from the model's tables, with 1-sigma
        and flags; ``polish`` by the exact solve; ``tare``: readings at no load; ``track_zero``:
        re-zero at every rest, with the calibration's recovery and drift (``--track-zero``).

    Returns
    -------
    ForceReadings
        ``.force_N`` (n,) N, NaN where flagged (never extrapolated); ``.regime``, ``.flag`` (ok,
        above_calibrated, below_range, above_range, saturated); ``.summary()``, ``.csv()``.

    Raises
    ------
    InputError
        A bad file or option, naming it; an estimate the layout cannot identify anywhere.

    Examples
    --------
    >>> forces = mst.read("cal/calibrated.yaml", "readings.csv", estimate="offset", out="o")  # doctest: +SKIP
    """
    estimate = _checked_estimate("offset" if estimate_offset else estimate, max_offset_sigma_mm, tare)
    reader, rd, _ = _reader(model, model_file, mechanics, gain_sel, res, False, readings, out, warn, estimate)
    offsets, built = _estimator(reader, estimate, mechanics, model_file or model, max_offset_sigma_mm, polish, warn)
    result = reader.read(rd, offsets, tare, track_zero)
    _write_forces(out, result.csv(), built)
    return result


def _checked_estimate(estimate: str, max_offset_sigma_mm: float, tare: int = 0) -> str:
    _one_of("--estimate", estimate, ESTIMATES)
    if isinstance(tare, bool) or not isinstance(tare, int) or tare < 0:
        raise InputError("--tare", tare, "a whole number of readings at no load (0: no tare)")
    if not (max_offset_sigma_mm > 0 and math.isfinite(max_offset_sigma_mm)):
        raise InputError("--max-offset-sigma-mm", max_offset_sigma_mm, "must be a positive number of mm")
    return estimate


def _estimator(reader, estimate: str, mechanics: str | None, model_file, max_sigma_mm: float, polish, warn):
    """(the reader of ``estimate``, or None; the table it built, to be written, or None).
    ``polish`` None: a live stream (never polished). InputError when the layout cannot identify
    the estimate anywhere in its range."""
    # deferred: the calibrate layer, as _reader
    from mst_cli.estimation.table_reader import (
        OffsetTableReader,
        ShearTableReader,
        offset_table_reader,
        shear_table_reader,
        two_chip_reader,
    )

    if estimate == "none":
        return None, None
    if not isinstance(model_file, (str, Path)):
        raise InputError("model_file", None, "name the model file: its offset table stands beside it")
    doc = reader.document
    mech = choose_mechanics(mechanics, doc.accuracy_rel, doc.mechanics).mechanics
    lever = reader.record.lever_factor() if reader.record is not None else 1.0
    offsets: OffsetTableReader | ShearTableReader
    if estimate == "shear" and len(doc.chips_mm) > 1:
        return two_chip_reader(doc, reader.inverse_map, lever, mech, bool(polish), warn), None
    if estimate == "shear":
        offsets, note = shear_table_reader(doc, reader.inverse_map, lever, Path(model_file), mech, bool(polish))
    else:
        offsets, note = offset_table_reader(
            doc, reader.inverse_map, lever, Path(model_file), mech, max_sigma_mm, bool(polish)
        )
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
    tare: int = 0,
    columns: str | None = None,
    send: str | None = None,
) -> SerialSamples:
    """A live MLX90393 stream to forces (``mst read --serial PORT``), through :func:`read`'s steps:
    the same readings give the same forces.csv, with a ``time_s`` column first.

    Parameters
    ----------
    model, port, out : str, Path or Document; str; str or Path, optional
        The calibrated model (as :func:`read`'s); the serial port; forces.csv's folder.
    baud, count, timeout_s, raw, estimate, tare : int, int, float, bool, str, int
        Stop when the port closes, after ``count`` samples, ``timeout_s`` of silence or Ctrl-C;
        the rest as :func:`read`'s. ``show`` gets each sample's line, ``status`` one at the start.
    columns, send : str, optional
        Which number of a line is which (:mod:`mst_cli.io.line_columns`); text sent at the start
        and after each line, for a sketch that prints only when asked.

    Returns
    -------
    SerialSamples
        ``.samples``, ``.forces`` (:class:`ForceReadings`), ``.skipped`` and ``.bad`` lines.

    Raises
    ------
    InputError
        A bad option, a port that cannot be opened, or a stream that gave no sample, naming it.

    Examples
    --------
    >>> mst.read_serial("cal/calibrated.yaml", "/dev/ttyACM0", count=100)  # doctest: +SKIP
    """
    from mst_cli.readout.live import read_stream  # deferred: as _reader's

    estimate = _checked_estimate(estimate, max_offset_sigma_mm, tare)
    opts = _live_options(port, baud, count, timeout_s, raw, tare, columns, send)
    reader, _, setting = _reader(model, model_file, mechanics, gain_sel, res, raw, None, out, warn)
    offsets, built = _estimator(reader, estimate, mechanics, model_file or model, max_offset_sigma_mm, None, warn)
    samples = read_stream(reader, port, opts, setting, show, offsets, status, warn)
    _write_forces(out, samples.csv(), built)
    return samples


def _write_forces(out: str | Path | None, forces_csv: str, built) -> None:
    """forces.csv (and a table ``built`` on the way, to keep) into ``out``, atomically; nothing
    without ``out``."""
    if out is not None:
        with staged(Path(out)) as st:
            st.write_text("forces.csv", forces_csv)
            if built is not None:
                built.save(st.path(built.file_name))


def _live_options(port, baud, count, timeout_s, raw, tare, columns, send):
    """The stream's options, checked: a port's name, a finite positive timeout."""
    from mst_cli.readout.live import LiveOptions  # deferred: the calibrate layer, as _reader's

    if not isinstance(port, str) or not port.strip():
        raise InputError("--serial", port, "a serial port's path, such as /dev/ttyACM0 or COM3")
    if timeout_s is not None and not (math.isfinite(timeout_s) and timeout_s > 0):
        raise InputError("--timeout", timeout_s, "a positive, finite number of seconds")
    return LiveOptions(baud, count, timeout_s, raw, tare, column_map(columns), _request(send))


def _request(send: str | None) -> bytes | None:
    """The bytes of ``--send`` (backslash escapes such as \\n read), None without one."""
    if send is None:
        return None
    if not send:
        raise InputError("--send", send, "a byte or a line to send for each sample (e.g. 'r' or 'read\\n')")
    text = send.encode("latin-1", "backslashreplace").decode("unicode_escape")
    return text.encode("utf-8")
