"""One sample per line from a serial port, as MLX90393 sketches print them.

Accepted lines (case-insensitive; anything else -- banners, status lines, "Unable to read XYZ
data" -- is skipped and counted):

* labelled: ``X: 12.3 \\tY: -4.5 \\tZ: 321.0 uTesla`` (Adafruit_MLX90393's ``basicdemo``),
  ``X:12.3,Y:-4.5,Z:321.0`` (Arduino serial plotter), ``Bx=12.3 By=-4.5 Bz=321.0 uT``,
  ``magX[-0.45] magY[1.50] magZ[3072.19] temperature(C)[24.50]`` (SparkFun's example):
  labels X/Y/Z, optionally prefixed B or mag, then ``:``, ``=`` or ``[``; a temperature label
  (T, temp, temperature, optionally ``(C)``) gives the chip's temperature in degC;
* one axis per line, X then Y then Z: ``X: 12.3456 uT`` / ``Y: -4.5000 uT`` / ``Z: 321.0000 uT``
  (the same sketch's ``readData`` print; :class:`SampleParser` joins the three lines);
* bare numbers separated by tabs, spaces, commas or semicolons (``-0.45 1.50 3072.19 24.50``,
  ReSkin's and AnySkin's tab-separated chips): which number is which is the column map's
  (:mod:`~mst_cli.io.line_columns`: ``--columns``, a header line ``X,Y,Z,T`` said before, or
  x y z [t] per chip by the count);
* units: ``uT``, ``uTesla``, ``µT``, ``microtesla`` or none (microtesla); ``mT`` (x 1000),
  ``G``/``gauss`` (x 100), ``mG`` (x 0.1). A unit after a number applies to it; a single unit at
  the end of the line applies to all;
* raw codes (``mst read --raw``): the same layouts with integers, no unit.

A line that has the form of a sample but numbers no chip gives (``1e999``, ``nan``, ``ovf``, a
fraction where a raw code belongs, a temperature outside the chip's -40..125 degC) is *bad*:
skipped and counted apart, never the end of the stream. Lines end in LF, CRLF or a bare CR.

The port: on POSIX it is opened with ``os.open`` and set raw with ``termios`` at the given baud
rate (a pseudo-terminal works the same way); no dependency. Elsewhere pyserial is used when it
is installed. A regular file or FIFO is read as it is (for replaying a captured stream).
"""

from __future__ import annotations

import contextlib
import errno
import functools
import math
import os
import queue
import re
import select
import stat
import threading
import time
from collections.abc import Generator, Iterator
from typing import NamedTuple

from mst_cli.io.line_columns import ColumnMap, default_map, header_map

NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf(?:inity)?|ovf)"
UNIT = r"(?:uT(?:esla)?|µT(?:esla)?|μT(?:esla)?|microtesla|mT|mG|G|gauss)"
UNIT_SCALE_uT = {
    "ut": 1.0,
    "utesla": 1.0,
    "µt": 1.0,
    "µtesla": 1.0,
    "μt": 1.0,
    "μtesla": 1.0,
    "microtesla": 1.0,
    "mt": 1000.0,
    "mg": 0.1,
    "g": 100.0,
    "gauss": 100.0,
}
T_C_RANGE = (-40.0, 125.0)  # the MLX90393's operating range: a temperature outside is a bad line
LABELLED = re.compile(
    rf"(?<![A-Za-z])(?:B|mag)?\s*([XYZ])\s*(?:[:=]|\[)\s*({NUMBER})\s*\]?\s*({UNIT})?(?![A-Za-z])", re.IGNORECASE
)
TEMPERATURE = re.compile(
    rf"(?<![A-Za-z])(?:temperature|temp|T)\s*(?:\(\s*[°]?C\s*\))?\s*(?:[:=]|\[)\s*({NUMBER})", re.IGNORECASE
)
BARE = re.compile(rf"^\s*(?:{NUMBER})(?:\s*[,;\s]\s*(?:{NUMBER}))*\s*[,;]?\s*({UNIT})?\s*$", re.IGNORECASE)
BARE_NUMBER = re.compile(NUMBER, re.IGNORECASE)
TRAILING_UNIT = re.compile(rf"({UNIT})\s*$", re.IGNORECASE)
PLAIN_NUMBER = r"[-+]?\d+(?:\.\d*)?"
# digits and points, one separator throughout ("-0.45,1.50,3072.19", tab-separated chips): a bare line
PLAIN = re.compile(rf"{PLAIN_NUMBER}(?:(?P<sep>[,;\t ]){PLAIN_NUMBER}(?:(?P=sep){PLAIN_NUMBER})*)?")
AXIS_LETTER = re.compile(r"[XYZ]", re.IGNORECASE)  # a labelled line names an axis; a bare one has none
HEADER_SPLIT = re.compile(r"\s*[,;\t]\s*|\s+")
LINE_END = re.compile(rb"\r\n|\r|\n")
READ_BYTES = 1 << 16


