"""No module in console/ or plugins/ over ``MAX_LINES`` lines: past it a module does
several jobs; split it by job into modules whose names say what they hold (issue 26)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MAX_LINES = 700


def line_counts(root: Path = ROOT) -> dict[str, int]:
    """Lines of every ``.py`` file under console/ and plugins/, by path from the root."""
    return {
        p.relative_to(root).as_posix(): len(p.read_text(encoding="utf-8").splitlines())
        for top in ("console", "plugins")
        for p in sorted((root / top).rglob("*.py"))
        if "__pycache__" not in p.parts
    }


def over_limit(counts: dict[str, int]) -> dict[str, int]:
    return {path: n for path, n in counts.items() if n > MAX_LINES}


def test_no_module_over_the_limit():
    new = over_limit(line_counts())
    assert not new, (
        f"over {MAX_LINES} lines: "
        + ", ".join(f"{p} ({n})" for p, n in sorted(new.items()))
        + "; split each by job into modules whose names say what they hold"
    )


def test_the_count_sees_every_module(tmp_path):
    """A module nested in a package counts; caches and other folders do not."""
    (tmp_path / "plugins" / "x" / "deep").mkdir(parents=True)
    (tmp_path / "plugins" / "x" / "deep" / "big.py").write_text("a = 1\n" * (MAX_LINES + 1))
    (tmp_path / "plugins" / "x" / "__pycache__").mkdir()
    (tmp_path / "plugins" / "x" / "__pycache__" / "big.py").write_text("a = 1\n" * 800)
    (tmp_path / "console").mkdir()
    (tmp_path / "console" / "ok.py").write_text("a = 1\n" * MAX_LINES)
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "big.py").write_text("a = 1\n" * 800)
    assert over_limit(line_counts(tmp_path)) == {"plugins/x/deep/big.py": MAX_LINES + 1}
