"""Text in square brackets shows as written on every screen (``console/tui/text.py``).

An AST scan of the console's screens and the plugins' panels: tables are
``LiteralTable`` (a str cell is never markup), and an f-string with markup escapes what
it interpolates (``escape(...)``, or a number with a format spec). Then, on the screens,
the brackets of a plugin's description, a device's error, a session failure and a log
record are all there."""

from __future__ import annotations

import ast
import asyncio
import re
from pathlib import Path

import console
import plugins
from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for

CONSOLE = Path(console.__file__).resolve().parent
PLUGINS = Path(plugins.__file__).resolve().parent
#: a markup tag in a template: [b], [/b], [/], [red], [b reverse], [dim] ...
TAG = re.compile(r"\[/?[a-z]*( [a-z]+)*\]")
NUMERIC_SPEC = re.compile(r".*[bcdeEfFgGnoxX%]$")


def screen_files() -> list[tuple[Path, str]]:
    """The files that put text on the screen: console/tui and each plugin's panel (and
    the demos' status lines, Textual markup by contract)."""
    files = [
        (p, f"console/{p.relative_to(CONSOLE).as_posix()}") for p in CONSOLE.glob("tui/**/*.py")
    ]
    for p in [*PLUGINS.glob("*/panel.py"), PLUGINS / "demos" / "status.py"]:
        files.append((p, f"plugins/{p.relative_to(PLUGINS).as_posix()}"))
    return sorted(files, key=lambda f: f[1])


def _is_escaped(value: ast.FormattedValue) -> bool:
    v = value.value
    if isinstance(v, ast.Call):
        fn = v.func
        name = (
            fn.id if isinstance(fn, ast.Name) else fn.attr if isinstance(fn, ast.Attribute) else ""
        )
        if name == "escape":
            return True
    spec = value.format_spec
    if isinstance(spec, ast.JoinedStr) and spec.values:
        last = spec.values[-1]
        if isinstance(last, ast.Constant) and NUMERIC_SPEC.match(str(last.value)):
            return True
    return False


def violations(source: str, rel: str) -> list[str]:
    out = []
    tree = ast.parse(source)
    specs = {id(n.format_spec) for n in ast.walk(tree) if isinstance(n, ast.FormattedValue)}
    for node in ast.walk(tree):
        where = f"{rel}:{getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.Call):
            fn = node.func
            name = (
                fn.id
                if isinstance(fn, ast.Name)
                else fn.attr
                if isinstance(fn, ast.Attribute)
                else ""
            )
            if name == "DataTable" and rel != "console/tui/text.py":
                out.append(f"{where}: DataTable(...): use console.tui.text.LiteralTable")
        elif isinstance(node, ast.JoinedStr) and id(node) not in specs:
            template = "".join(
                str(v.value) if isinstance(v, ast.Constant) else "{}" for v in node.values
            )
            if not TAG.search(template):
                continue
            for v in node.values:
                if isinstance(v, ast.FormattedValue) and not _is_escaped(v):
                    out.append(f"{where}: {ast.unparse(v.value)!r} in markup {template!r}")
    return out


def test_screens_show_dynamic_text_literally():
    found = []
    for path, rel in screen_files():
        found += violations(path.read_text(), rel)
    assert not found, (
        "values shown through markup must be escaped (console/tui/text.py):\n" + "\n".join(found)
    )


def test_the_scan_catches_each_form():
    bad = (
        "t = DataTable(id='x')\n"
        "a = f'[red]{msg}[/]'\n"
        "b = f'[b]{name}[/b]: {x:.1f} V {escape(why)}'\n"
        "c = f'plain {msg}'\n"  # no markup: the widget decides (markup=False)
        "d = f'{n:>4} [dim]{n:d}[/]'\n"
        "e = f'[audio] device = {name!r}'\n"
    )
    got = violations(bad, "console/tui/bad.py")
    assert [g.split(":")[1] for g in got] == ["1", "2", "3", "5", "6"], got
    assert "'msg'" in got[1] and "'name'" in got[2] and "'n'" in got[3]


