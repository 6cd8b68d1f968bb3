"""mst: design tool for multi-sensitivity soft tactile sensors.

The command line's verbs are functions in :mod:`mst_cli.api` (``from mst_cli import api as
mst``). The package re-exports those whose names are not also its subpackages: ``design`` and
``calibrate`` are (:mod:`mst_cli.design`, :mod:`mst_cli.calibrate`), and Python binds a
subpackage to its name in the package whenever it is imported, so only ``api.design`` and
``api.calibrate`` name the verbs reliably.
"""

__version__ = "0.15.0"

from mst_cli import api  # after __version__, which the api's modules read
from mst_cli.api import (
    InputError,
    check,
    designed,
    export,
    load,
    load_design,
    pareto,
    read,
    read_serial,
    simulate,
    slice,
)

__all__ = [
    "api",
    "InputError",
    "check",
    "designed",
    "export",
    "load",
    "load_design",
    "pareto",
    "read",
    "read_serial",
    "simulate",
    "slice",
]
