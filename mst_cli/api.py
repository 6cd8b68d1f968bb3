"""mst from Python: the command line's verbs as functions (``import mst_cli as mst``).

Each function takes the options of its command (same names, same defaults, same checks: bad
input raises :class:`~mst_cli.errors.InputError` naming the field, the value and what is
allowed) and returns the typed object the command prints and writes from. Units are in the
names: mm, N, MPa, degrees, T (tesla) in arrays, mT/uT where the name says so.

Each verb imports its own modules when it is called (``import mst_cli`` loads none of them), as
the command line loads only the command it runs: a script that calibrates does not pay for the
design solver or the CAD kernel.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from mst_cli.errors import InputError

if TYPE_CHECKING:
    from mst_cli.calibrate.calibration import Calibration
    from mst_cli.calibrate.reading import ForceReadings, SerialSamples
    from mst_cli.io.schema import Document

__all__ = ["InputError", "load", "load_design", "parse_params", "calibrate", "read",
           "read_serial"]

DEFAULT_PARAMETERS = ("modulus_factor", "wall_offset_mm", "gap_offset_mm", "remanence_factor")


def __getattr__(name: str):
    if name == "CalibrationFailed":       # the fit's own error class, without importing the fit
        from mst_cli.calibrate.fit import CalibrationFailed
        return CalibrationFailed
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
    from mst_cli.io.schema import load_document
    return load_document(path)


def load_design(path: str | Path | Document) -> Document:
    """A design file whose every cell is printable and works (InputError naming the first layer
    that breaks a rule); a Document is checked the same way and returned."""
    from mst_cli.io.schema import design_geometry, load_design_document
    if isinstance(path, (str, Path)):
        return load_design_document(path)[0]
    design_geometry(path)
    return path


def parse_params(text: str) -> tuple[str, ...]:
    """The parameter names of ``--params`` ("modulus_factor,gap_offset_mm")."""
    from mst_cli.calibrate.calibration import parse_params as parse
    return parse(text)


def calibrate(design: str | Path | Document, load_test: str | Path, *, out: str | Path | None = None,
              plot: bool = False, design_file: str | Path | None = None, mechanics: str = "spring",
              params: Sequence[str] | str = DEFAULT_PARAMETERS, gain_sel: int | None = None,
              res: int | None = None, table_size: int = 256,
              progress: Callable[[str], None] | None = None) -> Calibration:
    """Fit a design's print parameters to a load test of the printed sensor (``mst calibrate``).

    Parameters
    ----------
    design : str, Path or Document
        The design file the sensor was printed from (or its loaded Document; then
        ``design_file`` names it in calibration.json).
    load_test : str or Path
        CSV with force_N and Bx_uT, By_uT, Bz_uT (or Bx_code_lsb, By_code_lsb, Bz_code_lsb with
        ``gain_sel`` and ``res``): one row per sample, force in N, field in uT or raw LSB.
    out : str or Path, optional
        Folder to write calibrated.yaml, calibration.json, residuals.csv, lookup.csv and
        force_table.h into (atomically); nothing is written when None.
    plot : bool
        Also draw calibration.png into ``out`` (imports matplotlib).
    mechanics : {"spring", "frame", "continuum"}
        Layer mechanics of the fit; frame and continuum by space mapping on spring.
    params : sequence of str or str
        Parameters to fit (names of :data:`mst_cli.calibrate.fit.PARAMETERS`, or "a,b").
    gain_sel, res : int, optional
        The MLX90393 setting the load test was read at (0-7, 0-3).
    table_size : int
        Entries of lookup.csv (16-4096).

    Returns
    -------
    Calibration
        ``.fit.values`` (fitted parameters, units in their names) and ``.fit.std`` (1 sigma),
        ``.calibrated`` (the design as printed), ``.inverse_map`` (|B| in T -> force in N),
        ``.record`` (calibration.json), ``.summary()``.

    Raises
    ------
    InputError
        A bad file or option. CalibrationFailed: the fit failed (the message says why).
    """
    from mst_cli.calibrate.calibration import calibrate as run
    from mst_cli.io.outputs import check_out_dir
    if isinstance(params, str):
        params = parse_params(params)
    if not 16 <= table_size <= 4096:
        raise InputError("--table-size", table_size, "must be an integer from 16 to 4096")
    design_file = design_file or (design if isinstance(design, (str, Path)) else design.name)
    doc = load_design(design)
    if out is not None:
        check_out_dir(Path(out))              # a bad output path is refused before any work
    result = run(doc, design_file, load_test, mechanics=mechanics, params=params, gain_sel=gain_sel, res=res,
                 table_size=table_size, progress=progress)
    if out is not None:
        result.write(Path(out), plot=plot)
    return result


def _reader(design: str | Path | Document, model_file: str | Path | None, mechanics: str | None,
            gain_sel: int | None, res: int | None, raw: bool, readings: str | Path | None,
            out: str | Path | None, warn: Callable[[str], None] | None):
    from mst_cli.calibrate.loadtest import parse_readings, read_text, setting_of
    from mst_cli.calibrate.reading import ForceReader
    from mst_cli.io.outputs import check_out_dir
    from mst_cli.model.ladder import choose_mechanics

    doc = load_design(design)
    if model_file is None:
        if not isinstance(design, (str, Path)):
            raise InputError("model_file", None, "name the file the Document was loaded from "
                                                 "(its calibration.json stands beside it)")
        model_file = design
    if (gain_sel is None) != (res is None):
        raise InputError("--gain-sel/--res", f"{gain_sel}/{res}", "give both GAIN_SEL and RES, or neither")
    setting = setting_of(gain_sel, res) if gain_sel is not None else None
    if raw and setting is None:
        raise InputError("--gain-sel/--res", None, "--raw codes need the chip setting: give --gain-sel and --res")
    if out is not None:
        check_out_dir(Path(out))
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


def read(model: str | Path | Document, readings: str | Path, *, out: str | Path | None = None,
         model_file: str | Path | None = None, mechanics: str | None = None, gain_sel: int | None = None,
         res: int | None = None, warn: Callable[[str], None] | None = None) -> ForceReadings:
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

    Returns
    -------
    ForceReadings
        ``.force_N`` (n,) in N, NaN where flagged (never extrapolated); ``.regime`` (n,),
        ``.flag`` (n,) one of ok, above_calibrated, below_range, above_range, saturated;
        ``.force_resolution_N`` (n,); ``.summary()``, ``.csv()``.
    """
    from mst_cli.io.outputs import staged
    reader, rd, _ = _reader(model, model_file, mechanics, gain_sel, res, False, readings, out, warn)
    result = reader.read(rd)
    if out is not None:
        with staged(Path(out)) as st:
            st.write_text("forces.csv", result.csv())
    return result


