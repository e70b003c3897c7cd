"""The core ``haptable`` commands: plugins, doctor, play, estop, bench, console."""

from __future__ import annotations

import argparse
import contextlib
import inspect
import io
import json
import shutil
import sys
import textwrap
import wave

import numpy as np

from console.config.profile import save_overrides
from console.core.errors import EStopped, SafetyRefusal, UserError
from console.core.options import minutes, seconds
from console.core.suggest import suggestion
from console.runtime.buffer_doctor import describe as describe_buffer
from console.runtime.buffer_doctor import measure as measure_buffer
from console.runtime.doctor import checks
from console.runtime.selftest_last import note_last
from console.safety import Limits, check_plan


# ---------------------------------------------------------------------- plugins
def configure_plugins(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="machine-readable output")


def run_plugins(args, ctx) -> int:
    plugins = ctx.pm
    rows = []
    for kind, regs in sorted(plugins.registrations.items()):
        for name, reg in sorted(regs.items()):
            rows.append(
                {"kind": kind, "name": name, "plugin": reg.plugin, "description": reg.description}
            )
    data = {
        "plugins": plugins.plugin_names(),
        "provides": rows,
        "commands": sorted(plugins.commands),
        "benchmarks": sorted(plugins.benchmarks),
        "profile_sections": sorted(plugins.sections),
    }
    if args.json:
        print(json.dumps(data, indent=2))
        return 0
    print("plugins: " + ", ".join(data["plugins"]))
    width = max((len(r["kind"]) for r in rows), default=4)
    for r in rows:
        print(f"  {r['kind']:<{width}}  {r['name']:<14} [{r['plugin']}] {r['description']}")
    print("commands: " + ", ".join(data["commands"]))
    print("benchmarks: " + (", ".join(data["benchmarks"]) or "none"))
    return 0


