"""The whole-part rung's solves kept between runs, as small JSON files in mst's cache folder
(:mod:`mst_cli.io.cache`, its ``rung/`` subfolder), so ``model.load_path: section`` pays its
finite-element solves once per part: ``mst design`` then ``mst check --whole-part`` of the same
design, a second ``mst simulate``, a test suite's many processes.

A file is named by the hash of what the solve depends on (the rung's memo key: the geometry, the
material and the options, as their reprs) and of the source of every physics module
(``mst_cli/model``, its fitted data included), so a file from another version of the model is
never found. A file that does not parse, or parses to anything but what was written, is treated
as missing; a cache that cannot be written costs a solve, nothing more.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

from mst_cli.io.cache import cached_path, keep, touch
from mst_cli.model.mechanics import rung_keep

SUBFOLDER = "rung"
MAX_FILE_BYTES = 1 << 20  # a kept solve is well under a kilobyte a regime


@cache
def model_source_hash() -> str:
    """The hash of the physics modules' source and their fitted data (every ``mst_cli/model/**/*.py``
    and ``mst_cli/model/data/*``: a refit changes the model as an edit does)."""
    import hashlib  # deferred: OpenSSL, 3 ms of every start; only kept solves and the tables hash the model

    root = Path(rung_keep.__file__).resolve().parents[1]  # mst_cli/model
    digest = hashlib.sha256()
    for path in sorted([*root.rglob("*.py"), *(root / "data").glob("*")]):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def file_name(kind: str, key: tuple) -> str:
    """Where the solve ``kind`` of ``key`` is kept, inside the cache folder."""
    import hashlib  # deferred: as model_source_hash's

    digest = hashlib.sha256(f"{kind}\n{model_source_hash()}\n{key!r}".encode()).hexdigest()
    return f"{SUBFOLDER}/{kind}-{digest[:32]}.json"


class FileRungStore:
    """:class:`~mst_cli.model.mechanics.rung_keep.RungStore` in ``folder`` (None: the cache
    folder as the environment names it at each call)."""

    def __init__(self, folder: Path | None = None) -> None:
        self.folder = folder

    def load(self, kind: str, key: tuple) -> object | None:
        path = cached_path(file_name(kind, key), self.folder)
        try:
            if path is None or path.stat().st_size > MAX_FILE_BYTES:
                return None
            value = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        touch(path)
        return value

    def save(self, kind: str, key: tuple, value: object) -> None:
        try:
            text = json.dumps(value, allow_nan=False, default=_plain).encode()
        except (TypeError, ValueError):  # a solve that is not a number is not kept
            return
        keep(file_name(kind, key), lambda fh: _write(fh, text), self.folder)


def _write(fh, text: bytes) -> None:
    fh.write(text)


def _plain(value: object) -> object:
    """numpy's scalars as Python's (json's ``default``)."""
    item = getattr(value, "item", None)
    if item is None:
        raise TypeError(f"{type(value).__name__} is not a number")
    return item()


_CHOSEN: list[Path] = []  # a folder install() was given: the cache folder's call leaves it


def install(folder: Path | None = None) -> None:
    """Keep the rung's solves in ``folder``, else in the cache folder (in this process only when
    there is none). A folder given wins over the api's own call at import (a test session's)."""
    if folder is not None:
        _CHOSEN[:] = [folder]
        rung_keep.set_store(FileRungStore(folder))
    elif not _CHOSEN:  # the cache folder as the environment names it at each call (none: nothing kept)
        rung_keep.set_store(FileRungStore())
