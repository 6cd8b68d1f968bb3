"""Writing result files atomically: all of a command's files appear, or none do.

Files are first written into a hidden staging folder inside the output folder and renamed
into place only when every one of them has been written; on any error the staging folder is
removed, so a failed command leaves nothing half-written behind.

Interruptions (issue 13): while a staging folder exists, SIGTERM and SIGHUP raise
:class:`Interrupted` (SIGINT raises KeyboardInterrupt as usual), so the same abort removes it;
the renames of the commit run with those signals blocked, so an earlier complete output is
either kept whole or replaced whole. A staging folder is named ``.mst-staging-<pid>-<random>``:
one left by a killed run (SIGKILL, power loss) is removed by the next run into the same folder
when its process is gone or it is older than :data:`STALE_AFTER_S`; until then it is ignored.

JSON is written with ``allow_nan=False``: a NaN or infinity can never reach a file silently.
"""

from __future__ import annotations

import errno
import json
import math
import os
import shutil
import signal
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import yaml

STAGING_PREFIX = ".mst-staging-"
# libyaml's emitter where PyYAML was built with it: the same text as PyYAML's own emitter (the
# representer, which turns numbers into text, is PyYAML's in both), about 5 times faster
YAML_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
STALE_AFTER_S = 15 * 60
_LIVE: set[Path] = set()  # staging folders of this process still in use
_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


class Interrupted(SystemExit):
    """Raised by the SIGTERM / SIGHUP handler while files are staged (exit code 128 + signal)."""

    def __init__(self, signum: int):
        self.signum = signum
        super().__init__(128 + signum)

    @property
    def name(self) -> str:
        return signal.Signals(self.signum).name


def dumps_json(data: Any, **kwargs: Any) -> str:
    """``json.dumps`` that refuses NaN and infinities (ValueError) instead of writing them."""
    return json.dumps(data, allow_nan=False, **kwargs)


