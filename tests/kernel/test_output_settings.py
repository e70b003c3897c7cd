"""A table's kernel serves every client whose profile has its output settings: camera,
vision and TUIO settings never lock a shell out; a real output setting that differs is
refused in one line naming the key and the fix, exit 5 (the table is busy: another
console holds its outputs)."""

from __future__ import annotations

from console.config.profile import load_profile, save_overrides
from console.kernel.client import open_outputs

from .test_kernel import haptable


def test_tuio_switched_on_in_the_console_does_not_lock_a_shell_out(profile, plugins):
    console = open_outputs(profile, plugins, private=False)  # the console's, as F2 has it
    try:
        save_overrides(profile, {"tuio.enabled": True, "camera.fps": 30.0}, plugins)  # F2 u
        shell = open_outputs(load_profile("sim", plugins), plugins, private=False)
        try:
            assert shell.kernel_pid == console.kernel_pid  # it joins the same outputs
        finally:
            shell.close()
    finally:
        console.close()


def test_a_differing_output_setting_is_named_with_its_fix(profile, plugins):
    console = open_outputs(profile, plugins, private=False)
    try:
        save_overrides(profile, {"limits.piezo_max_v": 100.0}, plugins)
        got = haptable("play", "sine-PA")
    finally:
        console.close()
    assert got.returncode == 5, got.stdout + got.stderr
    line = got.stderr.strip()
    assert "limits.piezo_max_v 250.0 there, 100.0 here" in line, line
    assert "quit it first, or set the same value in this profile" in line, line
    assert "tuio." not in line and "Traceback" not in line and "\n" not in line  # no key of it
