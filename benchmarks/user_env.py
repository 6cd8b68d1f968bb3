"""The environment the timed commands run in: an installed copy's.

Every benchmark that times `mst` in a child process calls :func:`as_installed` first. A
development shell may set PYTHONDONTWRITEBYTECODE (this project's machines do); then every
command recompiles the package's sources on start (about 15 ms for `mst simulate`, more for
the design path), a cost no installed copy pays: pip compiles the bytecode on install, and
an editable install writes it on the first run. The floor's own libraries (numpy, yaml,
click) always start from bytecode, so without this the ratios would compare unlike starts.
"""

import os
import sys
from importlib import metadata


def libraries() -> str:
    """The interpreter and the libraries the design's path depends on, with their versions: the
    same tree takes another number of kernel calls on another numpy (docs/performance.md)."""
    found = []
    for name in ("numpy", "scipy", "nlopt"):
        try:
            found.append(f"{name} {metadata.version(name)}")
        except metadata.PackageNotFoundError:
            found.append(f"{name} not installed")
    return f"python {sys.version.split()[0]}, " + ", ".join(found)


def as_installed() -> None:
    """Let child processes use and write Python's bytecode cache, as an installed copy does."""
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
