"""Every vibrotactile cache entry is bound to its inputs (issue 25): map B is map A with its
FRFs rolled by 13 points; B's entry copied over A's name (or a truncated, empty,
/dev/zero or keyless entry) is logged, deleted and rebuilt: the answer equals a clean
build of A, never B's. Covers the tables (``tables-*``), the pair answers (``pair-*``),
the flows under a hand (``handflow-*``) and the flow atlas (``flowatlas-*``)."""

from __future__ import annotations

import dataclasses
import json
import logging
import shutil
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from console.cli.main import main
from console.files.vibration_map import VibrationMap, save_map

DAMAGES = ["other-map", "truncated", "empty", "dev-zero", "keyless"]


def _maps() -> tuple[VibrationMap, VibrationMap]:
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map, default_freq_hz

    a = analytic_map(SSPlate(), default_freq_hz(625.0, 2.0))
    b = dataclasses.replace(a, frf_um_per_v=np.roll(a.frf_um_per_v, 13, axis=1))
    return a, b


@pytest.fixture(scope="module")
def maps(tmp_path_factory) -> SimpleNamespace:
    d = tmp_path_factory.mktemp("maps")
    a, b = _maps()
    return SimpleNamespace(a=a, b=b, pa=save_map(d / "A.npz", a), pb=save_map(d / "B.npz", b))


def _damage(entry: Path, other: Path | None, how: str) -> None:
    if how == "other-map":
        assert other is not None
        shutil.copy(other, entry)
    elif how == "truncated":
        entry.write_bytes(entry.read_bytes()[: entry.stat().st_size // 2])
    elif how == "empty":
        entry.write_bytes(b"")
    elif how == "dev-zero":
        entry.unlink()
        entry.symlink_to("/dev/zero")
    else:  # the arrays without the key: what HapTable wrote before entries carried one
        with np.load(entry) as z:
            arrays = {k: z[k] for k in z.files if not k.startswith("cache_")}
        np.savez(entry, **arrays)


def _lines(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "haptable.cache"]


def _new(folder: Path, pattern: str, before: set[Path]) -> Path:
    (entry,) = set(folder.glob(pattern)) - before
    return entry


def _cli_json(capsys, *argv: str) -> dict:
    capsys.readouterr()
    code = main(list(argv))
    out = capsys.readouterr()
    assert code == 0, out.err
    return json.loads(out.out)


@pytest.mark.parametrize("damage", DAMAGES)
def test_tables_entry_of_another_map_is_rebuilt_not_played(maps, tmp_path, capsys, caplog, damage):
    """`cp C/tables-<hashB>.npz C/tables-<hashA>.npz; haptable flow A.npz --from 51 --to 52
    --json --cache-dir C`: A's flow, as a clean build gives it."""
    c = tmp_path / "C"

    def flow(path: Path) -> dict:
        return _cli_json(capsys, "flow", str(path), "--from", "51", "--to", "52", "--json",
                         "--cache-dir", str(c))  # fmt: skip

    clean_a = flow(maps.pa)
    entry_a = _new(c, "tables-*.npz", set())
    clean_b = flow(maps.pb)
    entry_b = _new(c, "tables-*.npz", {entry_a})
    assert clean_a != clean_b  # the two maps' flows differ: the swap would show
    _damage(entry_a, entry_b, damage)
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        assert flow(maps.pa) == clean_a
    lines = _lines(caplog)
    assert len(lines) == 1 and str(entry_a) in lines[0], lines
    assert entry_a.is_file() and not entry_a.is_symlink()
    assert entry_a.read_bytes() != entry_b.read_bytes()  # replaced by A's own entry
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        assert flow(maps.pa) == clean_a  # read from the cache now, without a word
        assert flow(maps.pb) == clean_b
    assert _lines(caplog) == []


@pytest.mark.parametrize("damage", DAMAGES)
def test_pair_entry_of_another_map_is_rebuilt(maps, tmp_path, caplog, damage):
    from plugins.vibrotactile.lazy import pair_cached, tables_cached

    c = tmp_path / "C"
    ta, tb = tables_cached(maps.a, 650.0, c), tables_cached(maps.b, 650.0, c)
    xy = ((250.0, 200.0), (330.0, 230.0))
    clean_a = pair_cached(ta, *xy, "spline", c)
    entry_a = _new(c, "pair-*.npz", set())
    clean_b = pair_cached(tb, *xy, "spline", c)
    entry_b = _new(c, "pair-*.npz", {entry_a})
    assert clean_a != clean_b
    _damage(entry_a, entry_b, damage)
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        assert pair_cached(ta, *xy, "spline", c) == clean_a
    assert len(_lines(caplog)) == 1 and str(entry_a) in _lines(caplog)[0]
    assert pair_cached(tb, *xy, "spline", c) == clean_b


@pytest.mark.parametrize("damage", ["other-map", "truncated", "keyless"])
def test_hand_flow_entry_of_another_map_is_rebuilt_not_played(
    maps, tmp_path, capsys, caplog, damage
):
    """`haptable flow A.npz --hand X,Y --direction D --cache-dir C` with B's entry at A's
    name: A's flow."""
    c = tmp_path / "C"

    def flow(path: Path) -> dict:
        return _cli_json(capsys, "flow", str(path), "--hand", "300,200", "--direction", "left",
                         "--json", "--cache-dir", str(c))  # fmt: skip

    clean_a = flow(maps.pa)
    entry_a = _new(c, "handflow-*.npz", set())
    clean_b = flow(maps.pb)
    entry_b = _new(c, "handflow-*.npz", {entry_a})
    assert clean_a != clean_b
    _damage(entry_a, entry_b, damage)
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        assert flow(maps.pa) == clean_a
    assert len(_lines(caplog)) == 1 and str(entry_a) in _lines(caplog)[0]


# ------------------------------------------------------------------------------- the flow atlas
STEP_MM = 40.0


@pytest.fixture
def atlas_setup(tmp_path, profile, plugins, monkeypatch, maps):
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(tmp_path / "cache"))  # HapTable's one cache
    return SimpleNamespace(profile=profile, pm=plugins, cache=tmp_path / "cache", maps=maps)


def _atlas(s, path: Path):
    eff = s.pm.get("effect", "hand_flow").factory(s.profile)  # a fresh effect: no memory
    return eff.hand_flow_atlas(str(path), STEP_MM, workers=1)


def _same_atlas(x, y) -> bool:
    keys = [k for k, v in x.a.items() if isinstance(v, np.ndarray)]
    return set(keys) <= set(y.a) and all(np.array_equal(x.a[k], y.a[k]) for k in keys)


@pytest.mark.parametrize("damage", ["other-map", "empty", "keyless"])
def test_flow_atlas_of_another_map_is_rebuilt_never_played(atlas_setup, caplog, damage):
    """Map B's atlas copied over map A's is not returned ``from_cache``: rebuilt from A."""
    s = atlas_setup
    clean_a = _atlas(s, s.maps.pa)
    entry_a = _new(s.cache, "flowatlas-*.npz", set())
    clean_b = _atlas(s, s.maps.pb)
    entry_b = _new(s.cache, "flowatlas-*.npz", {entry_a})
    assert not _same_atlas(clean_a, clean_b)
    _damage(entry_a, entry_b, damage)
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        again = _atlas(s, s.maps.pa)
    assert not again.from_cache, "rebuilt, not read"
    assert _same_atlas(again, clean_a)
    assert len(_lines(caplog)) == 1 and str(entry_a) in _lines(caplog)[0]
    assert _atlas(s, s.maps.pa).from_cache  # A's own entry now
