"""The README's Devices row names the test signals its list shows (``haptable play``'s
stimuli: ``console.signals.stimuli.STIMULI``) and says which the signal library shares:
it said they were "named as in the signal library: screen-180" while the list showed
``sine-PA``, ``relay-walk`` and the library ``tone-250``, ``bursts`` (a new operator's
try)."""

from __future__ import annotations

import re
from pathlib import Path

from console.config.signal_library import BUILTIN
from console.signals.stimuli import STIMULI

README = (Path(__file__).resolve().parents[2] / "README.md").read_text()


def _t_clause() -> str:
    row = next(line for line in README.splitlines() if line.startswith("| F1 | Devices |"))
    m = re.search(r"`t` plays the chosen test signal(.*?)and shows the peak", row)
    assert m, "the Devices row says what t plays"
    return m.group(1)


def test_the_devices_row_names_the_stimuli_the_list_shows():
    clause = _t_clause()
    named = set(re.findall(r"`([A-Za-z0-9-]+)`", clause))
    shown = {n for n in STIMULI if not n.startswith("sine-P")} | {"sine-PA", "sine-PALL"}
    assert shown <= named, f"the row leaves out {sorted(shown - named)}"
    others = named - set(STIMULI)
    assert others <= set(BUILTIN), f"neither a stimulus nor a library signal: {others}"
    if others:  # the library's own names are said to be the library's
        assert "signal library" in clause, clause
    shared = sorted(set(STIMULI) & set(BUILTIN))
    assert all(f"`{n}`" in clause for n in shared), shared
