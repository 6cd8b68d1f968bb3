"""One sample per line from a serial port, as the common Arduino MLX90393 sketches print them.

Accepted line formats (case-insensitive; anything else -- banners, "Unable to read XYZ data",
blank lines -- is skipped and counted):

* labelled: ``X: 12.3 \\tY: -4.5 \\tZ: 321.0 uTesla`` (Adafruit_MLX90393 ``basicdemo``, its
  unified-sensor event),
  ``X:12.3,Y:-4.5,Z:321.0`` (Arduino serial plotter), ``Bx=12.3 By=-4.5 Bz=321.0 uT``,
  ``magX: ... magY: ... magZ: ...``: labels X/Y/Z, optionally prefixed B or mag, then ``:`` or ``=``;
* one axis per line, X then Y then Z: ``X: 12.3456 uT`` / ``Y: -4.5000 uT`` / ``Z: 321.0000 uT``
  (the same sketch's ``readData`` print; :class:`SampleParser` joins the three lines);
* three bare numbers: ``12.3,-4.5,321.0`` or ``12.3 -4.5 321.0`` (tabs, spaces, commas or
  semicolons), x y z in that order;
* units: ``uT``, ``uTesla``, ``µT``, ``microtesla`` or none (microtesla); ``mT`` (x 1000),
  ``G``/``gauss`` (x 100), ``mG`` (x 0.1). A unit after a number applies to it; a single unit at
  the end of the line applies to all three;
* raw codes (``mst read --raw``): the same layouts with integers, no unit.

The port: on POSIX it is opened with ``os.open`` and set raw with ``termios`` at the given baud
rate (a pseudo-terminal works the same way); no dependency. Elsewhere pyserial is used when it
is installed. A regular file or FIFO is read as it is (for replaying a captured stream).
"""

from __future__ import annotations

import os
import re
import select
import time

NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
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
LABELLED = re.compile(rf"(?<![A-Za-z])(?:B|mag)?\s*([XYZ])\s*[:=]\s*({NUMBER})\s*({UNIT})?(?![A-Za-z])", re.IGNORECASE)
BARE = re.compile(rf"^\s*({NUMBER})\s*[,;\s]\s*({NUMBER})\s*[,;\s]\s*({NUMBER})\s*({UNIT})?\s*$", re.IGNORECASE)
TRAILING_UNIT = re.compile(rf"({UNIT})\s*$", re.IGNORECASE)


def parse_line(line: str, raw: bool = False) -> tuple[float, float, float] | None:
    """(x, y, z) in microtesla (or raw codes with ``raw``) from one line, or None."""
    line = line.strip()
    if not line:
        return None
    found: dict[str, tuple[str, str]] = {}
    for label, number, unit in LABELLED.findall(line):
        found.setdefault(label.lower(), (number, unit))
    if set(found) == {"x", "y", "z"}:
        trailing = TRAILING_UNIT.search(line)
        default = trailing.group(1) if trailing else ""
        values = []
        for axis in "xyz":
            number, unit = found[axis]
            values.append(_value(number, unit or default, raw))
        return None if None in values else tuple(values)
    m = BARE.match(line)
    if m:
        values = [_value(n, m.group(4) or "", raw) for n in m.groups()[:3]]
        return None if None in values else tuple(values)
    return None


class SampleParser:
    """Lines in, samples out: whole-sample lines as :func:`parse_line`, and samples printed one
    axis per line (X, then Y, then Z) joined. ``skipped`` counts lines that are neither."""

    def __init__(self, raw: bool = False):
        self.raw = raw
        self.skipped = 0
        self._axes: dict[str, float] = {}

    def feed(self, line: str) -> tuple[float, float, float] | None:
        sample = parse_line(line, self.raw)
        if sample is not None:
            self._axes = {}
            return sample
        found = LABELLED.findall(line.strip())
        axes = {label.lower() for label, _, _ in found}
        if len(found) == 1 and len(axes) == 1:
            label, number, unit = found[0]
            axis = label.lower()
            value = _value(number, unit, self.raw)
            expected = "xyz"[len(self._axes)]
            if value is None or axis != expected:
                self._axes = {}
                if axis != "x" or value is None:
                    self.skipped += 1
                    return None
            self._axes[axis] = value
            if len(self._axes) == 3:
                sample, self._axes = (self._axes["x"], self._axes["y"], self._axes["z"]), {}
                return sample
            return None
        self._axes = {}
        self.skipped += 1
        return None


def _value(number: str, unit: str, raw: bool):
    v = float(number)
    if raw:
        return v if not unit and v == int(v) else None
    return v * (UNIT_SCALE_uT.get(unit.lower(), 1.0) if unit else 1.0)


class LineSource:
    """Lines from a serial port (or a file / FIFO). Iterate; ``close()`` when done.

    Iteration ends when the port closes (EOF or EIO, as a pseudo-terminal reports a closed
    master) or when no byte arrives for ``timeout_s`` (None: wait for ever).
    """

    def __init__(self, port: str, baud: int = 115200, timeout_s: float | None = None):
        self.port, self.baud, self.timeout_s = port, baud, timeout_s
        self._serial = None
        self._fd = None
        try:
            import termios  # noqa: F401  # deferred: POSIX only (the test of the platform)

            posix = True
        except ImportError:
            posix = False
        if posix:
            self._fd = os.open(port, os.O_RDONLY | os.O_NOCTTY | os.O_NONBLOCK)
            try:
                if os.isatty(self._fd):
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

    def _read(self, wait_s: float) -> bytes | None:
        """Up to 4096 bytes; b"" if nothing arrived within wait_s; None at end of stream."""
        if self._serial is not None:  # pragma: no cover - Windows
            data = self._serial.read(4096)
            return data
        fd = self._fd
        assert fd is not None  # open (set in __init__ unless pyserial reads the port)
        ready, _, _ = select.select([fd], [], [], wait_s)
        if not ready:
            return b""
        try:
            data = os.read(fd, 4096)
        except BlockingIOError:
            return b""
        except OSError as exc:
            if exc.errno == 5:  # EIO: the other end of a (pseudo-)terminal closed
                return None
            raise
        return data if data else None

    def __iter__(self):
        buf = b""
        last = time.monotonic()
        while True:
            data = self._read(0.2)
            if data is None:
                break
            if data:
                last = time.monotonic()
                buf += data
                *complete, buf = buf.split(b"\n")
                for raw_line in complete:
                    yield raw_line.decode("utf-8", errors="replace").rstrip("\r")
            elif self.timeout_s is not None and time.monotonic() - last > self.timeout_s:
                break
            if len(buf) > 1 << 16:  # no newline in 64 KB: not a line protocol
                buf = b""
        if buf.strip():
            yield buf.decode("utf-8", errors="replace").rstrip("\r")

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