def screen_text(app) -> str:
    """What the terminal shows now, as lines of text."""
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def test_brackets_show_on_the_screens(plugins, monkeypatch):
    import logging

    from textual.widgets._toast import Toast

    from console.core.types import DeviceStatus
    from console.runtime import doctor
    from console.tui.logs import NotifyHandler
    from console.tui.safety_bar import SafetyBar

    real = doctor.diagnose

    def diagnose(profile, pm):
        why = "[audio] device = 'x': no stereo output matches"
        return [*real(profile, pm), DeviceStatus("audio", "cardx", "missing", why, "fix [b]")]

    # the Devices screen shows doctor's own checks (``doctor.checks`` looks it up here)
    monkeypatch.setattr(doctor, "diagnose", diagnose)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(220, 52), notifications=True) as pilot:
            handler = NotifyHandler(app)
            logging.getLogger().addHandler(handler)
            try:
                await wait_for(pilot, lambda: "cardx" in screen_text(app), 60, "doctor rows")
                shown = screen_text(app)
                assert "gestures ([tuio] enabled)" in shown  # a plugin's description
                assert "[audio] device = 'x'" in shown and "fix [b]" in shown

                def toasts() -> str:  # the newest only (``console.tui.toasts``)
                    return " ".join(str(t.render()) for t in app.screen.query(Toast))

                app.session.fail("outputs", "[audio] device = 'y': matches several outputs")
                await wait_for(pilot, lambda: "[audio] device = 'y'" in toasts(), 5, "toast")
                logging.getLogger("haptable.test").warning("[relays] serial = 'Z' not online")
                await wait_for(pilot, lambda: "[relays] serial = 'Z'" in toasts(), 5, "toast")
                bar = app.query_one(SafetyBar)
                bar.show(None, "[audio] device = '': there is no default stereo output")
                assert "not open: [audio] device = ''" in str(bar.render())
            finally:
                logging.getLogger().removeHandler(handler)

    asyncio.run(scenario())


# ---------------------------------------------------------------------- the help screens
#: a word in square brackets the help must show as written: ``[console]``, ``[limits]``
BRACKETED = re.compile(r"\[[^\[\]\n]+\]")


def pane_help_texts() -> dict[str, str]:
    """Every screen's help (``HELP_TEXT``) in console/tui and the plugins' panels, by
    the class that carries it; the AST finds the classes, so a new pane is not missed."""
    import importlib

    found = {}
    for path, rel in screen_files():
        tree = ast.parse(path.read_text())
        classes = [
            n.name
            for n in tree.body
            if isinstance(n, ast.ClassDef)
            and any(
                isinstance(s, ast.Assign)
                and any(getattr(t, "id", "") == "HELP_TEXT" for t in s.targets)
                for s in n.body
            )
        ]
        if not classes:
            continue
        module = importlib.import_module(rel.removesuffix(".py").replace("/", "."))
        for name in classes:
            found[f"{rel}:{name}"] = getattr(module, name).HELP_TEXT
    return found


def test_every_help_shows_its_brackets():
    from console.tui.help import help_text

    texts = pane_help_texts()
    # the core's screens and the plugins' panels are all there
    assert {"CameraPane", "LatencyPane", "SignalsPane", "ElectrostaticPane"} <= {
        k.split(":")[1] for k in texts
    }
    missing = []
    for where, text in texts.items():
        shown = " ".join(help_text(text).plain.split())
        for word in BRACKETED.findall(text):
            if " ".join(word.split()) not in shown:
                missing.append(f"{where}: {word}")
    assert not missing, "help text lost its brackets:\n" + "\n".join(missing)


def test_help_screens_show_profile_keys(plugins):
    """Camera's help names ``[console] image``, Electrostatic's ``[limits]``: on the
    help screen as written, at 80 and 120 columns."""

    async def scenario(size, tab, want):
        app = HapTableApp(Context("sim", plugins), fast=True, initial=tab)
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane(tab) is not None, 10, "pane")
            await pilot.pause(0.3)
            await pilot.press("question_mark")
            await wait_for(pilot, lambda: app.screen.query("#help-text"), 5, "help")
            await pilot.pause(0.1)
            w = app.screen.query_one("#help-text")
            from textual.geometry import Region

            strips = w.render_lines(Region(0, 0, w.size.width, w.size.height))
            shown = " ".join(" ".join(s.text for s in strips).split())
            assert want in shown, (size, tab, shown)

    for size in ((80, 24), (120, 40)):
        asyncio.run(scenario(size, "camera", "[console] image"))
        asyncio.run(scenario(size, "electrostatic", "[limits] screen_max_vpp"))
