"""Explicit on-disk cache for derived arrays, keyed by a hash of their inputs.

``cached(cache_dir, kind, key, compute)`` returns ``compute()``'s dict of arrays (and
JSON-able scalars), storing it as ``<cache_dir>/<kind>-<sha256(key)[:24]>.npz``. The key
is any JSON-able dict; it must contain everything the result depends on (the map's
``content_hash()``, parameters, code version). ``cache_dir=None`` disables caching.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from console import paths
from console.errors import UserError
from console.npz_safe import read_json_text, read_npz

CODE_VERSION = 1

log = logging.getLogger("haptable.vibrotactile.cache")


def default_cache_dir() -> Path:
    """HapTable's cache directory (``console.paths.cache_dir``)."""
    return paths.cache_dir()


def key_hash(key: dict) -> str:
    blob = json.dumps({"v": CODE_VERSION, **key}, sort_keys=True, default=str).encode()
    return hashlib.sha256(blob).hexdigest()[:24]


def _json(v, path: Path, key: str):
    return read_json_text(v, where=str(path), key=key, fix="", max_chars=2**28)


def read_entry(path: Path) -> dict:
    """A cache entry's arrays (``*_json`` keys decoded); ``UserError`` if it is damaged."""
    out = read_npz(path, what="cache entry", fix="it is recomputed")
    return {k: (_json(v, path, k) if k.endswith("_json") else v) for k, v in out.items()}


def write_entry(path: Path, result: dict) -> None:
    """Store ``result`` atomically (a reader never sees half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    with open(tmp, "wb") as fh:
        np.savez(
            fh,
            **{
                k: (np.array(json.dumps(v)) if k.endswith("_json") else v)
                for k, v in result.items()
            },
        )
    os.replace(tmp, path)


def cached(
    cache_dir: str | os.PathLike | None, kind: str, key: dict, compute: Callable[[], dict]
) -> dict:
    if cache_dir is None:
        return compute()
    path = Path(cache_dir) / f"{kind}-{key_hash(key)}.npz"
    if path.exists():
        try:
            return read_entry(path)
        except UserError as exc:  # a torn write or a damaged file: recompute
            log.warning("cache entry damaged, recomputing it: %s", exc)
            path.unlink(missing_ok=True)
    result = compute()
    write_entry(path, result)
    return result
