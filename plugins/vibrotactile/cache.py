"""Explicit on-disk cache for derived arrays, keyed by a hash of their inputs.

``cached(cache_dir, kind, key, compute)`` returns ``compute()``'s dict of arrays (and
JSON-able values under ``*_json`` names), stored as ``<cache_dir>/<kind>-<hash[:24]>.npz``
through ``console.files.cache_files``: the entry carries the hash of ``key`` and of its content
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

from console.plugin_api import cache_dir as console_cache_dir
from console.plugin_api import cached_arrays, input_hash
from console.plugin_api import entry_path as cache_entry_path

#: bumped when what an entry holds changes meaning
CODE_VERSION = 2


def default_cache_dir() -> Path:
    """HapTable's cache directory (``console.files.paths.cache_dir``)."""
    return console_cache_dir()


def key_hash(key: dict) -> str:
    """The entry's key: SHA-256 of ``key`` and this module's version."""
    return input_hash({"v": CODE_VERSION, **key})


def entry_path(cache_dir: str | os.PathLike, kind: str, key: dict) -> Path:
    return cache_entry_path(cache_dir, kind, key_hash(key))


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
    return cached_arrays(
        path, key_hash(key), compute, what=what or f"{kind} cache entry", check=check
    )


def cached(
    cache_dir: str | os.PathLike | None, kind: str, key: dict, compute: Callable[[], dict]
) -> dict:
    return cached_entry(cache_dir, kind, key, compute)[0]
