"""mst: design tool for multi-sensitivity soft tactile sensors.

The command line's verbs are functions here too (:mod:`mst_cli.api`): ``import mst_cli as mst``.
"""

__version__ = "0.6.0"

from mst_cli.api import *  # noqa: F403  (the verbs; each imports its modules when called)
from mst_cli.api import __all__ as __all__
