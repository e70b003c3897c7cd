"""``haptable study list``: the protocols in ``studies/`` as columns as wide as their
widest cell (a long protocol name no longer pushes its row out of line)."""

from __future__ import annotations

from collections.abc import Sequence

from rich.cells import cell_len

from console.plugin_api import counted

#: the columns: (header, right-aligned); the last one is never padded
COLUMNS = (("protocol", False), ("trials", True), ("design", False), ("title", False))


def protocol_rows() -> list[tuple[str, str, str, str]]:
    """(name, trials, design, title) of each protocol: a fixed one's trial count and its
    phases, an adaptive one's procedure and tracks (its trial count depends on the answers)."""
    from . import adaptive_protocol  # lazy: loads the adaptive procedures
    from . import protocol as protocols

    rows = []
    for name in protocols.available():
        if adaptive_protocol.is_adaptive(name):
            a = adaptive_protocol.load(name)
            design = f"{a.procedure['method']}, {counted(len(a.tracks), 'track')}"
            rows.append((name, "adaptive", design, a.title))
            continue
        p = protocols.load(name)
        phases = ", ".join(f"{ph.name} {ph.n_trials}" for ph in p.phases)
        rows.append((name, str(p.n_trials), phases, p.title))
    return rows


def aligned(rows: Sequence[Sequence[str]], columns=COLUMNS, indent: str = "  ") -> list[str]:
    """The header and ``rows`` as lines: each column as wide as its widest cell (header
    included, in terminal cells), two spaces apart, right-aligned where ``columns`` says."""
    table = [[h for h, _right in columns], *([str(c) for c in r] for r in rows)]
    widths = [max(cell_len(r[i]) for r in table) for i in range(len(columns))]
    lines = []
    for r in table:
        cells = []
        for i, (cell, (_h, right)) in enumerate(zip(r, columns, strict=True)):
            pad = " " * (widths[i] - cell_len(cell))
            last = i == len(columns) - 1
            cells.append(pad + cell if right else cell if last else cell + pad)
        lines.append(indent + "  ".join(cells))
    return lines


def print_protocols() -> int:
    """``haptable study list``."""
    for line in aligned(protocol_rows()):
        print(line)
    return 0
