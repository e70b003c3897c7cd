"""The one cache mechanism (console/files/cache_files.py): an entry carries the hash of its inputs
and of its content inside it; an entry of other inputs, a damaged, empty, truncated or
foreign one is logged (one line), deleted and rebuilt, never used."""

from __future__ import annotations

import logging
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from console.core.errors import UserError
from console.files import cache_files as cf

WHAT = "test cache entry"


def _arrays(seed: int) -> dict:
    rng = np.random.default_rng(seed)
    return {"x": rng.normal(size=(4, 5)), "n": np.arange(3) + seed, "info_json": {"seed": seed}}


def _same(a: dict, b: dict) -> bool:
    return (
        set(a) == set(b)
        and all(np.array_equal(a[k], b[k]) for k in a if not k.endswith("_json"))
        and all(a[k] == b[k] for k in a if k.endswith("_json"))
    )


class Builder:
    def __init__(self, seed: int) -> None:
        self.seed, self.calls = seed, 0

    def __call__(self) -> dict:
        self.calls += 1
        return _arrays(self.seed)


def _get(path: Path, key: str, build: Builder, check=None) -> tuple[dict, bool]:
    return cf.cached_arrays(path, key, build, what=WHAT, check=check)


def test_an_entry_carries_its_key_and_round_trips(tmp_path):
    key = cf.input_hash({"map": "a", "band_hz": 650.0})
    assert len(key) == 64 and key == cf.input_hash({"band_hz": 650.0, "map": "a"})
    path = cf.entry_path(tmp_path, "tables", key)
    assert path.name == f"tables-{key[:24]}.npz"
    cf.write_entry(path, key, _arrays(1))
    assert _same(cf.read_entry(path, key, what=WHAT), _arrays(1))
    assert not list(tmp_path.glob(".*.tmp"))  # the temporary file is gone


def test_an_entry_of_other_inputs_under_this_name_is_refused(tmp_path):
    ka, kb = cf.input_hash({"map": "a"}), cf.input_hash({"map": "b"})
    pa, pb = cf.entry_path(tmp_path, "k", ka), cf.entry_path(tmp_path, "k", kb)
    cf.write_entry(pb, kb, _arrays(2))
    shutil.copy(pb, pa)  # B's entry copied over A's name
    with pytest.raises(UserError, match="made from other inputs") as e:
        cf.read_entry(pa, ka, what=WHAT)
    assert "\n" not in str(e.value) and str(pa) in str(e.value)


@pytest.mark.parametrize(
    "damage",
    ["other-key", "no-key", "digest", "truncated", "empty", "dev-zero", "bit-flip", "dangling"],
)
def test_a_bad_entry_is_logged_deleted_and_rebuilt_never_used(tmp_path, caplog, damage):
    ka, kb = cf.input_hash({"map": "a"}), cf.input_hash({"map": "b"})
    pa, pb = cf.entry_path(tmp_path, "k", ka), cf.entry_path(tmp_path, "k", kb)
    build_a, build_b = Builder(1), Builder(2)
    clean, fresh = _get(pa, ka, build_a)
    assert fresh is False and build_a.calls == 1
    _get(pb, kb, build_b)
    if damage == "other-key":
        shutil.copy(pb, pa)
    elif damage == "no-key":  # an entry written before entries carried their key
        np.savez(pa, **{k: np.asarray(v) for k, v in _arrays(2).items() if k != "info_json"})
    elif damage == "digest":  # the right key, another content
        raw = dict(np.load(pa))
        raw["x"] = raw["x"] + 1.0
        np.savez(pa, **raw)
    elif damage == "truncated":
        pa.write_bytes(pa.read_bytes()[:300])
    elif damage == "empty":
        pa.write_bytes(b"")
    elif damage == "dev-zero":
        pa.unlink()
        pa.symlink_to("/dev/zero")
    elif damage == "bit-flip":
        data = bytearray(pa.read_bytes())
        data[len(data) // 3] ^= 0x10
        pa.write_bytes(bytes(data))
    else:
        pa.unlink()
        pa.symlink_to(tmp_path / "nowhere.npz")
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        got, from_cache = _get(pa, ka, build_a)
    assert from_cache is False and build_a.calls == 2, "rebuilt, not read"
    assert _same(got, clean) and not _same(got, _arrays(2))
    lines = [r.getMessage() for r in caplog.records if r.name == "haptable.cache"]
    assert len(lines) == 1 and str(pa) in lines[0] and "\n" not in lines[0]
    assert "deleted and rebuilt" in lines[0]
    assert pa.is_file() and not pa.is_symlink()  # replaced by A's own entry
    assert _same(cf.read_entry(pa, ka, what=WHAT), clean)
    again, from_cache = _get(pa, ka, build_a)
    assert from_cache is True and build_a.calls == 2 and _same(again, clean)


def test_a_check_refuses_content_with_the_right_key(tmp_path, caplog):
    key = cf.input_hash({"map": "a"})
    path = cf.entry_path(tmp_path, "k", key)
    cf.write_entry(path, key, {**_arrays(1), "x": np.full((4, 5), 1e9)})  # out of range

    def check(a: dict) -> None:
        if np.abs(a["x"]).max() > 100:
            raise UserError("key 'x': out of range")

    build = Builder(1)
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        got, from_cache = _get(path, key, build, check)
    assert not from_cache and build.calls == 1 and _same(got, _arrays(1))
    (line,) = [r.getMessage() for r in caplog.records if r.name == "haptable.cache"]
    assert "out of range" in line and str(path) in line


def test_no_cache_and_an_unwritable_cache_still_answer(tmp_path, caplog):
    build = Builder(1)
    got, from_cache = cf.cached_arrays(None, "k", build, what=WHAT)
    assert _same(got, _arrays(1)) and not from_cache
    blocker = tmp_path / "file"
    blocker.write_text("")
    key = cf.input_hash({"map": "a"})
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        got, _ = _get(cf.entry_path(blocker, "k", key), key, build)  # its folder is a file
    assert _same(got, _arrays(1))
    assert any("not cached" in r.getMessage() for r in caplog.records)


def test_a_failed_build_stores_nothing(tmp_path):
    key = cf.input_hash({"map": "a"})
    path = cf.entry_path(tmp_path, "k", key)

    def boom() -> dict:
        raise RuntimeError("cancelled")

    with pytest.raises(RuntimeError):
        _get(path, key, boom)  # type: ignore[arg-type]
    assert os.listdir(tmp_path) == []
