"""``mst read --serial``: a live stream read in batches through the one pipeline of files.

Every line waiting on the port is parsed at once (:class:`~mst_cli.io.serial_lines.LineSource`
batches), its samples are added to a :class:`StreamRecord` -- the readings file the stream
amounts to, the numbers as the sketch wrote them -- and the new rows are read together by
:meth:`~mst_cli.readout.reading.ForceReader.read` (the tare, the temperature law, no load,
the estimate, the branch), then shown one line per sample. A batch is estimated in one
vectorised call, so the reader keeps up with the chip whatever the rate, as long as a batch
takes less time than its samples took to arrive.

forces.csv is the whole recording read again at the end by the same call as a file's: the
branch of a reading and the dead band are decided on the whole sequence, as a file's are, so
the stream's forces.csv is the file's with one column more, ``time_s``: the host's arrival
time (s from the start; not the rig's clock: a batch arrives at once, so branches go by row
order). A line that is no sample is skipped and counted; a line with numbers no chip gives is
skipped and counted apart (never the end of the session); after a few unrecognised lines the
session says so, quoting one.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np

from mst_cli.calibration.chip_columns import chip_column_names
from mst_cli.calibration.loadtest import CODE_COLUMNS, UT_COLUMNS, Readings, beyond_error, field_of, fields_of
from mst_cli.calibration.temperature_fit import T_COLUMN
from mst_cli.errors import InputError
from mst_cli.io.line_columns import ColumnMap
from mst_cli.io.serial_lines import LineSample, LineSource, SampleParser
from mst_cli.model.chip import ChipSetting
from mst_cli.readout.reading import ForceReader, ForceReadings

UNRECOGNISED_NOTE = 5  # unrecognised lines before the session says so (once)
TIME_COLUMN = "time_s"


class _Rows:
    """A float or bool array that grows by blocks of rows (appended in amortised O(rows), read
    as one array): a long session's fields without re-joining them at every batch."""

    def __init__(self, shape: tuple[int, ...], dtype: type):
        self._a: np.ndarray = np.empty((64, *shape), dtype=dtype)
        self.n = 0

    def extend(self, block: np.ndarray) -> None:
        if self.n + len(block) > len(self._a):
            grown = np.empty((max(2 * len(self._a), self.n + len(block)), *self._a.shape[1:]), dtype=self._a.dtype)
            grown[: self.n] = self._a[: self.n]
            self._a = grown
        self._a[self.n : self.n + len(block)] = block
        self.n += len(block)

    def __getitem__(self, rows: slice) -> np.ndarray:
        return self._a[: self.n][rows]


@dataclass
class StreamRecord:
    """The samples of a stream as a readings file holds them: the cells as written, every
    chip's field (T), saturated, the chip's temperature when the lines carry one."""

    source: str
    raw: bool
    chips: int
    setting: ChipSetting | None
    cells: list[list[str]] = field(default_factory=list)
    times_s: list[float] = field(default_factory=list)
    with_T: bool | None = None  # decided by the first sample

    def __post_init__(self) -> None:
        self._B_T = _Rows((self.chips, 3), float)
        self._saturated = _Rows((), bool)

    def __len__(self) -> int:
        return len(self.cells)

    @property
    def B_T(self) -> np.ndarray:
        """(n, chips, 3) every sample's fields in T."""
        return self._B_T[:]

    def add(self, s: LineSample, t_s: float) -> None:
        """One sample (:meth:`add_many`); its InputError raised."""
        for _, exc in self.add_many([s], t_s):
            raise exc

    def add_many(self, samples: list[LineSample], t_s: float) -> list[tuple[int, InputError]]:
        """The samples that arrived together at ``t_s``, their fields checked at once; the
        (index, InputError) of each that is one no chip gives (a code or field beyond the
        setting), or that drops or adds the temperature the first sample had: not added."""
        if not samples:
            return []
        if self.raw and self.setting is None:
            field_of((0.0, 0.0, 0.0), self.raw, self.setting, self.source)  # raises: raw codes need a setting
        values = np.array([s.values for s in samples], dtype=float).reshape(-1, 3)
        B, sat, beyond = fields_of(values, self.raw, self.setting)
        B, sat, beyond = B.reshape(-1, self.chips, 3), sat.reshape(-1, self.chips), beyond.reshape(-1, 3 * self.chips)
        bad_rows = np.asarray(beyond.any(axis=1))
        errors: list[tuple[int, InputError]] = []
        kept: list[int] = []
        for i, s in enumerate(samples):
            where = f"{self.source} sample {len(self) + 1}"  # the cells of those kept are in already
            if self.with_T is not None and (s.T_C is not None) != self.with_T:
                had = "had" if self.with_T else "had no"
                errors.append((i, InputError(where, s.T_cell, f"the first sample's lines {had} T")))
            elif bad_rows[i]:
                errors.append((i, self._beyond(s, where)))
            else:
                self.with_T = s.T_C is not None
                kept.append(i)
                self.cells.append([*s.cells, *([s.T_cell] if s.T_cell is not None else [])])
        self._B_T.extend(B[kept])
        self._saturated.extend(np.asarray(sat[kept].any(axis=1)))
        self.times_s.extend([t_s] * len(kept))
        return errors

    def _beyond(self, s: LineSample, where: str) -> InputError:
        """The error of the first chip of ``s`` with a value beyond the setting."""
        for k in range(self.chips):
            xyz = s.values[3 * k : 3 * k + 3]
            if fields_of(np.array(xyz), self.raw, self.setting)[2].any():
                return beyond_error(xyz, self.raw, self.setting, where, self._names(k))
        raise AssertionError("no value beyond the setting")

    def _names(self, chip: int) -> tuple[str, str, str]:
        if chip == 0:
            return CODE_COLUMNS if self.raw else UT_COLUMNS
        return chip_column_names(chip + 1, self.raw)

    def header(self) -> list[str]:
        names = [c for k in range(self.chips) for c in self._names(k)]
        return names + ([T_COLUMN] if self.with_T else [])

    def readings(self, start: int = 0, stop: int | None = None) -> Readings:
        """Samples ``start`` to ``stop`` as a readings file (lines: the samples' numbers)."""
        stop = len(self) if stop is None else stop
        B = self._B_T[start:stop]
        return Readings(
            source=self.source,
            header=self.header(),
            rows=self.cells[start:stop],
            lines=list(range(start + 1, stop + 1)),
            B_T=B[:, 0],
            saturated=self._saturated[start:stop],
            force_N=None,
            raw=self.raw,
            setting=self.setting,
            B_chips_T=B if self.chips > 1 else None,
        )


