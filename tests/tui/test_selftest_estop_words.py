"""The self-test run from the console words an e-stop refusal as the console does, its
key first, whatever refused it: the table latched when it opened its outputs (the CLI's
words name `haptable reset` at a terminal first) or the kernel's "reset it first"."""

from __future__ import annotations

from types import SimpleNamespace

from console.core.errors import EStopLatched, SafetyRefusal
from console.tui import selftest_action


def _refused_by(exc: Exception, monkeypatch) -> str:
    def run(*_a, **_k):
        raise exc

    monkeypatch.setattr(selftest_action, "_run", run)
    pm = SimpleNamespace(commands={"selftest": object()})
    ok, line = selftest_action.run_selftest(None, pm)
    assert ok is None
    return line


def test_a_latched_table_is_refused_with_the_consoles_key(monkeypatch):
    cli = (
        "table sim: e-stop latched (operator e-stop (console)); nothing plays until an "
        "operator resets it: `haptable reset` at a terminal, or ctrl+r in the console"
    )
    line = _refused_by(EStopLatched(cli, "operator e-stop (console)"), monkeypatch)
    assert line == "self-test refused: e-stop active (operator e-stop (console)), ctrl+r resets"


def test_the_kernels_reset_it_first_becomes_the_consoles_key(monkeypatch):
    exc = SafetyRefusal("e-stop active (watchdog: frame loop stalled); reset it first")
    line = _refused_by(exc, monkeypatch)
    assert line == "self-test refused: e-stop active (watchdog: frame loop stalled), ctrl+r resets"
