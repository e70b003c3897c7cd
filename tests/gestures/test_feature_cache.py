"""The gesture feature cache is bound to its dataset (issue 25): set B's cached features
copied over set A's name (or a truncated, empty, /dev/zero or keyless entry) are logged,
deleted and extracted again: the features equal a clean extraction of A."""

from __future__ import annotations

import logging
import shutil
from pathlib import Path

import numpy as np
import pytest

from plugins.gestures.evaluate import cache_dir, extract
from plugins.gestures.feature_set import FeatureSet
from plugins.gestures.synth import synth

DAMAGES = ["other-set", "truncated", "empty", "dev-zero", "keyless"]


@pytest.fixture(scope="module")
def sets(tmp_path_factory) -> tuple[Path, Path]:
    d = tmp_path_factory.mktemp("sets")
    gestures = ("one_finger", "drag")
    for name, seed in (("A", 1), ("B", 2)):
        synth(d / name, 1, 2, seed=seed, workers=1, gestures=gestures, static_frames=3,
              dynamic_frames=4)  # fmt: skip
    return d / "A", d / "B"


def _same(x: FeatureSet, y: FeatureSet) -> bool:
    return (
        x.names == y.names
        and np.array_equal(x.labels, y.labels)
        and set(x.dynamic) == set(y.dynamic)
        and all(
            np.array_equal(getattr(x, f)[k], getattr(y, f)[k])
            for f in ("static", "kind", "dynamic", "score")
            for k in x.dynamic
        )
    )


def _damage(entry: Path, other: Path, how: str) -> None:
    if how == "other-set":
        shutil.copy(other, entry)
    elif how == "truncated":
        entry.write_bytes(entry.read_bytes()[: entry.stat().st_size // 2])
    elif how == "empty":
        entry.write_bytes(b"")
    elif how == "dev-zero":
        entry.unlink()
        entry.symlink_to("/dev/zero")
    else:
        with np.load(entry) as z:
            arrays = {k: z[k] for k in z.files if not k.startswith("cache_")}
        np.savez(entry, **arrays)


@pytest.mark.parametrize("damage", DAMAGES)
def test_features_of_another_set_are_extracted_again(sets, tmp_path, monkeypatch, caplog, damage):
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path / "cache"))
    a, b = sets
    clean_a = extract(a)
    (entry_a,) = cache_dir().glob("*.npz")
    clean_b = extract(b)
    (entry_b,) = set(cache_dir().glob("*.npz")) - {entry_a}
    assert not _same(clean_a, clean_b)
    assert _same(extract(a), clean_a)  # read from the cache
    _damage(entry_a, entry_b, damage)
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        again = extract(a)
    assert _same(again, clean_a) and not _same(again, clean_b)
    lines = [r.getMessage() for r in caplog.records if r.name == "haptable.cache"]
    assert len(lines) == 1 and str(entry_a) in lines[0], lines
    assert entry_a.is_file() and not entry_a.is_symlink()
    assert entry_a.read_bytes() != entry_b.read_bytes()
    assert _same(extract(b), clean_b)
