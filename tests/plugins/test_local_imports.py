"""No unexplained function-local import of a project module under console/ or plugins/.

An import inside a function hides an edge of the import graph (issue 26): it stays only
where it keeps a heavy or hardware library lazy, or keeps a module that every ``haptable``
start loads from loading more, and then says so with a comment starting ``# lazy:`` on its
line or the line before; one comment above a run of consecutive imports covers the run.
Every file under console/ and plugins/ is held to it, whoever owns it."""

from __future__ import annotations

import ast
from pathlib import Path

from ..console.test_import_graph import ROOT, imports, module_files, targets

MARK = "# lazy:"


def runs(tree: ast.AST) -> dict[int, tuple[int, int]]:
    """The line of each import inside a block -> the first and last line of the run of
    consecutive import statements it belongs to."""
    out: dict[int, tuple[int, int]] = {}
    for node in ast.walk(tree):
        for field in ("body", "orelse", "finalbody"):
            body = getattr(node, field, None)
            if not isinstance(body, list):
                continue
            run: list[ast.stmt] = []
            for stmt in [*body, None]:
                if isinstance(stmt, (ast.Import, ast.ImportFrom)):
                    run.append(stmt)
                    continue
                for member in run:
                    out[member.lineno] = (run[0].lineno, run[-1].end_lineno or run[-1].lineno)
                run = []
    return out


def unexplained(root: Path = ROOT) -> list[str]:
    """``file:line module`` of each function-local import of a project module under
    console/ or plugins/ with no ``# lazy:`` comment on its line, the line before, or (for a run of
    consecutive imports) the line before the run or a line of it."""
    mods = module_files(root)
    bad = []
    for name, path in mods.items():
        if name.partition(".")[0] not in ("console", "plugins"):
            continue
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        text = path.read_text(encoding="utf-8")
        lines = text.splitlines()
        tree = ast.parse(text)
        groups = runs(tree)
        for node, local in imports(tree):
            found = targets(node, package, mods) - {name}
            if not (local and found):
                continue
            n = node.lineno
            first, last = groups.get(n, (n, node.end_lineno or n))
            first = min(first, n)
            near = lines[max(first - 2, 0) : max(last, node.end_lineno or n)]
            if not any(MARK in line for line in near):
                rel = path.relative_to(root)
                bad.append((rel.as_posix(), n, f"{rel}:{n} imports {', '.join(sorted(found))}"))
    return [line for *_, line in sorted(bad)]


def test_every_local_import_of_a_project_module_says_why():
    bad = unexplained()
    assert not bad, (
        "function-local imports of project modules: move each to the top of its module "
        "(tests/console/test_import_graph.py keeps it free of cycles), or keep it local and "
        f"say why with '{MARK} ...' on its line or the line before (or above its run of "
        "imports):\n" + "\n".join(bad)
    )


def test_the_check_sees_local_imports_and_their_comment(tmp_path):
    """A local project import is reported; one with ``# lazy:`` above or at its end (or
    above its run of imports), a top-level one and a local third-party one are not."""
    (tmp_path / "console").mkdir()
    (tmp_path / "console" / "__init__.py").write_text("")
    pkg = tmp_path / "plugins" / "demo"
    pkg.mkdir(parents=True)
    (tmp_path / "plugins" / "__init__.py").write_text("")
    (pkg / "__init__.py").write_text("")
    (pkg / "cam.py").write_text("X = 1\n")
    (pkg / "run.py").write_text(
        "from .cam import X\n"
        "def f():\n    from . import cam\n"
        "def g():\n    # lazy: keeps the camera out of startup\n    from .cam import X\n"
        "def h():\n    import plugins.demo.cam  # lazy: same\n    import numpy\n"
        "def k():\n    # lazy: a run\n    import numpy\n    from .cam import X\n    return X\n"
        "def m():\n    import numpy\n\n    from .cam import X\n    # lazy: not above\n"
    )
    assert unexplained(tmp_path) == [
        "plugins/demo/run.py:3 imports plugins.demo.cam",
        "plugins/demo/run.py:18 imports plugins.demo.cam",
    ]
