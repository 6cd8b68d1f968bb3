"""mst from Python: the command line's verbs as functions (``from mst_cli import api as mst``).

Each function takes the options of its command (same names, same defaults, same checks: bad
input raises :class:`~mst_cli.errors.InputError` naming the field, the value and what is
allowed) and returns the typed object the command prints and writes from; given ``out=`` it
writes the files the command writes, atomically. Units are in the names: mm, N, MPa, degrees,
T (tesla) in arrays, mT/uT where the name says so.

The command line imports this module, :mod:`mst_cli.errors` and its own modules only: this is
the one door. The layers ``mst simulate`` needs (the sensor, the model, the simulation's files)
are imported here; a verb whose layer costs start-up time ``mst simulate`` should not pay
imports it when called, with the reason and the cost measured (``python -X importtime``).
"""

from __future__ import annotations

from mst_cli.api._calibrating import ESTIMATES as ESTIMATES
from mst_cli.api._calibrating import calibrate, check_argument_order, parse_params, read, read_serial
from mst_cli.api._common import load, load_design
from mst_cli.api._common import tell_rung_solves as tell_rung_solves
from mst_cli.api._designing import design, designed, pareto, run_design
from mst_cli.api._making import check, export, slice
from mst_cli.api._measuring import bench
from mst_cli.api._simulating import offset_map, run_simulate, simulate, simulate_offcentre
from mst_cli.errors import CalibrationFailed, InputError
from mst_cli.io.files import is_machine_fault as is_machine_fault
from mst_cli.io.files import os_error_text as os_error_text
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE
from mst_cli.model.load_path import FINGERTIP_PATCH_MM as FINGERTIP_PATCH_MM

__all__ = [
    "InputError",
    "CalibrationFailed",
    "load",
    "load_design",
    "simulate",
    "simulate_offcentre",
    "offset_map",
    "run_simulate",
    "design",
    "pareto",
    "run_design",
    "designed",
    "export",
    "check",
    "slice",
    "parse_params",
    "calibrate",
    "check_argument_order",
    "read",
    "read_serial",
    "bench",
]
# also here for the command line, which imports nothing else of the package: Interrupted (a
# signal ended a run), SEED_RANGE (--seed's bounds), ESTIMATES (--estimate's choices),
# FINGERTIP_PATCH_MM (--press-width-mm's default), is_machine_fault and os_error_text,
# tell_rung_solves (the progress line before the whole-part rung's solves)


def __getattr__(name: str):
    # SlicerError (PrusaSlicer misbehaved) without importing the slicer before it is asked for
    if name == "SlicerError":
        from mst_cli.cad.slicer import SlicerError  # deferred: the CAD layer, 30 ms measured

        return SlicerError
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
