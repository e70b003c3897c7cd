"""The projector plugin registers how it is started (``haptable_register_projectors``);
the console's service takes the command from that registration and knows no plugin module."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from console.config.plugins import BUILTIN_PLUGINS, load_plugins
from console.config.profile import load_profile
from console.core.errors import UserError
from console.runtime.projector.service import ProjectorService, projector_launch
from console.runtime.projector.supervisor import ProjectorLaunch


@pytest.fixture(scope="module")
def plugins():
    return load_plugins()


def test_the_projector_plugin_registers_its_command(plugins, tmp_path):
    profile = load_profile("sim", plugins)
    regs = plugins.of("projector")
    assert set(regs) == {"moderngl"} and regs["moderngl"].plugin == "projector"
    assert profile.get("projector.driver") == "moderngl"
    sock = tmp_path / "p.sock"
    launch = projector_launch(profile, plugins, sock, headless=True, extra=["--size", "32x32"])
    argv = list(launch.argv)
    assert argv[:3] == [sys.executable, "-m", "plugins.projector"]
    assert argv[argv.index("--socket") + 1] == str(sock)
    assert argv[argv.index("--profile") + 1] == str(profile.path)
    assert "--headless" in argv and argv[-2:] == ["--size", "32x32"]
    assert launch.environment() is None  # the console's own environment


def _with_projectors(regs: dict, profile_data: dict | None = None):
    plugins = SimpleNamespace(of=lambda kind: regs if kind == "projector" else {})
    data = profile_data or {}
    profile = SimpleNamespace(get=lambda key, default=None: data.get(key, default), path=None)
    return plugins, profile


def test_without_a_registered_projector_starting_says_which_plugin_to_enable(tmp_path):
    plugins, profile = _with_projectors({})
    with pytest.raises(UserError, match="enable the projector plugin") as e:
        ProjectorService.from_profile(profile, plugins, log_path=tmp_path / "log")
    assert "\n" not in str(e.value)


def test_without_the_projector_plugin_the_console_loads_and_says_so(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    builtins = {k: v for k, v in BUILTIN_PLUGINS.items() if k != "projector"}
    pm = load_plugins(builtins=builtins)
    assert pm.of("projector") == {}
    with pytest.raises(UserError, match="enable the projector plugin"):
        ProjectorService.from_profile(None, pm)


def test_the_profile_picks_a_projector_by_name_and_an_unknown_name_is_one_line(tmp_path):
    made = []

    def other(profile, *, socket_path, headless=False, extra=()):
        made.append((socket_path, headless, list(extra)))
        return ProjectorLaunch(["/bin/true", str(socket_path)], env={"HAPTABLE_X": "1"})

    def builtin(profile, **kw):
        raise AssertionError("the profile named the other one")

    regs = {
        "moderngl": SimpleNamespace(name="moderngl", plugin="projector", factory=builtin),
        "other": SimpleNamespace(name="other", plugin="third", factory=other),
    }
    plugins, profile = _with_projectors(
        regs, {"projector.driver": "other", "projector.socket_path": str(tmp_path / "p.sock")}
    )
    svc = ProjectorService.from_profile(profile, plugins, log_path=tmp_path / "log")
    try:
        assert svc.supervisor.command == ["/bin/true", str(tmp_path / "p.sock")]
        assert svc.supervisor.env["HAPTABLE_X"] == "1"
        assert svc.supervisor.env["PATH"] == os.environ["PATH"]  # additions, not a new env
        assert made == [(Path(tmp_path / "p.sock"), False, [])]
    finally:
        svc.close()
    plugins, profile = _with_projectors(regs, {"projector.driver": "nope"})
    with pytest.raises(UserError, match=r"driver = 'nope': no such projector; available: moder"):
        projector_launch(profile, plugins, tmp_path / "p.sock")


def test_a_projector_that_gives_no_command_is_named(tmp_path):
    reg = SimpleNamespace(name="empty", plugin="third", factory=lambda p, **kw: ProjectorLaunch([]))
    plugins, profile = _with_projectors({"empty": reg})
    with pytest.raises(UserError, match=r"projector 'empty' \(plugin third\): gave no command"):
        projector_launch(profile, plugins, tmp_path / "p.sock")


def test_a_profile_naming_an_unknown_projector_is_refused_when_loaded(plugins, tmp_path):
    from console.config.profile import ProfileError

    sim = (Path(__file__).parents[2] / "profiles" / "sim.toml").read_text()
    path = tmp_path / "bad.toml"
    path.write_text(
        sim + '\n[projector]\ndriver = "modrengl"\n'
        if "[projector]" not in sim
        else sim.replace("[projector]", '[projector]\ndriver = "modrengl"', 1)
    )
    with pytest.raises(ProfileError, match=r"bad.toml.*\[projector\] driver.*'moderngl'") as e:
        load_profile(str(path), plugins)
    assert "\n" not in str(e.value)
