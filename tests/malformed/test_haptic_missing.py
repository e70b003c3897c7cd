"""``haptable signals import`` of a file that is not there: the line says it does not
exist and to check the path, never to correct a JSON it never read."""

from __future__ import annotations

import pytest

from console.cli.main import main


@pytest.mark.parametrize("name", ["nope.ahap", "nope.haptic"])
def test_missing_file_says_so_and_to_check_the_path(name, tmp_path, capsys):
    f = tmp_path / name
    capsys.readouterr()
    assert main(["signals", "import", str(f)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    line = lines[0]
    assert str(f) in line and "no such file" in line and "check the path" in line
    assert "JSON" not in line and "design tool" not in line


def test_a_folder_is_not_told_to_fix_its_json(tmp_path, capsys):
    d = tmp_path / "dir.ahap"
    d.mkdir()
    capsys.readouterr()
    assert main(["signals", "import", str(d)]) == 2
    line = capsys.readouterr().err.strip()
    assert "a folder" in line and "JSON" not in line


def test_a_folder_without_a_suffix_is_said_to_be_a_folder(tmp_path, capsys):
    """A new operator's try: ``haptable signals import /tmp`` said ``cannot tell the
    format from the suffix ''``; it is a folder: the line says so and what to give."""
    capsys.readouterr()
    assert main(["signals", "import", str(tmp_path)]) == 2
    line = capsys.readouterr().err.strip()
    assert "is a folder" in line and "suffix ''" not in line, line
    assert ".ahap" in line and ".haptic" in line, line
