"""Explicit on-disk cache for derived arrays, keyed by a hash of their inputs.

``cached(cache_dir, kind, key, compute)`` returns ``compute()``'s dict of arrays (and
JSON-able values under ``*_json`` names), stored as ``<cache_dir>/<kind>-<hash[:24]>.npz``
through ``console.cache_files``: the entry carries the hash of ``key`` and of its content
inside it, and an entry of other inputs (another map's copied over this name), damaged or
empty is logged, deleted and recomputed, never returned. The key is any JSON-able dict; it
must contain everything the result depends on (the map's ``content_hash()``, parameters,
code version). ``cache_dir=None`` disables caching.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from console import cache_files, paths

#: bumped when what an entry holds changes meaning
CODE_VERSION = 2


def default_cache_dir() -> Path:
    """HapTable's cache directory (``console.paths.cache_dir``)."""
    return paths.cache_dir()


def key_hash(key: dict) -> str:
    """The entry's key: SHA-256 of ``key`` and this module's version."""
    return cache_files.input_hash({"v": CODE_VERSION, **key})


def entry_path(cache_dir: str | os.PathLike, kind: str, key: dict) -> Path:
    return cache_files.entry_path(cache_dir, kind, key_hash(key))


def cached_entry(
    cache_dir: str | os.PathLike | None,
    kind: str,
    key: dict,
    compute: Callable[[], dict],
    *,
    what: str | None = None,
    check: Callable[[dict], Any] | None = None,
) -> tuple[dict, bool]:
    """``(result, from_cache)``; ``check(result)`` raising ``UserError`` refuses an entry
    whose content fails it (recomputed)."""
    path = None if cache_dir is None else entry_path(cache_dir, kind, key)
    return cache_files.cached_arrays(
        path, key_hash(key), compute, what=what or f"{kind} cache entry", check=check
    )


def cached(
    cache_dir: str | os.PathLike | None, kind: str, key: dict, compute: Callable[[], dict]
) -> dict:
    return cached_entry(cache_dir, kind, key, compute)[0]
