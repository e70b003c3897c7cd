"""``haptable study list`` (issue 27): its columns line up whatever the names' lengths,
each as wide as its widest cell; counts say "1 track", "16 tracks"."""

from __future__ import annotations

import re

from plugins.studies.list_table import aligned, counted


def test_the_listed_columns_line_up(double_plugins, capsys):
    from console.cli.main import main

    assert main(["study", "list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["protocol", "trials", "design", "title"]
    rows = {ln.split()[0]: ln for ln in lines[1:]}
    assert {"exp1", "knob", "threshold_electrovibration"} <= set(rows)
    name_col, design_col, title_col = (lines[0].index(h) for h in ("protocol", "design", "title"))
    trials_end = lines[0].index("trials") + len("trials")
    for name, ln in rows.items():
        assert ln.index(name) == name_col, ln  # the names start together
        cells = [c for c in ln.strip().split("  ") if c.strip()]
        trials, design, title = (c.strip() for c in cells[1:4])
        assert ln.index(trials, len(name) + name_col) + len(trials) == trials_end, ln
        assert ln.index(design, trials_end) == design_col, ln
        assert ln.rindex(title) == title_col, ln
    # the widest name sets the first column: two spaces after it
    widest = max(rows, key=len)
    assert re.match(rf"^  {widest}  \S", rows[widest]), rows[widest]
    assert "track(s)" not in "\n".join(lines)


def test_cells_of_any_width_and_counts():
    lines = aligned([("a", "5", "x", "t1"), ("a_long_name", "12345", "yy", "t2")])
    assert lines == [
        "  protocol     trials  design  title",
        "  a                 5  x       t1",
        "  a_long_name   12345  yy      t2",
    ]
    assert counted(1, "track") == "1 track" and counted(16, "track") == "16 tracks"
    assert counted(0, "contact") == "0 contacts"