# ---------------------------------------------------------------------- doctor
def configure_doctor(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true")
    p.add_argument(
        "--buffer",
        type=seconds(3600.0, lo=1.0),
        metavar="SECONDS",
        help="also measure for SECONDS how late this machine wakes the audio thread and "
        "size the sound card's buffer ([audio] buffer_ms) to it",
    )
    p.add_argument(
        "--save", action="store_true", help="with --buffer: store the buffer in the profile"
    )


def run_doctor(args, ctx) -> int:
    statuses = checks(ctx.profile, ctx.pm)
    bad = [s for s in statuses if s.state in ("missing", "error")]
    code, part = _selftest_part(args, ctx)  # the self-test's quick part, when a plugin has one
    buffer = _buffer_part(args, ctx)
    if args.json:
        print(
            json.dumps(
                {
                    "profile": str(ctx.profile.path),
                    "devices": [s.__dict__ for s in statuses],
                    "selftest": json.loads(part) if part else None,
                    "buffer": buffer,
                    "ok": not bad and not code,
                },
                indent=2,
            )
        )
    else:
        print(f"profile: {ctx.profile.path}")
        for s in statuses:
            line = f"  {s.kind:<10} {s.name:<12} {s.state:<9} {s.why}"
            print(line.rstrip())
            if s.fix:
                print(f"  {'':<10} {'':<12} fix: {s.fix}")
        print(part, end="")
        if buffer is not None:
            print("\n".join(describe_buffer(buffer)))
    return 1 if bad or code else 0


def _buffer_part(args, ctx) -> dict | None:
    """``--buffer SECONDS``: the machine's wake lateness and the buffer it needs (stored
    with ``--save``); None without it."""
    if args.buffer is None:
        if args.save:
            raise UserError("doctor --save stores the measured buffer: add --buffer SECONDS")
        return None
    got = measure_buffer(ctx.profile, args.buffer)
    if args.save and "error" not in got:
        if got["too_long"]:
            raise UserError(
                f"doctor --buffer: {got['recommended_buffer_ms']:g} ms of buffer would be "
                "needed; not saved: give the audio thread real-time priority or use a "
                "quieter machine"
            )
        where = save_overrides(
            ctx.profile, {"audio.buffer_ms": got["recommended_buffer_ms"]}, ctx.pm
        )
        got["saved_to"] = str(where)
    return got


def _selftest_part(args, ctx) -> tuple[int, str]:
    """``haptable selftest --doctor``'s exit status and output (0, "" without one); its
    outcome kept for the console's Devices row (``console.runtime.selftest_last``)."""
    cmd = ctx.pm.commands.get("selftest")
    if cmd is None:
        return 0, ""
    p = argparse.ArgumentParser()
    cmd.configure(p)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = int(cmd.run(p.parse_args(["--doctor", "--json"]), ctx) or 0)
    said = buf.getvalue()
    try:
        part = json.loads(said)
        state, lines = str(part["state"]), [str(x) for x in part["lines"]]
    except (ValueError, KeyError, TypeError):
        return code, said  # not the report we know: as it printed it
    note_last(ctx.profile.name, "quick", state, "; ".join(lines), "haptable doctor")
    if args.json:
        return code, said
    return code, "".join(f"  {'selftest':<10} {'quick':<12} {state:<9} {ln}\n" for ln in lines)


# ---------------------------------------------------------------------- play
def configure_play(p: argparse.ArgumentParser) -> None:
    p.add_argument("name", nargs="?", help="test stimulus (see --list)")
    p.add_argument("--list", action="store_true", help="list the test stimuli")
    p.add_argument(
        "--out",
        help="also write the plan as a WAV, a channel per [audio] channels name "
        "(volts / full scale)",
    )
    p.add_argument("--dry-run", action="store_true", help="check the plan, do not play it")
    p.add_argument("--fast", action="store_true", help="twin: fast-forward instead of real time")


#: a play this long or shorter holds no table: the console's keys wait for its end
#: (Relays says which play they wait for); a longer one holds it (``Context.outputs``)
SHORT_PLAY_S = 5.0


def write_plan_wav(plan, path: str, limits) -> None:
    """Write a checked plan as the sound card would play it (gaps not included), 16-bit,
    a channel per ``[audio] channels`` name (the bus: stereo, piezo left)."""
    layout = limits.layout
    cols = np.concatenate([np.stack(layout.columns(s), 1) for s in plan.segments])
    full = [limits.screen_card_v if k == "screen" else limits.piezo_card_v for k in layout.kinds()]
    pcm = (np.clip(cols / np.array(full), -1, 1) * 32767).astype("<i2")
    with open(path, "wb") as f, wave.open(f, "wb") as w:  # the path fails here, cleanly
        w.setnchannels(layout.n)
        w.setsampwidth(2)
        w.setframerate(plan.sample_rate_hz)
        w.writeframes(pcm.tobytes())


def play_and_report(
    ctx, plan, *, fast: bool = False, out: str | None = None, dry_run: bool = False
) -> int:
    """Check a plan through the gate, optionally write it, play it, and say what happened."""
    limits = Limits.from_profile(ctx.profile)
    check_plan(plan, limits)
    if out:
        write_plan_wav(plan, out, limits)
        print(f"wrote {out}")
    if dry_run:
        print(f"{plan.name}: {plan.duration_s:.2f} s, {len(plan.segments)} segment(s): accepted")
        return 0
    # a long plan holds the table as a demo does (the console refuses its plays at once,
    # naming it); a short one is over before a key waiting for it is missed
    with ctx.outputs(fast=fast, hold=plan.duration_s > SHORT_PLAY_S) as outputs:
        start = int(outputs.status()["gate"]["clock"])  # the table's earlier switches: not ours
        play_or_estopped(outputs, plan)
        print(f"played {plan.name}: {plan.duration_s:.2f} s in {len(plan.segments)} segment(s)")
        log = outputs.relay_log()
        for r in (x for x in log or () if x.clock >= start):
            state = "closed" if r.closed else "opened"
            print(
                f"  relay {r.channel} {state} at +{1e3 * (r.clock - start) / plan.sample_rate_hz:.1f}"
                f" ms (outputs {' / '.join(f'{v:.1f} V' for v in r.level_v)})"
            )
    return 0


def play_or_estopped(outputs, plan) -> None:
    """Play ``plan`` and wait for it; a play the e-stop ended leaves as ``EStopped``
    (exit 4) even when its end reached us before the e-stop's event (a loaded machine:
    the kernel sends the two from two threads), asking the kernel whether it is
    e-stopped (its flag is set before the play ends)."""
    try:
        outputs.play(plan)
    except SafetyRefusal:
        gate = outputs.status()["gate"]
        if gate["estopped"]:
            raise EStopped(outputs.estopped_by or gate["estop_reason"]) from None
        raise


def run_play(args, ctx) -> int:
    # lazy: keeps `haptable` startup light
    from console.signals.stimuli import STIMULI, make_stimulus

    if args.list or not args.name:
        for name, (desc, _) in STIMULI.items():
            print(f"  {name:<14} {desc}")
        return 0 if args.list else 2
    plan = make_stimulus(
        args.name,
        int(ctx.profile.get("audio.sample_rate_hz")),
        float(ctx.profile.get("limits.max_plan_s")),
    )
    return play_and_report(ctx, plan, fast=args.fast, out=args.out, dry_run=args.dry_run)


# ---------------------------------------------------------------------- estop, reset
def configure_estop(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true")
    p.add_argument(
        "--timeout",
        type=seconds(60.0, lo=0.01),
        default=2.0,
        help="seconds each table's outputs process has to confirm its silence (default 2)",
    )


def run_estop(args, ctx) -> int:
    """`haptable estop` (``console.kernel.shell``; the ``haptable`` entry point runs it
    before anything heavy is imported: this path serves ``console.cli.main.main``)."""
    # lazy: keeps `haptable` startup light
    from console.kernel.shell import main as shell_main

    argv = ["estop", "--timeout", str(args.timeout)] + (["--json"] if args.json else [])
    return shell_main((["--profile", ctx.profile_arg] if ctx.profile_arg else []) + argv)


def configure_reset(p: argparse.ArgumentParser) -> None:
    pass


def run_reset(args, ctx) -> int:
    """`haptable reset`: an operator's, at a terminal (``console.kernel.shell``)."""
    # lazy: keeps `haptable` startup light
    from console.kernel.shell import main as shell_main

    return shell_main((["--profile", ctx.profile_arg] if ctx.profile_arg else []) + ["reset"])


# ---------------------------------------------------------------------- bench
def configure_bench(p: argparse.ArgumentParser) -> None:
    p.add_argument("name", nargs="?", help="benchmark to run (`list` or none: list them)")
    p.add_argument("--json", action="store_true")
    p.add_argument("--quick", action="store_true", help="fewer repetitions")
    p.add_argument("--report", help="write a Markdown report (and plots) into this folder")
    p.add_argument("--minutes", type=minutes(), help="duration, for benchmarks that run for a time")


def run_bench(args, ctx) -> int:
    benches = ctx.pm.benchmarks
    if not args.name or args.name == "list":
        _list_benchmarks(benches, args.json)
        return 0
    if args.name not in benches:
        hint = suggestion(args.name, [*sorted(benches), "list"], "did you mean {!r}? ")
        raise UserError(
            f"no benchmark {args.name!r}; {hint}available: {', '.join(sorted(benches))}"
        )
    run = benches[args.name].run
    kwargs = {"report_dir": args.report, "minutes": args.minutes}
    accepted = inspect.signature(run).parameters
    takes_any = any(p.kind is p.VAR_KEYWORD for p in accepted.values())
    for key, value in list(kwargs.items()):
        if value is None:
            del kwargs[key]
        elif key not in accepted and not takes_any:
            raise UserError(f"benchmark {args.name!r} does not take --{key.replace('_dir', '')}")
    result = run(ctx, args.quick, **kwargs)
    if args.json:
        print(json.dumps(result, indent=2, default=float))
    else:
        _print_nested(result)
    return 0


def _list_benchmarks(benches: dict, as_json: bool) -> None:
    """Each benchmark: its name and what it measures, the whole description wrapped to
    the terminal's width under its own column (``--json``: as data)."""
    if as_json:
        rows = [{"name": n, "help": b.help} for n, b in sorted(benches.items())]
        print(json.dumps(rows, indent=2))
        return
    width = shutil.get_terminal_size((100, 24)).columns
    pad = max((len(n) for n in benches), default=0)
    indent = " " * (pad + 2)
    text_width = max(width - len(indent), 30)  # a narrow terminal: words, not letters
    for name, b in sorted(benches.items()):
        words = " ".join(str(b.help).split())
        lines = textwrap.wrap(words, text_width, break_on_hyphens=False) or [""]
        print(f"{name:<{pad}}  {lines[0]}".rstrip())
        for more in lines[1:]:
            print(indent + more)


def _print_nested(d, indent: int = 0) -> None:
    for k, v in d.items():
        if isinstance(v, dict):
            print(" " * indent + f"{k}:")
            _print_nested(v, indent + 2)
        else:
            print(" " * indent + f"{k}: {v}")


# ---------------------------------------------------------------------- console
def configure_console(p: argparse.ArgumentParser) -> None:
    # lazy: pluggy loads only when the console is configured
    from console.config.core_sections import IMAGE_MODES

    p.add_argument(
        "--image",
        choices=IMAGE_MODES,
        default=None,
        help="the Camera screen's IR view: auto (ask the terminal for Sixel or the Kitty "
        "graphics protocol), halfblock (characters, never ask) or a protocol; default: "
        "the profile's [console] image, else auto",
    )


def run_console(args, ctx) -> int:
    # lazy: Textual loads only when the console opens
    from console.tui.app import run_app

    return run_app(ctx, image=getattr(args, "image", None))


def register_core(register) -> None:
    register("plugins", configure_plugins, run_plugins, help="list plugins and what they provide")
    register("doctor", configure_doctor, run_doctor, help="check each device of the profile")
    register("play", configure_play, run_play, help="play a named test stimulus through the gate")
    register(
        "estop",
        configure_estop,
        run_estop,
        help="silence the outputs, open every relay and latch the e-stop (every table)",
    )
    register(
        "reset",
        configure_reset,
        run_reset,
        help="an operator's, at a terminal: clear a latched e-stop, saying who and when",
    )
    register("bench", configure_bench, run_bench, help="run a benchmark (timing + accuracy)")
    register("console", configure_console, run_console, help="the operator console (default)")


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use the `haptable` command")
