"""Bounded reading of ``.npz`` archives and of the JSON they carry.

``read_npz(path, what=..., fix=...)`` returns ``{key: array}`` or raises ONE-line
``UserError`` naming the file, the member (key) and the fix. Nothing is allocated before
its size is known and allowed:

- the file must be a regular, non-empty zip archive whose members are all ``KEY.npy``,
  stored or deflated (what ``np.savez``/``savez_compressed`` write), no name twice;
- the zip directory's declared uncompressed sizes must sum to at most
  ``MAX_TOTAL_BYTES`` and no member may claim a ratio above ``MAX_RATIO`` (deflate cannot
  exceed ~1032:1, so more is a lying header); ``zipfile`` never returns more bytes than
  declared, so the bound holds for what is read;
- each member's ``.npy`` header (``read_magic`` + ``read_array_header_1_0/2_0``) is read
  first: a plain dtype (bool, integer, float, complex, str/bytes; never objects, so
  nothing is unpickled) whose shape times item size equals the member's data size;
- then the array is read (``allow_pickle=False``); a CRC or deflate error is a line too.

``read_json_text`` parses a JSON member with a length and nesting bound.
"""

from __future__ import annotations

import json
import os
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np
from numpy.lib import format as npformat

from console.core.errors import UserError
from console.files.file_read import check_regular

#: the largest total uncompressed size accepted (a map of 5 x 84 points x 64k bins is
#: 430 MB; the maps and tables HapTable writes are a few MB)
MAX_TOTAL_BYTES = 512 * 2**20
#: deflate's largest possible ratio is about 1032:1; a member claiming more lies
MAX_RATIO = 1100
MAX_MEMBERS = 64
#: dtype kinds accepted: bool, signed/unsigned integer, float, complex, str, bytes
KINDS = "biufcUS"
MAX_JSON_CHARS = 1_000_000
MAX_JSON_DEPTH = 32


def _mb(n: int) -> str:
    return f"{n / 2**20:,.0f} MB" if n >= 2**20 else f"{n:,} bytes"


def _regular_file(p: Path, what: str, fix: str) -> int:
    """The size of ``p``, a non-empty regular file (``file_read.check_regular``); else
    one line naming ``what``."""
    st = check_regular(p, what=what, fix=fix, missing_ok=True)
    if st is None:
        raise UserError(f"{p}: no such {what}; {fix}")
    if st.st_size == 0:
        raise UserError(f"{p}: empty file, not a {what} (.npz); {fix}")
    return st.st_size


def _check_infos(
    p: Path, z: zipfile.ZipFile, what: str, fix: str, limit: int
) -> list[zipfile.ZipInfo]:
    infos = z.infolist()
    if not infos:
        raise UserError(f"{p}: an empty .npz archive, not a {what}; {fix}")
    if len(infos) > MAX_MEMBERS:
        raise UserError(f"{p}: {len(infos)} members, more than a {what} holds; {fix}")
    seen: set[str] = set()
    total = 0
    for info in infos:
        name = info.filename
        if not name.endswith(".npy") or "/" in name:
            raise UserError(
                f"{p}: member {name!r} is not a .npy array, so this is not a {what}; {fix}"
            )
        if name in seen:
            raise UserError(f"{p}: member {name!r} appears twice; {fix}")
        seen.add(name)
        if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            raise UserError(
                f"{p}: key {name[:-4]!r} is compressed with zip method {info.compress_type} "
                f"(numpy writes stored or deflate); {fix}"
            )
        if info.file_size > MAX_RATIO * max(info.compress_size, 1):
            raise UserError(
                f"{p}: key {name[:-4]!r} declares {_mb(info.file_size)} uncompressed from "
                f"{_mb(info.compress_size)} (more than deflate can do: a zip bomb or a "
                f"corrupt header); {fix}"
            )
        total += info.file_size
    if total > limit:
        raise UserError(
            f"{p}: the archive declares {_mb(total)} uncompressed, above the "
            f"{_mb(limit)} limit of a {what}; {fix}"
        )
    return infos


