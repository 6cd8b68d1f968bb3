"""A serial port for tests and benchmarks: a pseudo-terminal fed a board's bytes (a writer
thread, at a given rate of lines a second or as fast as the port takes them) and read by
``api.read_serial`` as a board's stream would be."""

from __future__ import annotations

import os
import pty
import threading
import time
import tty

import numpy as np

from mst_cli import api


class PtyFeed:
    """A pseudo-terminal whose master a thread feeds ``lines`` (bytes, each with its line end),
        ``rate`` lines a second (None: at once), from :meth:`start` (at once unless ``start`` is
    False). ``port`` is the slave's path; close() when read."""

    def __init__(self, lines: list[bytes], rate: float | None = None, batch: int = 20, start: bool = True):
        self.master, self.slave = pty.openpty()
        tty.setraw(self.slave)
        self.port = os.ttyname(self.slave)
        self.lines, self.rate, self.batch = lines, rate, batch
        self.received: bytes = b""  # what the reader sent (a sketch that prints when asked)
        self._thread = threading.Thread(target=self._feed, daemon=True)
        if start:
            self.start()

    def start(self) -> None:
        """Start feeding (a board that starts printing)."""
        self._thread.start()

    def _feed(self) -> None:
        t0 = time.perf_counter()
        try:
            for i in range(0, len(self.lines), self.batch):
                if self.rate is not None:  # in step with the clock: a board at its rate
                    time.sleep(max(0.0, t0 + i / self.rate - time.perf_counter()))
                os.write(self.master, b"".join(self.lines[i : i + self.batch]))
        except OSError:
            pass  # the reader closed the port first

    def close(self) -> None:
        if self._thread.is_alive():
            self._thread.join(timeout=10)
        os.close(self.master)
        os.close(self.slave)


def read_fed_lines(model, lines: list[bytes], rate: float | None = None, **options):
    """(api.read_serial's result, the lines it showed) of ``lines`` written to a pseudo-terminal;
    ``options`` go to read_serial (give count, or a timeout_s for a stream that ends)."""
    feed = PtyFeed(lines, rate)
    shown: list[str] = []
    try:
        got = api.read_serial(model, feed.port, show=shown.append, **options)
    finally:
        feed.close()
    return got, shown


def read_fed_stream(model, B_uT: np.ndarray, **options):
    """(api.read_serial's result, the lines it showed) of the readings ``B_uT`` (n, 3) written to
    a pseudo-terminal; ``options`` go to read_serial (count is the readings' number)."""
    lines = [f"{b[0]:.4f},{b[1]:.4f},{b[2]:.4f}\r\n".encode() for b in B_uT]
    return read_fed_lines(model, lines, count=len(B_uT), **options)
