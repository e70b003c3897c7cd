"""The Devices screen's self-test (key s): the ``selftest`` command a plugin registers
(``plugins.vibrotactile.cli.selftest``), run in the screen's worker thread, its lines back.

The console knows the command by its registered name only: it runs it with ``--json``
(the operator's outputs through the gate, like ``haptable selftest``) and reads the
report. Without a plugin offering it, it says so.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
from types import SimpleNamespace
from typing import Any

from console.core.errors import SafetyRefusal, UserError


def run_selftest(profile: Any, pm: Any) -> tuple[bool, str]:
    """(healthy, one line for the status line) of a full self-test on ``profile``."""
    cmd = pm.commands.get("selftest")
    if cmd is None:
        return False, "self-test: no plugin offers it (the vibrotactile plugin does)"
    p = argparse.ArgumentParser()
    cmd.configure(p)
    buf = io.StringIO()
    try:
        with contextlib.redirect_stdout(buf):
            code = int(
                cmd.run(p.parse_args(["--json"]), SimpleNamespace(profile=profile, pm=pm)) or 0
            )
        report = json.loads(buf.getvalue())
    except (UserError, SafetyRefusal) as exc:
        return False, f"self-test: {exc}"
    except ValueError:
        return False, "self-test: its report was not readable; run `haptable selftest`"
    lines = report.get("lines") or []
    took = f" ({report.get('elapsed_s', 0):.0f} s)"
    return code == 0, "self-test: " + "; ".join(lines) + took
