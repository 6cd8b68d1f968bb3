"""mst: design tool for multi-sensitivity soft tactile sensors.

The command line's verbs are functions in :mod:`mst_cli.api` (``from mst_cli import api as
mst``). The package re-exports those whose names are not also its subpackages: ``design`` is
(:mod:`mst_cli.design`), and Python binds a subpackage to its name in the package whenever it is
imported, so only ``api.design`` names that verb reliably. ``mst_cli.__version__`` is the installed version
(:mod:`mst_cli.version`). The package sits at the api's layer: nothing below imports it.
"""

from typing import TYPE_CHECKING

from mst_cli import api
from mst_cli.errors import InputError
from mst_cli.version import package_version

if TYPE_CHECKING:
    from mst_cli.api import (
        calibrate,
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


def __getattr__(name: str):
    # the version on demand: reading the package metadata costs start-up time no verb needs
    if name == "__version__":
        return package_version()
    # a verb from the api, which loads its family's module when first asked (mst_cli.api)
    if name in __all__:
        return getattr(api, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "api",
    "InputError",
    "calibrate",
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
