"""mst from Python: the command line's verbs as functions (``from mst_cli import api as mst``).

Each function takes the options of its command (same names, same defaults, same checks: bad
input raises :class:`~mst_cli.errors.InputError` naming the field, the value and what is
allowed) and returns the typed object the command prints and writes from; given ``out=`` it
writes the files the command writes, atomically. Units are in the names: mm, N, MPa, degrees,
T (tesla) in arrays, mT/uT where the name says so.

The command line imports this module, :mod:`mst_cli.errors` and its own modules only: this is
the one door. What every verb shares (loading a design: the sensor, the model) is imported
here; each verb family's module (``_simulating``, ``_designing``, ``_calibrating``, ``_making``,
``_measuring``) is imported when one of its names is first asked for, so a command pays for its
own family only (``mst design`` does not load the calibration's and the simulation's verbs:
about 6 ms, ``python -X importtime``). A verb whose layer costs start-up time imports it when
called, with the reason and the cost measured.
"""

from __future__ import annotations

from types import ModuleType
from typing import TYPE_CHECKING

from mst_cli.api._common import load, load_design
from mst_cli.api._common import tell_rung_solves as tell_rung_solves
from mst_cli.errors import CalibrationFailed, InputError
from mst_cli.io.files import is_machine_fault as is_machine_fault
from mst_cli.io.files import os_error_text as os_error_text
from mst_cli.io.outputs import Interrupted as Interrupted
from mst_cli.model.file_keys import SEED_RANGE as SEED_RANGE
from mst_cli.model.load_path import FINGERTIP_PATCH_MM as FINGERTIP_PATCH_MM

if TYPE_CHECKING:
    from mst_cli.api._calibrating import ESTIMATES as ESTIMATES
    from mst_cli.api._calibrating import calibrate, check_argument_order, parse_params, read, read_serial
    from mst_cli.api._designing import design, designed, pareto, run_design
    from mst_cli.api._making import check, export, slice
    from mst_cli.api._measuring import bench
    from mst_cli.api._simulating import offset_map, run_simulate, simulate, simulate_offcentre

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

# each verb's family module, loaded when one of its names is first asked for
_FAMILY = {
    **dict.fromkeys(("ESTIMATES", "calibrate", "check_argument_order", "parse_params", "read", "read_serial"), "calib"),
    **dict.fromkeys(("design", "designed", "pareto", "run_design"), "design"),
    **dict.fromkeys(("check", "export", "slice"), "making"),
    "bench": "measuring",
    **dict.fromkeys(("offset_map", "run_simulate", "simulate", "simulate_offcentre"), "simulate"),
}


def _family(family: str) -> ModuleType:
    """The api module of ``family`` (one of _FAMILY's values), imported now."""
    if family == "calib":
        from mst_cli.api import _calibrating  # deferred: mst design and mst simulate never read a load test

        return _calibrating
    if family == "design":
        from mst_cli.api import _designing  # deferred: only the verb's family is loaded

        return _designing
    if family == "making":
        from mst_cli.api import _making  # deferred: only the verb's family is loaded

        return _making
    if family == "measuring":
        from mst_cli.api import _measuring  # deferred: only the verb's family is loaded

        return _measuring
    from mst_cli.api import _simulating  # deferred: mst design does not load the simulate verbs

    return _simulating


def __getattr__(name: str):
    if name in _FAMILY:
        value = getattr(_family(_FAMILY[name]), name)
        globals()[name] = value  # bound now: the next look-up is a plain attribute
        return value
    # SlicerError (PrusaSlicer misbehaved) without importing the slicer before it is asked for
    if name == "SlicerError":
        from mst_cli.cad.slicer import SlicerError  # deferred: the CAD layer, 30 ms measured

        return SlicerError
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
