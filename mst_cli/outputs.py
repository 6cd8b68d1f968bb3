"""Writing result files atomically: all of a command's files appear, or none do.

Files are first written into a hidden staging folder inside the output folder and renamed
into place only when every one of them has been written; on any error the staging folder is
removed, so a failed command leaves nothing half-written behind.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

import yaml


class Staging:
    """Collects files in a temporary folder; :meth:`commit` moves them to ``out_dir``."""

    def __init__(self, out_dir: Path):
        self.out_dir = Path(out_dir)
        self.out_dir.parent.mkdir(parents=True, exist_ok=True)
        self._created_out_dir = not self.out_dir.exists()
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self.tmp = Path(tempfile.mkdtemp(prefix=".mst-staging-", dir=self.out_dir))
        self.names: list[str] = []

    def path(self, name: str) -> Path:
        """Where to write ``name`` for now (inside the staging folder)."""
        self.names.append(name)
        return self.tmp / name

    def write_text(self, name: str, text: str) -> None:
        self.path(name).write_text(text)

    def write_json(self, name: str, data) -> None:
        self.write_text(name, json.dumps(data, indent=2, sort_keys=False) + "\n")

    def write_yaml(self, name: str, data) -> None:
        self.write_text(name, yaml.safe_dump(data, sort_keys=False, default_flow_style=None))

    def commit(self) -> list[Path]:
        final = []
        for name in self.names:
            target = self.out_dir / name
            os.replace(self.tmp / name, target)
            final.append(target)
        shutil.rmtree(self.tmp, ignore_errors=True)
        return final

    def abort(self) -> None:
        shutil.rmtree(self.tmp, ignore_errors=True)
        if self._created_out_dir:
            try:
                self.out_dir.rmdir()          # only if nothing else is in it
            except OSError:
                pass


@contextmanager
def staged(out_dir: Path):
    """``with staged(dir) as st: st.write_json(...)`` -- renamed into place on success only."""
    st = Staging(out_dir)
    try:
        yield st
    except BaseException:
        st.abort()
        raise
    st.commit()