class LineSample(NamedTuple):
    """One sample of a line: ``values`` x, y, z of every chip (3 k; microtesla, or raw codes),
    ``cells`` the same as written (as forces.csv echoes them), the chip's temperature (degC)
    and its cell, None when the line has none."""

    values: tuple[float, ...]
    cells: tuple[str, ...]
    T_C: float | None = None
    T_cell: str | None = None


class BadLine(ValueError):
    """A line in a sample's form whose numbers no chip gives: the reason."""


def parse_line(line: str, raw: bool = False, columns: ColumnMap | None = None, chips: int = 1) -> LineSample | None:
    """The sample of one line (:class:`LineSample`), None when it is none; BadLine when it is
    one whose numbers no chip gives."""
    line = line.strip()
    if not line:
        return None
    plain = PLAIN.fullmatch(line)
    if plain is not None:  # the commonest stream, read without the general forms' searches
        return _bare(line.split(plain.group("sep")) if plain.group("sep") else [line], "", raw, columns, chips)
    if chips == 1 and AXIS_LETTER.search(line) is not None:  # a labelled line names its axes
        found: dict[str, tuple[str, str]] = {}
        for label, number, unit in LABELLED.findall(line):
            found.setdefault(label.lower(), (number, unit))
        if set(found) == {"x", "y", "z"}:
            trailing = TRAILING_UNIT.search(line)
            default = trailing.group(1) if trailing else ""
            values = [_value(found[a][0], found[a][1] or default, raw) for a in "xyz"]
            t = TEMPERATURE.search(line)
            units = [found[a][1] or default for a in "xyz"]
            return _sample(values, [found[a][0] for a in "xyz"], units, t and t.group(1))
    m = BARE.match(line)
    if m is None:
        return None
    numbers = BARE_NUMBER.findall(line[: m.start(1)] if m.group(1) else line)
    return _bare(numbers, m.group(1) or "", raw, columns, chips)


def _bare(numbers: list[str], unit: str, raw: bool, columns: ColumnMap | None, chips: int) -> LineSample | None:
    """The sample of a line of bare ``numbers`` (as written) in ``unit``, placed by ``columns``."""
    where = _placement(columns, len(numbers), chips)
    if where is None:
        return None
    xyz, t_at = where
    values = [_value(numbers[i], unit, raw) for i in xyz]
    return _sample(values, [numbers[i] for i in xyz], [unit] * len(xyz), None if t_at is None else numbers[t_at])


@functools.lru_cache(maxsize=256)
def _placement(columns: ColumnMap | None, n_numbers: int, chips: int) -> tuple[tuple[int, ...], int | None] | None:
    """Where x, y, z (and t) sit among a bare line's ``n_numbers`` numbers (:meth:`ColumnMap.place`),
    found once per map and count: a stream's lines share both."""
    return (columns or default_map(n_numbers, chips) or ColumnMap(group=("x", "y", "z"))).place(n_numbers, chips)


def _sample(values: list[float], cells: list[str], units: list[str], t_cell: str | None) -> LineSample:
    """The sample of parsed values, their cells as written (converted where a unit scaled them)
    and the temperature's cell; BadLine for a temperature no chip reads."""
    if any(units):  # a scaled number is shown converted
        shown = [c if UNIT_SCALE_uT.get(u.lower(), 1.0) == 1.0 else f"{v:.9g}" for c, u, v in zip(cells, units, values)]
    else:
        shown = cells
    if t_cell is None:
        return LineSample(tuple(values), tuple(shown))
    T = float(t_cell)
    lo, hi = T_C_RANGE
    if not lo <= T <= hi:  # NaN fails too
        raise BadLine(f"temperature {t_cell}: the chip reads {lo:g}..{hi:g} degC")
    return LineSample(tuple(values), tuple(shown), T, t_cell)


def _value(number: str, unit: str, raw: bool) -> float:
    v = float(number)
    if not math.isfinite(v):
        raise BadLine(f"{number} is not a finite number")
    if raw:
        if unit or v != int(v):
            raise BadLine(f"{number}{unit}: a raw code is an integer without a unit")
        return v
    v *= UNIT_SCALE_uT.get(unit.lower(), 1.0) if unit else 1.0
    if not math.isfinite(v):
        raise BadLine(f"{number} {unit} is not a finite field")
    return v