def read_serial(model: str | Path | Document, port: str, *, out: str | Path | None = None,
                model_file: str | Path | None = None, baud: int = 115200, count: int | None = None,
                timeout_s: float | None = None, raw: bool = False, mechanics: str | None = None,
                gain_sel: int | None = None, res: int | None = None, warn: Callable[[str], None] | None = None,
                status: Callable[[str], None] | None = None, show: Callable[[str], None] = print) -> SerialSamples:
    """A live MLX90393 stream to forces (``mst read --serial PORT``): one line per sample goes to
    ``show``; stops when the port closes, after ``count`` samples, ``timeout_s`` seconds of
    silence or Ctrl-C; ``status`` gets a line when reading starts. ``out``: forces.csv of every
    sample (time s, the three values, force N, regime, flag, resolution N)."""
    from mst_cli.io.outputs import staged
    reader, _, setting = _reader(model, model_file, mechanics, gain_sel, res, raw, None, out, warn)
    if status is not None:
        status(f"{reader.document.name}: reading {port} at {baud} baud (Ctrl-C to stop)")
    samples = reader.stream(port, baud, count, timeout_s, raw, setting, show)
    if out is not None:
        with staged(Path(out)) as st:
            st.write_text("forces.csv", samples.csv(reader.inverse_map))
    return samples