def finite_or_none(data: Any) -> Any:
    """A copy of nested dicts/lists/tuples with every non-finite float replaced by None."""
    if isinstance(data, dict):
        return {k: finite_or_none(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [finite_or_none(v) for v in data]
    if isinstance(data, float) and not math.isfinite(data):
        return None
    return data


def _name_max(path: Path) -> int:
    for p in [path, *path.parents]:
        try:
            return os.pathconf(p, "PC_NAME_MAX")
        except (OSError, ValueError):
            continue
    return 255


def check_out_dir(out_dir: Path) -> None:
    """OSError naming the path when ``out_dir`` cannot be a folder: a NUL in it (EINVAL), a
    component longer than the file system allows (ENAMETOOLONG), or a regular file at it or
    above it (ENOTDIR). Cheap: the commands call it before their work, Staging again. Other
    faults (read-only, full) surface from mkdir and the writes themselves."""
    text = os.fspath(out_dir)
    if "\0" in text:
        raise OSError(errno.EINVAL, "the path holds a NUL byte", text.replace("\0", "\\0"))
    out_dir = Path(out_dir)
    limit = _name_max(out_dir)
    if any(len(os.fsencode(part)) > limit for part in out_dir.parts):
        raise OSError(errno.ENAMETOOLONG, os.strerror(errno.ENAMETOOLONG), text)
    for p in [*reversed(out_dir.parents), out_dir]:
        if p.exists() and not p.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(p))


def _pid_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # someone else's live process
    except (OverflowError, OSError):
        return False
    return True


def _staging_pid(name: str) -> int | None:
    head, sep, _ = name[len(STAGING_PREFIX) :].partition("-")
    return int(head) if sep and head.isdigit() and len(head) < 12 else None


def remove_stale_staging(out_dir: Path, now: float | None = None) -> list[Path]:
    """Remove the staging folders in ``out_dir`` that no live run owns; returns them.

    Stale: the recorded process is gone (or is this process, which no longer uses it), or the
    folder is older than STALE_AFTER_S (a pid may be reused). Folders in use are never touched.
    """
    now = time.time() if now is None else now
    removed: list[Path] = []
    try:
        entries = list(os.scandir(out_dir))
    except OSError:
        return removed
    for entry in entries:
        if not entry.name.startswith(STAGING_PREFIX):
            continue
        path = Path(entry.path)
        try:
            if not entry.is_dir(follow_symlinks=False) or path in _LIVE:
                continue
            age = now - entry.stat(follow_symlinks=False).st_mtime
        except OSError:
            continue
        pid = _staging_pid(entry.name)
        dead = pid is not None and (pid == os.getpid() or not _pid_alive(pid))
        if dead or age > STALE_AFTER_S:
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


class Staging:
    """Collects files in a temporary folder; :meth:`commit` moves them to ``out_dir``."""

    def __init__(self, out_dir: Path):
        self.out_dir = Path(out_dir)
        check_out_dir(self.out_dir)
        # the folders this creates (outermost first), removed again on abort when still empty
        self._created = [p for p in [*reversed(self.out_dir.parents), self.out_dir] if not p.exists()]
        self._created_out_dir = bool(self._created) and self._created[-1] == self.out_dir
        try:
            self.out_dir.mkdir(parents=True, exist_ok=True)
            remove_stale_staging(self.out_dir)
            self.tmp = Path(tempfile.mkdtemp(prefix=f"{STAGING_PREFIX}{os.getpid()}-", dir=self.out_dir))
        except OSError as exc:
            self._remove_created()
            if exc.filename is None or STAGING_PREFIX in str(exc.filename):
                exc.filename, exc.filename2 = str(self.out_dir), None
            raise
        _LIVE.add(self.tmp)
        self.names: list[str] = []
        self.removals: list[str] = []  # old files of out_dir this run replaces by nothing

    def path(self, name: str) -> Path:
        """Where to write ``name`` for now (inside the staging folder)."""
        self.names.append(name)
        (self.tmp / name).parent.mkdir(parents=True, exist_ok=True)  # a name may hold a subfolder
        return self.tmp / name

    def write_text(self, name: str, text: str) -> None:
        self._write(name, lambda path: path.write_text(text))

    def write_bytes(self, name: str, data: bytes) -> None:
        self._write(name, lambda path: path.write_bytes(data))

    def _write(self, name: str, write) -> None:
        """``write(staged path)``; an OSError (a full disk) names out_dir/``name``, not the
        staging folder."""
        try:
            write(self.path(name))
        except OSError as exc:
            if exc.filename is None or STAGING_PREFIX in str(exc.filename):
                exc.filename, exc.filename2 = str(self.out_dir / name), None
            raise

    def write_json(self, name: str, data: Any) -> None:
        self.write_text(name, dumps_json(data, indent=2, sort_keys=False) + "\n")

    def write_yaml(self, name: str, data: Any) -> None:
        self.write_text(name, yaml.dump(data, Dumper=YAML_DUMPER, sort_keys=False, default_flow_style=None))

    def remove(self, name: str) -> None:
        """Remove out_dir/``name`` when the staged files are committed (with them, under the same
        blocked signals): a picture this run did not draw must not survive beside its new files,
        and a run that fails keeps the old set whole."""
        self.removals.append(name)

    def commit(self) -> list[Path]:
        final = []
        with _signals_blocked():
            for name in self.removals:
                if name not in self.names:
                    (self.out_dir / name).unlink(missing_ok=True)
            for name in self.names:
                target = self.out_dir / name
                target.parent.mkdir(parents=True, exist_ok=True)
                os.replace(self.tmp / name, target)
                final.append(target)
        shutil.rmtree(self.tmp, ignore_errors=True)
        _LIVE.discard(self.tmp)
        return final

    def abort(self) -> None:
        shutil.rmtree(self.tmp, ignore_errors=True)
        _LIVE.discard(self.tmp)
        self._remove_created()

    def _remove_created(self) -> None:
        for p in reversed(self._created):  # innermost first; only if nothing else is in it
            try:
                p.rmdir()
            except OSError as exc:
                if exc.errno not in (errno.ENOENT, errno.ENAMETOOLONG):  # never made: go on
                    break


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextmanager
def _signals_blocked():
    """Hold SIGINT/SIGTERM/SIGHUP back (delivered on exit) so a rename loop runs whole."""
    sigs = {signal.SIGINT, *_SIGNALS}
    if not _main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, sigs)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _raise_interrupted(signum, frame):
    raise Interrupted(signum)


@contextmanager
def _terminate_raises():
    """While inside: SIGTERM / SIGHUP raise :class:`Interrupted` (where they would kill)."""
    installed = {}
    if _main_thread():
        for sig in _SIGNALS:
            try:
                if signal.getsignal(sig) == signal.SIG_DFL:
                    installed[sig] = signal.signal(sig, _raise_interrupted)
            except (OSError, ValueError):
                pass
    try:
        yield
    finally:
        for sig, old in installed.items():
            signal.signal(sig, old)


@contextmanager
def staged(out_dir: Path) -> Iterator[Staging]:
    """``with staged(dir) as st: st.write_json(...)`` -- renamed into place on success only.

    An OSError without a path (a full disk while writing) is given the output folder's path.
    """
    with _terminate_raises():
        st = Staging(out_dir)
        try:
            yield st
            st.commit()
        except BaseException as exc:
            st.abort()
            if isinstance(exc, OSError) and (exc.filename is None or STAGING_PREFIX in str(exc.filename)):
                exc.filename, exc.filename2 = str(st.out_dir), None
            raise