class SampleParser:
    """Lines in, samples out: whole-sample lines as :func:`parse_line` (a header line ``X,Y,Z,T``
    sets the column map when ``columns`` is None), and samples printed one axis per line (X, then
    Y, then Z) joined. ``skipped`` counts lines that are no sample (``first_skipped`` quotes
    one), ``bad`` the lines in a sample's form with numbers no chip gives (``first_bad``)."""

    def __init__(self, raw: bool = False, columns: ColumnMap | None = None, chips: int = 1):
        self.raw, self.columns, self.chips = raw, columns, chips
        self.fixed_columns = columns is not None
        self.skipped = self.bad = 0
        self.first_skipped: str | None = None
        self.first_bad: tuple[str, str] | None = None
        self._axes: dict[str, tuple[float, str]] = {}

    def feed(self, line: str) -> LineSample | None:
        if not line or line.isspace():
            return None  # a blank line (a CRLF split across reads, an empty println): nothing to count
        try:
            sample = parse_line(line, self.raw, self.columns, self.chips)
            if sample is not None:
                if self._axes:
                    self._axes = {}
                return sample
            if self._header(line):
                return None
            return self._one_axis(line) if self.chips == 1 else self._skip(line)
        except BadLine as exc:
            self._axes = {}
            self.bad += 1
            self.first_bad = self.first_bad or (line.strip(), str(exc))
            return None

    def _header(self, line: str) -> bool:
        """Whether ``line`` is a header line (names only); its map is kept unless --columns gave one."""
        names = header_map(HEADER_SPLIT.split(line.strip()))
        if names is None:
            return False
        if not self.fixed_columns:
            self.columns = names
        return True

    def _one_axis(self, line: str) -> LineSample | None:
        found = LABELLED.findall(line.strip())
        if len(found) != 1:
            return self._skip(line)
        label, number, unit = found[0]
        axis = label.lower()
        value = _value(number, unit, self.raw)
        if axis != "xyz"[len(self._axes)]:
            self._axes = {}
            if axis != "x":
                return self._skip(line)
        self._axes[axis] = (value, number if UNIT_SCALE_uT.get(unit.lower(), 1.0) == 1.0 else f"{value:.9g}")
        if len(self._axes) < 3:
            return None
        got, self._axes = self._axes, {}
        return LineSample(tuple(got[a][0] for a in "xyz"), tuple(got[a][1] for a in "xyz"))

    def _skip(self, line: str) -> LineSample | None:
        self._axes = {}
        self.skipped += 1
        self.first_skipped = self.first_skipped or line.strip()
        return None


