"""The environment the timed commands run in: an installed copy's.

Every benchmark that times `mst` in a child process calls :func:`as_installed` first. A
development shell may set PYTHONDONTWRITEBYTECODE (this project's machines do); then every
command recompiles the package's sources on start (about 15 ms for `mst simulate`, more for
the design path), a cost no installed copy pays: pip compiles the bytecode on install, and
an editable install writes it on the first run. The floor's own libraries (numpy, yaml,
click) always start from bytecode, so without this the ratios would compare unlike starts.
"""

import os


def as_installed() -> None:
    """Let child processes use and write Python's bytecode cache, as an installed copy does."""
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
