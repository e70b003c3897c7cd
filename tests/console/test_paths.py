"""console.files.paths: one rule per directory, and the tests never write outside their tmp root."""

from __future__ import annotations

import os
import pwd
from pathlib import Path

import pytest

from console.files import paths

FUNCS = {
    "config": ("HAPTABLE_CONFIG_DIR", "XDG_CONFIG_HOME", ".config", paths.config_dir),
    "state": ("HAPTABLE_STATE_DIR", "XDG_STATE_HOME", ".local/state", paths.state_dir),
    "cache": ("HAPTABLE_CACHE_DIR", "XDG_CACHE_HOME", ".cache", paths.cache_dir),
    "data": ("HAPTABLE_DATA_DIR", "XDG_DATA_HOME", ".local/share", paths.data_dir),
}


@pytest.mark.parametrize("kind", sorted(FUNCS))
def test_override_then_xdg_then_home(kind, tmp_path, monkeypatch):
    override, xdg, default, fn = FUNCS[kind]
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv(override, str(tmp_path / "mine"))
    monkeypatch.setenv(xdg, str(tmp_path / "xdg"))
    assert fn() == tmp_path / "mine"
    assert fn("a", "b.npz") == tmp_path / "mine" / "a" / "b.npz"
    monkeypatch.delenv(override)
    assert fn("a") == tmp_path / "xdg" / "haptable" / "a"
    for ignored in ("", "relative/dir"):  # the XDG spec: empty or relative means unset
        monkeypatch.setenv(xdg, ignored)
        assert fn() == tmp_path / "home" / default / "haptable"
    monkeypatch.delenv(xdg)
    assert fn() == tmp_path / "home" / default / "haptable"


def test_runtime_dir_rule_is_the_checked_one(tmp_path, monkeypatch):
    from console.kernel.private_dir import runtime_dir

    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    assert paths.runtime_dir() == tmp_path / "haptable"
    assert runtime_dir() == paths.runtime_dir() and paths.runtime_dir().is_dir()
    monkeypatch.delenv("XDG_RUNTIME_DIR")
    assert paths.runtime_dir() == Path(f"/tmp/haptable-{os.getuid()}")


def test_every_directory_the_project_writes_is_under_the_tests_tmp_roots(pinned_root):
    """conftest pins them: a test that caches a table cannot touch the user's ~/.cache."""
    from console.config.profile import search_dirs
    from console.runtime.measured_map import cache_dir as console_cache
    from console.tui.logs import log_path
    from plugins.gestures.evaluate import cache_dir as gestures_cache
    from plugins.gestures.panel import data_dir as gestures_data
    from plugins.vibrotactile.cache import default_cache_dir as vt_cache

    written = [
        paths.config_dir(),
        paths.state_dir(),
        paths.cache_dir(),
        paths.data_dir(),
        log_path(),
        console_cache(),  # the measured maps (the console's and the demos')
        gestures_cache(),
        gestures_data(),
        vt_cache(),
        search_dirs()[-2],  # the operator's profiles (the last is the project's own)
    ]
    for p in written:
        assert p.is_relative_to(pinned_root), p
    real_home = Path(pwd.getpwuid(os.getuid()).pw_dir)
    for p in written:
        assert not p.is_relative_to(real_home / ".cache"), p
    assert paths.runtime_dir().is_relative_to(Path(os.environ["XDG_RUNTIME_DIR"]))


def test_per_profile_dirs_are_one_component_below_config_and_state(tmp_path, monkeypatch):
    monkeypatch.setenv("HAPTABLE_CONFIG_DIR", str(tmp_path / "cfg"))
    monkeypatch.setenv("HAPTABLE_STATE_DIR", str(tmp_path / "st"))
    assert (
        paths.profile_config_dir("sim", "signals.toml") == tmp_path / "cfg" / "sim" / "signals.toml"
    )
    assert paths.profile_state_dir("haptable-lab") == tmp_path / "st" / "haptable-lab"
    # a name never climbs out or lands in the folder of profile files
    assert paths.profile_config_dir("../x/y").parent == tmp_path / "cfg"
    assert paths.profile_config_dir("profiles") != paths.config_dir("profiles")