def _header(p: Path, key: str, fh, size: int, fix: str, limit: int) -> tuple[tuple, np.dtype]:
    """Shape and dtype from a member's .npy header, checked against its size."""
    try:
        version = npformat.read_magic(fh)
        if version == (1, 0):
            shape, fortran, dtype = npformat.read_array_header_1_0(fh)
        elif version == (2, 0):
            shape, fortran, dtype = npformat.read_array_header_2_0(fh)
        else:
            raise ValueError(f".npy format version {version} is not supported")
        offset = fh.tell()
    except ValueError as exc:
        raise UserError(f"{p}: key {key!r} has no valid .npy header ({exc}); {fix}") from None
    except (OSError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise UserError(
            f"{p}: key {key!r} cannot be read ({exc}): the file is damaged; {fix}"
        ) from None
    if dtype.hasobject or dtype.kind not in KINDS or dtype.fields is not None:
        why = "pickled Python objects (refused)" if dtype.hasobject else f"dtype {dtype}"
        raise UserError(
            f"{p}: key {key!r} holds {why}; only plain numbers and text are read; {fix}"
        )
    count = 1
    for n in shape:
        count *= int(n)
    need = count * dtype.itemsize
    if need > limit:
        raise UserError(
            f"{p}: key {key!r} declares shape {shape} {dtype} ({_mb(need)}), above the "
            f"{_mb(limit)} limit; {fix}"
        )
    if size - offset != need:
        raise UserError(
            f"{p}: key {key!r} declares shape {shape} {dtype} ({_mb(need)}) but holds "
            f"{_mb(max(size - offset, 0))}: truncated or corrupt; {fix}"
        )
    return shape, dtype


def read_npz(
    path: str | os.PathLike, *, what: str, fix: str, max_bytes: int | None = None
) -> dict[str, np.ndarray]:
    """All arrays of a ``.npz`` archive, each size-checked before it is read.

    ``what`` names the file kind in messages ("vibration map"); ``fix`` ends each one;
    ``max_bytes``: the total uncompressed bound (default ``MAX_TOTAL_BYTES``).
    """
    p = Path(path)
    limit = MAX_TOTAL_BYTES if max_bytes is None else int(max_bytes)
    _regular_file(p, what, fix)
    try:
        z = zipfile.ZipFile(p)
    except zipfile.BadZipFile:
        raise UserError(
            f"{p}: not a zip archive (truncated, or not a .npz at all), so not a {what}; {fix}"
        ) from None
    except (OSError, ValueError, EOFError) as exc:
        raise UserError(f"{p}: cannot read the archive ({exc}); {fix}") from None
    out: dict[str, np.ndarray] = {}
    with z:
        for info in _check_infos(p, z, what, fix, limit):
            key = info.filename[:-4]
            try:
                with z.open(info) as fh:
                    _header(p, key, fh, info.file_size, fix, limit)
                with z.open(info) as fh:
                    out[key] = npformat.read_array(fh, allow_pickle=False)
            except UserError:
                raise
            except (
                ValueError,
                OSError,
                EOFError,
                zipfile.BadZipFile,
                zlib.error,
                NotImplementedError,
            ) as exc:
                raise UserError(
                    f"{p}: key {key!r} cannot be read ({exc}): the file is damaged; {fix}"
                ) from None
    return out


def json_depth(obj: Any) -> int:
    """Nesting depth of a parsed JSON value (iterative: no recursion limit)."""
    deepest, stack = 0, [(obj, 1)]
    while stack:
        o, d = stack.pop()
        if isinstance(o, (dict, list)):
            deepest = max(deepest, d)
            stack.extend((v, d + 1) for v in (o.values() if isinstance(o, dict) else o))
    return deepest


def read_json_text(
    value: Any,
    *,
    where: str,
    key: str,
    fix: str,
    max_depth: int = MAX_JSON_DEPTH,
    max_chars: int = MAX_JSON_CHARS,
) -> Any:
    """Parse a JSON string (a 0-d str array from a ``.npz`` or a ``str``) with bounds on
    its length and nesting; a ``UserError`` naming ``where`` and ``key`` otherwise."""
    if isinstance(value, np.ndarray):
        if value.shape != () or value.dtype.kind not in "US":
            raise UserError(
                f"{where}: key {key!r} must be one JSON string, not a {value.dtype} array of "
                f"shape {value.shape}; {fix}"
            )
        value = value.item()
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    if not isinstance(value, str):
        raise UserError(f"{where}: key {key!r} must be a JSON string; {fix}")
    if len(value) > max_chars:
        raise UserError(
            f"{where}: key {key!r} is {len(value):,} characters of JSON (limit "
            f"{max_chars:,}); {fix}"
        )
    try:
        obj = json.loads(value)
    except RecursionError:
        raise UserError(
            f"{where}: key {key!r} nests deeper than {max_depth} levels; {fix}"
        ) from None
    except ValueError as exc:
        raise UserError(f"{where}: key {key!r} is not valid JSON ({exc}); {fix}") from None
    if json_depth(obj) > max_depth:
        raise UserError(f"{where}: key {key!r} nests deeper than {max_depth} levels; {fix}")
    return obj


def npz_keys(
    path: str | os.PathLike, *, what: str, fix: str, max_bytes: int | None = None
) -> list[str]:
    """The keys of a ``.npz`` archive (its directory checked as ``read_npz`` does, no
    array read): to tell one kind of file from another before loading it."""
    p = Path(path)
    _regular_file(p, what, fix)
    try:
        with zipfile.ZipFile(p) as z:
            limit = MAX_TOTAL_BYTES if max_bytes is None else int(max_bytes)
            return [i.filename[:-4] for i in _check_infos(p, z, what, fix, limit)]
    except zipfile.BadZipFile:
        raise UserError(
            f"{p}: not a zip archive (truncated, or not a .npz at all), so not a {what}; {fix}"
        ) from None
    except (OSError, ValueError, EOFError) as exc:
        raise UserError(f"{p}: cannot read the archive ({exc}); {fix}") from None
