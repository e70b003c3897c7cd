"""The plugin contract: built-ins, entry points, blocking, misspelled hooks, documentation."""

from __future__ import annotations

import base64
import hashlib
import json
import os
import subprocess
import sys
import textwrap
import venv
import zipfile
from pathlib import Path

import pytest

import console
from console.cli.main import main
from console.config.plugins import load_plugins
from console.core import hookspecs
from console.core.errors import UserError
from console.core.hookspecs import hookimpl


def test_plugins_json_lists_builtins_with_kinds(capsys):
    assert main(["plugins", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    kinds = {(r["kind"], r["name"]) for r in data["provides"]}
    assert ("audio_output", "twin") in kinds
    assert ("relay_board", "twin") in kinds
    assert "twin" in data["plugins"] and "core" in data["plugins"]
    assert {"plugins", "doctor", "play", "estop", "bench"} <= set(data["commands"])


def test_misspelled_hook_fails_naming_the_plugin():
    class Typo:
        @hookimpl
        def haptable_register_camera(self, register):  # missing the "s"
            pass

    with pytest.raises(UserError) as err:
        load_plugins(extra={"typo-cam": Typo()})
    msg = str(err.value)
    assert "typo-cam" in msg and "haptable_register_camera" in msg
    assert "haptable_register_cameras" in msg  # the suggestion
    assert "\n" not in msg


def test_block_env_var_removes_a_plugin_and_its_children(monkeypatch):
    monkeypatch.setenv("HAPTABLE_BLOCK_PLUGINS", "twin")
    plugins = load_plugins()
    assert not any(n == "twin" or n.startswith("twin.") for n in plugins.plugin_names())
    assert "twin" not in plugins.of("audio_output")


def test_extra_plugin_registers_like_a_builtin():
    class Cam:
        @hookimpl
        def haptable_register_cameras(self, register):
            register("toy", lambda profile: "camera", description="a toy camera")

    plugins = load_plugins(extra={"toy": Cam()})
    reg = plugins.get("camera", "toy")
    assert reg.plugin == "toy" and reg.factory(None) == "camera"


def test_every_hook_is_documented():
    hooks = hookspecs.documented_hooks()
    assert len(hooks) >= 8
    for name, doc in hooks.items():
        assert doc and len(doc.split()) >= 12, f"{name} lacks documentation"
        assert "factory" in doc or "register(" in doc, f"{name}: document what register() takes"
    module_doc = hookspecs.__doc__ or ""
    assert "register(" in module_doc


def test_unknown_hook_without_docs_would_be_caught():
    """A spec added without a docstring fails the documentation check."""

    def haptable_register_undocumented(register):
        pass

    doc = haptable_register_undocumented.__doc__
    assert not doc  # the check above would reject exactly this


def _toycam_wheel(folder: Path) -> Path:
    """A wheel of ``haptable-toycam`` (a ``haptable`` entry point) written as the wheel
    format says (PEP 427): installing it needs pip only, no build backend, so the test does
    not depend on the setuptools (or its lack of ``bdist_wheel``) of any interpreter."""
    info = "haptable_toycam-0.1.dist-info"
    files = {
        "haptable_toycam/__init__.py": textwrap.dedent("""
            from console.core.hookspecs import hookimpl

            @hookimpl
            def haptable_register_cameras(register):
                register("toycam", lambda profile: None, description="out-of-tree camera")
        """),
        f"{info}/METADATA": "Metadata-Version: 2.1\nName: haptable-toycam\nVersion: 0.1\n",
        f"{info}/WHEEL": "Wheel-Version: 1.0\nGenerator: hand\nRoot-Is-Purelib: true\n"
        "Tag: py3-none-any\n",
        f"{info}/entry_points.txt": "[haptable]\ntoycam = haptable_toycam\n",
    }
    record = []
    for name, text in files.items():
        digest = hashlib.sha256(text.encode()).digest()
        b64 = base64.urlsafe_b64encode(digest).rstrip(b"=").decode()
        record.append(f"{name},sha256={b64},{len(text.encode())}")
    files[f"{info}/RECORD"] = "\n".join([*record, f"{info}/RECORD,,"]) + "\n"
    wheel = folder / "haptable_toycam-0.1-py3-none-any.whl"
    with zipfile.ZipFile(wheel, "w") as z:
        for name, text in files.items():
            z.writestr(name, text)
    return wheel


@pytest.mark.slow
def test_out_of_tree_distribution_shows_up(tmp_path):
    """A tiny distribution with a `haptable` entry point, installed by pip into a fresh
    venv that sees nothing of the base interpreter's packages."""
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(system_site_packages=False, with_pip=False).create(env_dir)
    py = env_dir / "bin" / "python"
    subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(py), "install", "-q", "--no-deps"]
        + ["--no-index", "--disable-pip-version-check", str(_toycam_wheel(tmp_path))],
        check=True,
    )
    # the console and its dependencies from this checkout and this environment
    here = Path(console.__file__).resolve().parent.parent
    deps = [p for p in sys.path if p.endswith(("site-packages", "dist-packages"))]
    out = subprocess.run(
        [str(py), "-m", "console.cli.main", "plugins", "--json"],
        capture_output=True,
        text=True,
        check=True,
        cwd=tmp_path,
        env={
            "PATH": "/usr/bin:/bin",
            "HAPTABLE_LOAD_ENTRYPOINTS": "1",
            "HOME": str(tmp_path),
            "PYTHONPATH": os.pathsep.join([str(here), *deps]),
        },
    )
    data = json.loads(out.stdout)
    assert "toycam" in data["plugins"]
    assert {
        "kind": "camera",
        "name": "toycam",
        "plugin": "toycam",
        "description": "out-of-tree camera",
    } in data["provides"]


def test_the_outputs_process_loads_every_builtin_that_registers_what_it_builds(plugins):
    """The kernel loads only ``KERNEL_BUILTINS``: a built-in that starts registering a
    sound card, a relay board or a vibrometer must be added there, or the kernel would
    not find its driver."""
    from console.config.plugins import KERNEL_BUILTINS, KERNEL_KINDS

    owners = {reg.plugin for kind in KERNEL_KINDS for reg in plugins.of(kind).values()}
    assert owners and owners <= set(KERNEL_BUILTINS), owners - set(KERNEL_BUILTINS)
