"""Cache files bound to the inputs that made them: one mechanism for every on-disk cache.

A cached artefact is only as good as the claim that it was made from the inputs asked
for. A file name is no such claim (a file can be copied over another's name), so every
entry carries, inside it, the hash of its inputs and the hash of its own content:

- ``input_hash(inputs)``: the SHA-256 of a JSON-able description of everything the
  result depends on (map content hash, parameters, code version); the entry's key;
- ``entry_path(cache_dir, kind, key)``: ``<cache_dir>/<kind>-<key[:24]>.npz``;
- ``write_entry(path, key, arrays)``: writes the arrays plus ``cache_key`` (the key) and
  ``cache_digest`` (SHA-256 of every other member) atomically (a reader never sees half
  a file); members named ``*_json`` hold any JSON-able value;
- ``read_entry(path, key, what=...)``: the arrays (``*_json`` decoded) through the
  bounded reader (``console.files.npz_safe``: kind, size, dtypes), or ONE-line ``UserError`` when
  the file is damaged, holds no key, another key, or content that is not what was written;
- ``load_or_build(path, build, read=..., write=...)``: the policy every cache follows:
  an entry that fails ``read`` is logged (one line), deleted and rebuilt, never used;
  ``cached_arrays`` is that policy for keyed ``.npz`` entries (with an optional ``check``
  of the content). Files of other formats (the measured map) bring their own ``read``.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import os
import tempfile
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from console.core.errors import UserError
from console.files.npz_safe import read_json_text, read_npz

#: bumped when the layout of cache entries changes (older entries are never read)
FORMAT = 2
#: the member holding the entry's key (``input_hash`` of what made it)
KEY = "cache_key"
#: the member holding the SHA-256 of every other member
DIGEST = "cache_digest"
#: how a message about a cache entry ends
FIX = "deleted and rebuilt"

log = logging.getLogger("haptable.cache")

T = TypeVar("T")


def input_hash(inputs: Mapping[str, Any]) -> str:
    """SHA-256 (hex) of ``inputs`` as canonical JSON (sorted keys; other types as str)."""
    blob = json.dumps({"cache_format": FORMAT, **inputs}, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()


def entry_path(cache_dir: str | os.PathLike, kind: str, key: str) -> Path:
    """Where the entry of ``kind`` with ``key`` lives."""
    return Path(cache_dir) / f"{kind}-{key[:24]}.npz"


def content_digest(arrays: Mapping[str, np.ndarray]) -> str:
    """SHA-256 of the members (names, dtypes, shapes and bytes; ``KEY``/``DIGEST`` aside)."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        if name in (KEY, DIGEST):
            continue
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        h.update(a.tobytes())
    return h.hexdigest()


@contextlib.contextmanager
def atomic_target(path: str | os.PathLike) -> Iterator[Path]:
    """A temporary path beside ``path``, moved onto it when the block succeeds (removed
    when it fails): readers see the old file or the whole new one, never half."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.replace(tmp, p)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def write_entry(path: str | os.PathLike, key: str, arrays: Mapping[str, Any]) -> Path:
    """Store ``arrays`` (``*_json`` members: JSON-able values) with ``key`` and the digest."""
    members = {
        k: (np.array(json.dumps(v)) if k.endswith("_json") else np.asarray(v))
        for k, v in arrays.items()
        if k not in (KEY, DIGEST)
    }
    members[KEY] = np.array(str(key))
    members[DIGEST] = np.array(content_digest(members))
    with atomic_target(path) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **members)
    return Path(path)


def _text(raw: np.ndarray | None) -> str | None:
    if raw is None or raw.shape != () or raw.dtype.kind not in "US":
        return None
    return str(raw.item())


def read_entry(path: str | os.PathLike, key: str, *, what: str) -> dict[str, Any]:
    """The arrays of the entry at ``path`` (``*_json`` decoded; ``KEY``/``DIGEST`` dropped)
    when it was made from ``key`` and holds what was written; one-line ``UserError`` else."""
    p = Path(path)
    raw = read_npz(p, what=what, fix=FIX)
    stored = _text(raw.get(KEY))
    if stored is None:
        raise UserError(
            f"{p}: no {KEY} inside (not an entry of this cache), so not a {what}; {FIX}"
        )
    if stored != key:
        raise UserError(
            f"{p}: made from other inputs ({KEY} {stored[:12]}..., asked for {key[:12]}...), "
            f"so not this {what}; {FIX}"
        )
    if _text(raw.get(DIGEST)) != content_digest(raw):
        raise UserError(f"{p}: its content is not what was written (digest differs); {FIX}")
    return {
        k: (
            read_json_text(v, where=str(p), key=k, fix=FIX, max_chars=2**28)
            if k.endswith("_json")
            else v
        )
        for k, v in raw.items()
        if k not in (KEY, DIGEST)
    }


def discard(path: str | os.PathLike, reason: UserError | str) -> None:
    """Log ``reason`` (one line) and delete the entry (a directory in its place stays:
    the write after the rebuild then fails and says so)."""
    log.warning("%s", " ".join(str(reason).split()))
    with contextlib.suppress(OSError):
        os.unlink(path)


def load_or_build(
    path: str | os.PathLike | None,
    build: Callable[[], T],
    *,
    read: Callable[[Path], T],
    write: Callable[[Path, T], Any],
) -> tuple[T, bool]:
    """``(value, from_cache)``: ``read(path)`` when it succeeds, else ``build()`` stored with
    ``write``. ``read`` raises ``UserError`` for an entry it refuses (damaged, another key,
    failing a check): logged, deleted, rebuilt. A failed write is logged; the value is
    still returned. ``path=None``: no cache."""
    if path is not None:
        p = Path(path)
        if os.path.lexists(p):
            try:
                return read(p), True
            except UserError as exc:
                discard(p, exc)
    value = build()
    if path is not None:
        try:
            write(Path(path), value)
        except OSError as exc:
            log.warning(
                "%s: cannot store the cache entry (%s); not cached", path, exc.strerror or exc
            )
    return value, False


def cached_arrays(
    path: str | os.PathLike | None,
    key: str,
    build: Callable[[], dict[str, Any]],
    *,
    what: str,
    check: Callable[[dict[str, Any]], Any] | None = None,
) -> tuple[dict[str, Any], bool]:
    """``load_or_build`` for a keyed ``.npz`` entry; ``check(arrays)`` raising ``UserError``
    (or ``KeyError``) refuses an entry whose content fails it (it is rebuilt)."""

    def read(p: Path) -> dict[str, Any]:
        arrays = read_entry(p, key, what=what)
        if check is not None:
            try:
                check(arrays)
            except (UserError, KeyError, ValueError) as exc:
                raise UserError(f"{p}: fails the checks of a {what} ({exc}); {FIX}") from None
        return arrays

    return load_or_build(path, build, read=read, write=lambda p, a: write_entry(p, key, a))
