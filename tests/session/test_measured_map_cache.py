"""The kept measured map is bound to what made it (issue 25): it carries the key of the
profile's plate and vibrometer and the hash of its content inside; another map copied
over it (map B = the plate's map with its FRFs rolled by 13 points), a truncated, empty,
/dev/zero or keyless file is logged (one line), deleted and measured again, never played;
the console's Vibration screen never loads it."""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import shutil
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

DAMAGES = ["other-map", "truncated", "empty", "dev-zero", "keyless", "bit-flip"]


def _damage(path: Path, fv, how: str, tmp: Path) -> None:
    from console.files.vibration_map import save_map

    if how == "other-map":  # `cp B.npz $HAPTABLE_CACHE_DIR/console/measured-map-<key>.npz`
        b = dataclasses.replace(fv.map, frf_um_per_v=np.roll(fv.map.frf_um_per_v, 13, axis=1))
        shutil.copy(save_map(tmp / "B.npz", b), path)
    elif how == "truncated":
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "dev-zero":
        path.unlink()
        path.symlink_to("/dev/zero")
    elif how == "keyless":  # the plate's own map, as kept before maps carried their key
        save_map(path, fv.map)
    else:
        data = bytearray(path.read_bytes())
        data[len(data) // 2] ^= 0x01
        path.write_bytes(bytes(data))


def _lines(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "haptable.cache"]


def _query(fv, capsys) -> dict:
    """`haptable tables query measured --active 51 --passive 52 --json` (no tables cache:
    the map is what is under test)."""
    from plugins.vibrotactile.cli import tables as tables_cli

    p = argparse.ArgumentParser()
    tables_cli.configure_tables(p)
    argv = ["query", "measured", "--active", "51", "--passive", "52", "--json", "--rule", "paper"]
    args = p.parse_args([*argv, "--cache-dir", "none"])
    capsys.readouterr()
    assert tables_cli.run_tables(args, SimpleNamespace(profile=fv.profile, pm=fv.pm)) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("damage", DAMAGES)
def test_a_bad_kept_map_is_measured_again_never_played(
    fake_vibrometer, tmp_path, capsys, caplog, damage
):
    from console.runtime.measured_map import measured_map, measured_map_path

    fv = fake_vibrometer
    clean = _query(fv, capsys)
    path = measured_map_path(fv.profile)
    assert fv.calls == [1] and path.is_file()
    _damage(path, fv, damage, tmp_path)
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        assert _query(fv, capsys) == clean
    assert fv.calls == [1, 1], "measured again"
    lines = _lines(caplog)
    assert len(lines) == 1 and str(path) in lines[0] and "\n" not in lines[0], lines
    assert path.is_file() and not path.is_symlink()
    m = measured_map(fv.profile, fv.pm)  # the new file is the plate's, read without a word
    assert m.content_hash() == fv.map.content_hash() and fv.calls == [1, 1]


@pytest.mark.parametrize("damage", ["other-map", "truncated"])
def test_the_console_never_loads_a_bad_kept_map(fake_vibrometer, tmp_path, caplog, damage):
    """The Vibration screen (``load_cached``) and a scene (``current_map``) find no map
    instead of another plate's; asking never measures; the file is gone."""
    from console.core.errors import UserError
    from console.runtime.measured_map import measured_map_file
    from console.session import ConsoleSession

    fv = fake_vibrometer
    path = measured_map_file(fv.profile, fv.pm)
    _damage(path, fv, damage, tmp_path)
    session = ConsoleSession(SimpleNamespace(profile=fv.profile, pm=fv.pm))
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        assert session.vibration.load_cached() is None
        with pytest.raises(UserError, match="no vibration map yet"):
            session.vibration.current_map()
    assert len(_lines(caplog)) == 1 and not path.exists() and fv.calls == [1]
    assert session.vibration.load_cached() is None


def test_a_good_kept_map_carries_its_key_and_is_found(fake_vibrometer):
    from console.files.vibration_map import load_map
    from console.runtime.measured_map import measured_map_file
    from console.session import ConsoleSession

    fv = fake_vibrometer
    path = measured_map_file(fv.profile, fv.pm)
    prov = load_map(path).provenance
    assert len(prov["cache_key"]) == 64 and prov["content_sha256"] == fv.map.content_hash()
    session = ConsoleSession(SimpleNamespace(profile=fv.profile, pm=fv.pm))
    assert session.vibration.load_cached() is not None
    assert session.vibration.current_map() is not None and fv.calls == [1]


def test_another_plates_kept_map_is_not_this_plates(fake_vibrometer, caplog):
    """The file of one plate configuration copied to another's name is measured again."""
    from console.runtime.measured_map import measured_map_file

    fv = fake_vibrometer
    first = measured_map_file(fv.profile, fv.pm)
    fv.profile.plate = {"thickness_mm": 99.0}
    from console.runtime.measured_map import measured_map_path

    second = measured_map_path(fv.profile)
    second.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy(first, second)
    with caplog.at_level(logging.WARNING, logger="haptable.cache"):
        assert measured_map_file(fv.profile, fv.pm) == second
    assert fv.calls == [1, 1] and len(_lines(caplog)) == 1
