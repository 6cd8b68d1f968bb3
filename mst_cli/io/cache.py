"""Where ``mst`` keeps what it builds once per model and reuses on the next call (issue 45): the
readers' tables, each file named by the hash of what it was built from, so a stale one is never
found. The folder is ``$MST_CACHE_DIR``, else ``$XDG_CACHE_HOME/mst``, else ``~/.cache/mst``.

A file is written to a temporary name beside its place and renamed over it, so a reader never
finds half a file; at most :data:`MAX_KEPT` files are kept (the least recently used go). A cache
that cannot be written (a read-only home, a full disk) costs the next call a rebuild, nothing more:
:func:`keep` says why and raises nothing.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

CACHE_ENV = "MST_CACHE_DIR"
MAX_KEPT = 64  # files (a default table is 0.3 to 0.6 MB)


def cache_dir() -> Path | None:
    """The cache folder (None when the environment names none and there is no home)."""
    given = os.environ.get(CACHE_ENV)
    if given:
        return Path(given)
    xdg = os.environ.get("XDG_CACHE_HOME")
    if xdg and os.path.isabs(xdg):
        return Path(xdg) / "mst"
    try:
        return Path.home() / ".cache" / "mst"
    except RuntimeError:  # no home directory to expand
        return None


def cached_path(name: str, folder: Path | None = None) -> Path | None:
    """Where the file ``name`` is kept (in ``folder``, else the cache folder; None without one)."""
    folder = folder if folder is not None else cache_dir()
    return None if folder is None else folder / name


def keep(name: str, write: Callable[[BinaryIO], None], folder: Path | None = None) -> tuple[Path | None, str | None]:
    """``write`` the file ``name`` into the cache (``folder``, else the cache folder): (its path,
    None), or (None, why it was not kept). Nothing half-written is left under ``name``."""
    path = cached_path(name, folder)
    if path is None:
        return None, "no cache folder (set MST_CACHE_DIR)"
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".keep-", dir=path.parent)
        with os.fdopen(fd, "wb") as fh:
            write(fh)
        os.replace(tmp, path)
    except OSError as exc:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        return None, f"{exc.strerror or exc} ({path.parent})"
    _prune(path.parent)
    return path, None


def touch(path: Path) -> None:
    """Mark a kept file as just used (the least recently used are pruned first)."""
    with contextlib.suppress(OSError):
        os.utime(path)


def _prune(folder: Path) -> None:
    with contextlib.suppress(OSError):
        kept = sorted((p for p in folder.iterdir() if p.is_file() and not p.name.startswith(".")), key=_mtime)
        for old in kept[:-MAX_KEPT]:
            with contextlib.suppress(OSError):
                old.unlink()


def _mtime(path: Path) -> float:
    try:
        return path.stat().st_mtime
    except OSError:
        return 0.0
