"""Reading an input file with bounded work and without blocking (issues 13 and 22).

Every file a command reads (design and spec files, load tests, readings, export.json, a
slicer profile, calibration.json) goes through :func:`read_input`. It refuses, naming the
path, anything that is not a regular file: a FIFO (whose ``open`` would wait for a writer
forever), a character or block device (``/dev/zero`` never ends), a socket or a folder. The
check is made on ``stat`` before opening and again on the open descriptor, which is opened
non-blocking, so nothing can hang between the two. At most ``limit`` + 1 bytes are read.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from mst_cli.errors import InputError

_KINDS = (
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISDIR, "a folder"),
)


# errno values that are the machine's fault (full disk, I/O error) rather than a bad path
MACHINE_FAULTS = frozenset(
    getattr(errno, name)
    for name in (
        "ENOSPC",
        "EDQUOT",
        "EIO",
        "ENOMEM",
        "EMFILE",
        "ENFILE",
        "EFBIG",
        "EAGAIN",
        "EBUSY",
        "ETXTBSY",
        "ESTALE",
        "ENOLCK",
        "EREMOTEIO",
        "ENOBUFS",
        "EINTR",
    )
    if hasattr(errno, name)
)


def is_machine_fault(exc: OSError) -> bool:
    """True when a file-system error is the machine's fault (:data:`MACHINE_FAULTS`), not the path's."""
    return exc.errno in MACHINE_FAULTS


def os_error_text(exc: OSError) -> str:
    """The paths of a file-system error, its errno reason and the errno's name, in one phrase."""
    name = errno.errorcode.get(exc.errno, "") if exc.errno is not None else ""
    reason = exc.strerror or (os.strerror(exc.errno) if exc.errno else str(exc))
    paths = " -> ".join(str(p) for p in (exc.filename, exc.filename2) if p is not None) or "(unknown path)"
    return f"{paths}: {reason}" + (f" ({name})" if name else "")


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _refuse_special(mode: int, field: str, path: Path, what: str) -> None:
    if not stat.S_ISREG(mode):
        raise InputError(field, str(path), f"is {_kind(mode)}, not a {what}: give a regular file")


def _reason(exc: BaseException) -> str:
    return getattr(exc, "strerror", None) or str(exc)


def read_input(
    path: str | Path, limit: int, *, field: str = "(file)", what: str = "file", too_large: str = ""
) -> bytes:
    """The bytes of the regular file ``path`` (at most ``limit``).

    InputError naming ``field`` and the path when it does not exist, is not a regular file,
    cannot be opened or read (the errno reason), or is larger than ``limit`` bytes
    (``too_large`` is appended to that message)."""
    path = Path(path)
    try:
        _refuse_special(os.stat(path).st_mode, field, path, what)
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
        with os.fdopen(fd, "rb") as fh:
            _refuse_special(os.fstat(fd).st_mode, field, path, what)  # replaced since the stat
            data = fh.read(limit + 1)
    except FileNotFoundError:
        raise InputError(field, str(path), "file not found") from None
    except InputError:
        raise
    except (OSError, ValueError) as exc:  # ValueError: a NUL in the path
        raise InputError(field, str(path), f"cannot be read ({_reason(exc)})") from None
    if len(data) > limit:
        raise InputError(field, str(path), f"is larger than {limit} bytes{too_large}")
    return data


def read_input_text(
    path: str | Path,
    limit: int,
    *,
    field: str = "(file)",
    what: str = "text file",
    too_large: str = "",
    encoding: str = "utf-8",
) -> str:
    """:func:`read_input` decoded (InputError when it is not text in ``encoding``)."""
    data = read_input(path, limit, field=field, what=what, too_large=too_large)
    try:
        return data.decode(encoding)
    except UnicodeDecodeError:
        raise InputError(field, str(path), f"is not a UTF-8 {what}") from None
