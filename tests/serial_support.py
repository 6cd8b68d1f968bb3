"""A serial port for tests: a pseudo-terminal fed readings (uT, one per line) and read by
``api.read_serial`` as a board's stream would be."""

from __future__ import annotations

import os
import pty
import tty

import numpy as np

from mst_cli import api


def read_fed_stream(model, B_uT: np.ndarray, **options):
    """(api.read_serial's samples, the lines it showed) of the readings ``B_uT`` (n, 3) written to
    a pseudo-terminal; ``options`` go to read_serial (count is the readings' number)."""
    master, slave = pty.openpty()
    tty.setraw(slave)
    for b in B_uT:
        os.write(master, f"{b[0]:.4f},{b[1]:.4f},{b[2]:.4f}\r\n".encode())
    shown: list[str] = []
    try:
        got = api.read_serial(model, os.ttyname(slave), count=len(B_uT), show=shown.append, **options)
    finally:
        os.close(master)
        os.close(slave)
    return got, shown
