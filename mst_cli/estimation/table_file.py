"""The table files beside a model, read as every input file is (issue 46): an npz of plain
arrays, its members' unpacked size and each array header's claim bounded before numpy allocates
anything, no pickles, every array's kind, shape and values checked. Pure: bytes in, arrays out
(:meth:`~mst_cli.estimation.inverse_table.InverseTable.read` opens the file)."""

from __future__ import annotations

import io
import math
import zipfile
import zlib

import numpy as np

_NPY_HEADERS = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
TABLE_KEYS = ("format", "kind", "source_hash", "force_N", "u", "v", "B_T")
MAX_TABLE_BYTES = 64_000_000  # a default table is 0.3 to 0.6 MB; the finest grid a few MB
# what a file that is not an npz of plain arrays raises inside numpy and zipfile
PARSE_ERRORS = (OSError, ValueError, KeyError, TypeError, EOFError, MemoryError, zipfile.BadZipFile, zlib.error)


def npz_arrays(data: bytes, keys: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The arrays ``keys`` of an npz file's bytes, its members' unpacked size bounded before any is read."""
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        names = {info.filename: info.file_size for info in zf.infolist()}
    if sum(names.values()) > MAX_TABLE_BYTES:
        raise ValueError(f"its arrays unpack to {sum(names.values())} bytes, over {MAX_TABLE_BYTES}")
    missing = [k for k in keys if f"{k}.npy" not in names]
    if missing:
        raise KeyError(f"no {', '.join(missing)}")
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        for key in keys:  # each header's claim against its member's size, before numpy allocates it
            with zf.open(f"{key}.npy") as fh:
                header = _NPY_HEADERS.get(np.lib.format.read_magic(fh))
                if header is None:
                    raise ValueError(f"its {key} is an .npy of a version numpy's savez does not write")
                shape, _, dtype = header(fh)  # at most 10,000 bytes of header
            if dtype.hasobject or math.prod(shape) * dtype.itemsize > names[f"{key}.npy"]:
                raise ValueError(f"its {key} claims {shape} {dtype} in {names[f'{key}.npy']} bytes")
    with np.load(io.BytesIO(data), allow_pickle=False) as z:
        return {k: np.asarray(z[k]) for k in keys}


def checked_arrays(
    z: dict[str, np.ndarray], table_format: int, kinds: tuple[str, ...]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, str, np.ndarray, str]:
    """(force_N, u, v, kind, B_T, source_hash) of a table's arrays, checked; ValueError saying
    which is not what a table holds."""
    if z["format"].shape != () or z["format"].dtype.kind not in "iu" or int(z["format"]) != table_format:
        raise ValueError(f"of another format than {table_format}")
    for key in ("kind", "source_hash"):
        if z[key].shape != () or z[key].dtype.kind != "U":
            raise ValueError(f"its {key} is not one text")
    kind = str(z["kind"])
    if kind not in kinds:
        raise ValueError(f"of kind {kind[:20]!r}, not one of {', '.join(kinds)}")
    nodes = []
    for key in ("force_N", "u", "v"):
        a = z[key]
        if a.ndim != 1 or a.dtype.kind != "f" or len(a) < 2 or not np.all(np.isfinite(a)) or np.any(np.diff(a) <= 0):
            raise ValueError(f"its {key} nodes are not at least 2 ascending finite numbers")
        nodes.append(a.astype(float))
    B = z["B_T"]
    shape = (len(nodes[0]), len(nodes[1]), len(nodes[2]), 3)
    if B.dtype.kind != "f" or B.shape != shape:
        raise ValueError(f"its field B_T is not numbers of shape {shape}")
    if not np.all(np.isfinite(B)) or float(np.max(np.abs(B))) >= 1.0:
        raise ValueError("its field B_T holds values that are not finite or beyond 1 T")
    return nodes[0], nodes[1], nodes[2], kind, np.ascontiguousarray(B, dtype=float), str(z["source_hash"])
