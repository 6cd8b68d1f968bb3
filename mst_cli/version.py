"""The package's version, read from its installed metadata: pyproject.toml is the one place it is
written, so the version a report or a header carries is the one pip installed."""

from __future__ import annotations

import functools


@functools.cache
def package_version() -> str:
    """The installed package's version ("0+unknown" for a source tree that was not installed)."""
    # deferred: importlib.metadata loads the email package, about 10 ms no command should pay
    # before it writes a file that names the version
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("mst")
    except PackageNotFoundError:
        return "0+unknown"
