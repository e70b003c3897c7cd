"""The README's plugin example works, and CI runs exactly the README's test command."""

from __future__ import annotations

import re
import types
from pathlib import Path

import numpy as np

from console.cli.main import Context
from console.config.plugins import load_plugins

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text()


def block(name: str) -> str:
    m = re.search(rf"<!-- {name} -->\n```\w*\n(.*?)```\n<!-- /{name} -->", README, re.S)
    assert m, f"README lacks the {name} block"
    return m.group(1)


def test_plugin_example_plays_through_the_gate():
    code = block("plugin-example")
    assert len(code.strip().splitlines()) <= 32
    mod = types.ModuleType("haptable_tick")
    exec(compile(code, "README plugin example", "exec"), mod.__dict__)
    plugins = load_plugins(extra={"tick": mod})
    assert plugins.get("effect", "tick").plugin == "tick"
    cmd = plugins.commands["tick"]
    import argparse

    parser = argparse.ArgumentParser()
    cmd.configure(parser)
    args = parser.parse_args(["--patch", "PC"])
    ctx = Context("sim", plugins)
    played = {}
    real_outputs = ctx.outputs

    def spy(fast=None):
        cm = real_outputs(fast=True)
        out = cm.__enter__()
        played["out"] = out
        return _Wrap(cm, out, played)

    ctx.outputs = spy
    assert cmd.run(args, ctx) == 0
    assert played["out"].closed  # the command left its table
    rec = played["recording"]
    assert np.max(np.abs(rec[:, 0])) > 19.0  # the 20 V tick reached the piezo channel
    assert [(r.channel, r.closed) for r in played["relay_log"]] == [(3, True), (3, False)]


class _Wrap:
    """The command's outputs (a kernel client); what the twin got is read from the
    kernel as the command leaves, before the client closes."""

    def __init__(self, cm, out, played):
        self.cm, self.out, self.played = cm, out, played

    def __enter__(self):
        return self.out

    def __exit__(self, *exc):
        self.played["recording"] = self.out.recording()
        self.played["relay_log"] = self.out.relay_log()
        return self.cm.__exit__(*exc)


def test_ci_runs_the_readme_test_command():
    ci = (ROOT / ".ci" / "run").read_text()
    assert "test-command" in ci and "README.md" in ci
    assert "pytest" in block("test-command")
    assert "haptable" in block("console-command")


def test_readme_installs_the_system_packages_ci_installs_in_one_line():
    lines = block("system-packages").strip().splitlines()
    assert len(lines) == 1 and "apt-get install" in lines[0]
    readme_pkgs = {w for w in lines[0].split() if not w.startswith("-")}
    readme_pkgs -= {"sudo", "apt-get", "install"}
    ci = (ROOT / ".ci" / "run").read_text()
    ci_pkgs = set(re.search(r"^pkgs=\((.*?)\)", ci, re.M).group(1).split())
    assert readme_pkgs == ci_pkgs
