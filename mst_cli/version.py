"""The package's version, read from its installed metadata: pyproject.toml is the one place it is
written, so the version a report or a header carries is the one pip installed."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("mst")
except PackageNotFoundError:  # a source tree imported without being installed
    __version__ = "0+unknown"