class LineSource:
    """Lines from a serial port (or a file / FIFO), in batches: :meth:`batches` yields every
    complete line waiting at once. ``close()`` when done.

    Reading ends when the port closes (EOF or EIO, as a pseudo-terminal reports a closed
    master) or when no byte arrives for ``timeout_s`` (None: wait for ever). ``request``: bytes
    written when the port opens, after every line received and after a second of silence (a
    sketch that prints only when asked).
    """

    def __init__(self, port: str, baud: int = 115200, timeout_s: float | None = None, request: bytes | None = None):
        self.port, self.baud, self.timeout_s, self.request = port, baud, timeout_s, request
        self._serial = None
        self._fd = None
        self.is_tty = True
        self.cut_off: str | None = None  # a last line without its end, from a port that closed mid-line
        self._stopping = False  # set by :meth:`waiting`'s caller being done: the reading thread ends
        try:
            import termios  # noqa: F401  # deferred: POSIX only (the test of the platform)

            posix = True
        except ImportError:
            posix = False
        if posix:
            mode = os.O_RDWR if request else os.O_RDONLY
            self._fd = os.open(port, mode | os.O_NOCTTY | os.O_NONBLOCK)
            try:
                if stat.S_ISDIR(os.fstat(self._fd).st_mode):
                    raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), port)
                self.is_tty = os.isatty(self._fd)
                if self.is_tty:
                    _set_raw(self._fd, baud)
            except BaseException:
                os.close(self._fd)
                raise
        else:  # pragma: no cover - Windows
            try:
                import serial  # deferred: pyserial, an optional dependency (Windows only)
            except ImportError:
                raise OSError(
                    0, "reading a serial port on this platform needs pyserial (pip install pyserial)", port
                ) from None
            self._serial = serial.Serial(port, baud, timeout=0.2)

    def _write(self, times: int = 1) -> None:
        if not self.request or times <= 0:
            return
        if self._serial is not None:  # pragma: no cover - Windows
            self._serial.write(self.request * times)
            return
        assert self._fd is not None
        with contextlib.suppress(BlockingIOError):  # the port's buffer is full: requests are waiting
            os.write(self._fd, self.request * times)

    def _read(self, wait_s: float) -> bytes | None:
        """Every byte waiting (after up to wait_s for the first); b"" if none came; None at end."""
        if self._serial is not None:  # pragma: no cover - Windows
            return self._serial.read(max(1, self._serial.in_waiting))
        fd = self._fd
        assert fd is not None  # open (set in __init__ unless pyserial reads the port)
        ready, _, _ = select.select([fd], [], [], wait_s)
        if not ready:
            return b""
        chunks: list[bytes] = []
        while True:
            try:
                data = os.read(fd, READ_BYTES)
            except BlockingIOError:
                break
            except OSError as exc:
                if exc.errno != errno.EIO:  # EIO: the other end of a (pseudo-)terminal closed
                    raise OSError(exc.errno, exc.strerror, self.port) from None
                data = b""
            if not data:
                return b"".join(chunks) if chunks else None
            chunks.append(data)
            if len(data) < READ_BYTES:
                break
        return b"".join(chunks)

    def batches(self) -> Iterator[list[str]]:
        """Lists of the complete lines that arrived together (LF, CRLF or a bare CR ends one)."""
        buf = b""
        last = asked = time.monotonic()
        self._write()
        while not self._stopping:
            data = self._read(0.2)
            if data is None:
                break
            if data:
                last = time.monotonic()
                *complete, buf = LINE_END.split(buf + data)
                if complete:
                    self._write(len(complete))
                    yield [line.decode("utf-8", errors="replace") for line in complete]
            elif self.timeout_s is not None and time.monotonic() - last > self.timeout_s:
                break
            elif self.request and time.monotonic() - max(last, asked) > 1.0:
                asked = time.monotonic()
                self._write()  # a request lost (or the sketch was not listening yet)
            if len(buf) > READ_BYTES:  # no line end in 64 KB: not a line protocol
                buf = b""
        if self._stopping:
            return  # the reader is done: a line still arriving is not cut off
        if buf.strip() and self.is_tty:  # a board stopped mid-line: its numbers are cut off
            self.cut_off = buf.decode("utf-8", errors="replace")
        elif buf.strip():  # a captured file's last line without its line end
            yield [buf.decode("utf-8", errors="replace")]

    def waiting(self) -> Generator[list[tuple[float, list[str]]], None, None]:
        """Everything that arrived while the caller was busy: lists of (its arrival time on
        ``time.monotonic``, the batch's lines). The port is read by a thread of its own, so it is
        drained while a batch is estimated (a pseudo-terminal holds 4 kB, a board's USB buffer
        little more: left unread, the board would wait and the batches stay small). close() the
        iterator when done: the thread ends within 0.2 s. The port's errors are raised here."""
        got: queue.SimpleQueue = queue.SimpleQueue()

        def read() -> None:
            try:
                for batch in self.batches():
                    got.put((time.monotonic(), batch))
            except BaseException as exc:  # raised in the caller's thread
                got.put(exc)
            got.put(None)

        thread = threading.Thread(target=read, name=f"read {self.port}", daemon=True)
        thread.start()
        try:
            while True:
                try:
                    items = [got.get(timeout=0.2)]  # a timeout: Ctrl-C is seen while waiting
                except queue.Empty:
                    continue
                while not got.empty():
                    items.append(got.get_nowait())
                for item in items:
                    if isinstance(item, BaseException):
                        raise item
                batches = [item for item in items if item is not None]
                if batches:
                    yield batches
                if None in items:
                    return
        finally:
            self._stopping = True
            thread.join()

    def __iter__(self) -> Iterator[str]:
        for batch in self.batches():
            yield from batch

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
        if self._serial is not None:  # pragma: no cover - Windows
            self._serial.close()
            self._serial = None


def _set_raw(fd: int, baud: int) -> None:
    """8N1, no echo, no line editing, no flow control, at ``baud``."""
    import termios  # deferred: POSIX only (never reached elsewhere)

    attrs = termios.tcgetattr(fd)
    iflag, oflag, cflag, lflag, ispeed, ospeed, cc = attrs
    iflag &= ~(
        termios.IGNBRK
        | termios.BRKINT
        | termios.PARMRK
        | termios.ISTRIP
        | termios.INLCR
        | termios.IGNCR
        | termios.ICRNL
        | termios.IXON
        | termios.IXOFF
    )
    oflag &= ~termios.OPOST
    lflag &= ~(termios.ECHO | termios.ECHONL | termios.ICANON | termios.ISIG | termios.IEXTEN)
    cflag &= ~(termios.CSIZE | termios.PARENB | termios.CSTOPB)
    cflag |= termios.CS8 | termios.CREAD | termios.CLOCAL
    speed = getattr(termios, f"B{baud}", None)
    if speed is not None:
        ispeed = ospeed = speed
    cc = list(cc)
    cc[termios.VMIN] = 1
    cc[termios.VTIME] = 0
    termios.tcsetattr(fd, termios.TCSANOW, [iflag, oflag, cflag, lflag, ispeed, ospeed, cc])