@dataclass
class SerialSamples:
    """What a stream gave: its record, the forces of the whole recording, and the lines skipped
    (no sample) and bad (numbers no chip gives), one of each quoted."""

    record: StreamRecord
    forces: ForceReadings
    skipped: int
    bad: int
    first_skipped: str | None = None
    first_bad: tuple[str, str] | None = None

    @property
    def samples(self) -> list[list[str]]:
        return self.record.cells

    def csv(self) -> str:
        """forces.csv: time_s, then what the same readings give from a file."""
        lines = self.forces.csv().splitlines()
        out = [f"{TIME_COLUMN},{lines[0]}"]
        out += [f"{t:.4f},{line}" for t, line in zip(self.record.times_s, lines[1:])]
        return "\n".join(out) + "\n"

    def line(self) -> str:
        """The closing line of the session."""
        text = f"{len(self.record)} samples, {self.skipped} lines skipped (not a sample)"
        if self.bad:
            assert self.first_bad is not None
            text += f", {self.bad} bad lines skipped (first: {self.first_bad[0]!r}: {self.first_bad[1]})"
        return text


@dataclass
class LiveOptions:
    """How a stream is read: ``count`` samples at most, ``timeout_s`` of silence, ``tare`` the
    first samples at no load, ``columns`` the lines' column map (None: by the line),
    ``request`` bytes to send for each sample (a sketch that prints when asked)."""

    baud: int = 115200
    count: int | None = None
    timeout_s: float | None = None
    raw: bool = False
    tare: int = 0
    columns: ColumnMap | None = None
    request: bytes | None = None


def read_stream(
    reader: ForceReader,
    port: str,
    opts: LiveOptions,
    setting: ChipSetting | None,
    show: Callable[[str], None],
    offsets=None,
    status: Callable[[str], None] | None = None,
    warn: Callable[[str], None] | None = None,
) -> SerialSamples:
    """Read ``port`` until it closes, ``opts.count`` samples, ``opts.timeout_s`` of silence or
    Ctrl-C; each batch through ``reader.read`` (``offsets``: the estimate), each sample's line
    through ``show``; ``status`` once the port is open. InputError when no sample came."""
    src = LineSource(port, opts.baud, opts.timeout_s, opts.request)
    if status is not None:
        status(f"{reader.document.name}: reading {port} at {opts.baud} baud (Ctrl-C to stop)")
    chips = len(reader.document.chips_mm)
    record = StreamRecord(port, opts.raw, chips, setting)
    parser = SampleParser(opts.raw, opts.columns, chips)
    live = _Live(reader, offsets, opts.tare, show)
    arriving = src.waiting()
    try:
        _read_batches(arriving, parser, record, live, opts.count, warn)
    except KeyboardInterrupt:
        pass
    finally:
        arriving.close()  # the reading thread ends before the port closes
        src.close()
    if src.cut_off is not None:
        parser.bad += 1
        parser.first_bad = parser.first_bad or (src.cut_off.strip(), "cut off: the port closed mid-line")
    if not len(record):
        quoted = f" (e.g. {parser.first_skipped!r})" if parser.first_skipped else ""
        raise InputError(
            port,
            f"{parser.skipped + parser.bad} lines",
            f"gave no sample{quoted}: lines of x, y, z per chip are read (give --columns for another order)",
        )
    tare = opts.tare
    if tare > len(record):
        if warn is not None:
            warn(f"--tare {tare}: only {len(record)} samples came; tared on them")
        tare = len(record)
    made = live.estimates() if live.shown == len(record) else None  # Ctrl-C mid-batch: estimate afresh
    forces = reader.read(record.readings(), offsets, tare, estimated=made)
    return SerialSamples(record, forces, parser.skipped, parser.bad, parser.first_skipped, parser.first_bad)


def _read_batches(
    arriving: Iterator[list[tuple[float, list[str]]]],
    parser: SampleParser,
    record: StreamRecord,
    live: _Live,
    count: int | None,
    warn: Callable[[str], None] | None,
) -> None:
    """Every batch ``arriving`` (:meth:`LineSource.waiting`) into ``record`` (a sample no chip
    gives is a bad line), all that waited shown by ``live`` at once, until the port ends or
    ``count`` samples came."""
    said: set[str] = set()
    t0 = time.monotonic()
    for waited in arriving:
        for t, batch in waited:
            lines = iter(batch)
            while count is None or len(record) < count:  # again while bad samples fell short of count
                samples, texts = _samples(parser, lines, None if count is None else count - len(record))
                if not samples:
                    break
                for i, exc in record.add_many(samples, t - t0):
                    parser.bad += 1
                    parser.first_bad = parser.first_bad or (texts[i].strip(), str(exc))
        _say_once(parser, len(record), said, warn)
        live.show_new(record)
        if count is not None and len(record) >= count:
            return


def _samples(parser: SampleParser, lines: Iterator[str], most: int | None) -> tuple[list[LineSample], list[str]]:
    """The next samples of ``lines`` (at most ``most``) and the lines they came from."""
    samples: list[LineSample] = []
    texts: list[str] = []
    for line in lines:
        sample = parser.feed(line)
        if sample is not None:
            samples.append(sample)
            texts.append(line)
            if most is not None and len(samples) >= most:
                break
    return samples, texts


def _say_once(parser: SampleParser, samples: int, said: set[str], warn: Callable[[str], None] | None) -> None:
    """While running: a note once a few lines were not recognised, and at the first bad line."""
    if warn is None:
        return
    if parser.skipped >= UNRECOGNISED_NOTE and "skipped" not in said:
        said.add("skipped")
        warn(
            f"{parser.skipped} lines are no sample so far ({samples} samples), e.g. {parser.first_skipped!r}: "
            "lines of x, y, z [t] per chip are read; --columns names another order (presets: xyz, xyzt, "
            "reskin, anyskin)"
        )
    if parser.bad and "bad" not in said:
        said.add("bad")
        assert parser.first_bad is not None
        warn(f"skipped a bad line {parser.first_bad[0]!r}: {parser.first_bad[1]} (counted; the session goes on)")


@dataclass
class _Live:
    """The lines shown while reading: each new batch read by the pipeline (after the tare's
    samples have come, with the shift they give)."""

    reader: ForceReader
    offsets: object
    tare: int
    show: Callable[[str], None]
    shown: int = 0
    shift_uT: float | None = None
    parts: list = field(default_factory=list)  # each batch's estimates, kept for the whole recording

    def estimates(self):
        """The estimates of every sample shown (None without an estimate): the batches' own, not
        made twice (a reading's estimate is its own, whichever batch it came in)."""
        if not self.parts:
            return None
        return type(self.parts[0]).concat(self.parts)

    def show_new(self, record: StreamRecord) -> None:
        n = len(record)
        if n <= self.shown or n < self.tare:
            return  # nothing new, or the tare's samples still coming
        if self.tare and self.shift_uT is None:
            self.shift_uT = self.reader.tare_shift_uT(record.readings(0, self.tare), self.tare)
        got = self.reader.read(record.readings(self.shown, n), self.offsets, tare_shift_uT=self.shift_uT)  # type: ignore[arg-type]
        if got.offset is not None:
            self.parts.append(got.offset)
        B_abs = np.linalg.norm(got.readings.B_T, axis=1)
        for i in range(n - self.shown):
            self.show(f"{self.shown + i + 1:6d}  {_terminal(got, i)}  |B| {B_abs[i] * 1e3:.4f} mT")
        self.shown = n


def _terminal(got: ForceReadings, i: int) -> str:
    """One sample's force, regime, flag, branch and estimate, as a person reads them."""
    f, fl = float(got.force_N[i]), str(got.flag[i])
    text = f"F = {f:8.3f} N  regime {int(got.regime[i])}" if np.isfinite(f) else f"F = {'-':>8}    "
    if fl != "ok":
        text += f"  {fl}"
    if got.branches is not None and got.branches.branch[i] not in ("", "loading"):
        text += f"  {got.branches.branch[i]}"
    if got.offset is not None:
        text += got.offset.terminal(i)
    return text
