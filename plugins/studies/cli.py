"""``haptable study run exp1|exp2|knob --participant P01 --out DIR``: run a participant.

A person: the participant's fields from options, or prompted at a terminal; answers typed
(or from a keypad: 8/2/4/6, 1/2 for experiment 1, 0 replays). ``--simulate``: a simulated
participant (the registered ``SimulatedObserver``); ``--participants N`` runs P01..PN
(or from ``--participant``'s number on). A run stopped for any reason (Ctrl-C, kill -9)
resumes with the same command: the next trial of the stored plan, the trial in flight
repeated. ``haptable study list`` lists the protocols.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import re
import signal
import sys
from pathlib import Path
from typing import Any

from console.plugin_api import EStopped, UserError, load_map

from . import analyze_cli
from . import protocol as protocols
from .analyze_cli import add_parser
from .hold import hold_for_run, hold_map_for_run, hold_table_for_run
from .plan import check_seed_row
from .run_estop import estop_reason, says_estopped
from .start import PARTICIPANT_KEYS, prepare, stored_participant
from .store import check_detail, check_id, resume_text
from .store import progress as store_progress

MAX_PARTICIPANTS = 500


def configure(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="study_cmd", metavar="ACTION", required=True)
    r = sub.add_parser("run", help="run a protocol for a participant (resumes a stopped run)")
    r.add_argument("study", help="exp1, exp2, knob, or a protocol .toml file")
    r.add_argument("--participant", default=None, help="participant id, e.g. P01")
    r.add_argument("--out", type=Path, required=True, help="the study's folder")
    r.add_argument("--simulate", action="store_true", help="simulated participant(s)")
    r.add_argument("--participants", type=int, default=None, help="with --simulate: run N")
    r.add_argument("--map", type=Path, default=None, help="vibration map (default: measured)")
    r.add_argument("--seed", default=None, help="the participant's seed (0 .. 2^63 - 1)")
    r.add_argument(
        "--row", default=None, help="Latin-square row, 0-based (default: id's number - 1)"
    )
    r.add_argument("--trials", type=int, default=None, help="run at most this many trials now")
    r.add_argument("--age", type=int, default=None)
    r.add_argument("--sex", default=None, help="female, male, other, undisclosed")
    r.add_argument("--handedness", default=None, help="left, right, ambidextrous")
    r.add_argument("--hand-width-cm", type=float, default=None)
    r.add_argument("--hand-length-cm", type=float, default=None)
    r.add_argument("--consent", action="store_true", help="the informed consent is noted")
    r.add_argument("--json", action="store_true", help="print a JSON summary at the end")
    r.add_argument("--quiet", action="store_true", help="no line per trial")
    r.add_argument(
        "--record",
        action="store_true",
        help="record each trial into DIR/<participant>/recording/ ([recording] study_trials)",
    )
    rp = sub.add_parser("replay", help="re-render a recorded study's stimuli: the same?")
    rp.add_argument("path", help="a trial file, a participant's folder or the study's --out")
    sub.add_parser("list", help="the protocols in studies/ and their trial counts")

    add_parser(sub)


def whole(text: str | None, flag: str) -> int | None:
    """A whole-number option given as text (``None``: not given); one line otherwise."""
    if text is None:
        return None
    if not re.fullmatch(r"[+-]?[0-9]{1,100}", text.strip()):
        raise UserError(f"{flag} {text!r}: give a whole number (digits only)")
    return int(text)


def _ids(args: argparse.Namespace) -> list[str]:
    if args.participant is not None:
        check_id(args.participant)
    if args.participants is None:
        if not args.participant:
            raise UserError("study run: give --participant P01 (or --simulate --participants N)")
        return [args.participant]
    if not args.simulate:
        raise UserError("--participants N runs simulated participants: add --simulate")
    if not 1 <= args.participants <= MAX_PARTICIPANTS:
        raise UserError(f"--participants {args.participants}: give 1..{MAX_PARTICIPANTS}")
    first, prefix, width = 1, "P", 2
    if args.participant:
        m = re.fullmatch(r"(.*?)([0-9]+)", args.participant)
        if not m:
            raise UserError(
                f"--participant {args.participant!r}: with --participants it is the first id "
                "and must end in a number (P01)"
            )
        prefix, first, width = m.group(1), int(m.group(2)), len(m.group(2))
    return [f"{prefix}{first + k:0{width}d}" for k in range(args.participants)]


def _details(args: argparse.Namespace, pid: str) -> dict[str, Any]:
    """The participant's details: the options' (checked at once), the missing ones asked
    at a terminal, each answer checked as typed (the option's rule and words) and asked
    again until it is taken; no consent noted ends the run before its first trial."""
    d = {
        "age": args.age,
        "sex": args.sex,
        "handedness": args.handedness,
        "hand_width_cm": args.hand_width_cm,
        "hand_length_cm": args.hand_length_cm,
        "consent": True if args.consent else None,
    }
    for k, v in d.items():
        if k != "consent" and v is not None:
            d[k] = check_detail(pid, k, v)  # a bad option: said before anything is asked
    missing = [k for k in PARTICIPANT_KEYS if d[k] is None]
    if missing and not sys.stdin.isatty():
        opts = ", ".join("--" + k.replace("_", "-") for k in missing)
        raise UserError(f"participant {pid}: give {opts} (or run at a terminal to be asked)")
    for k in missing:
        d[k] = _ask(pid, k)
    return d


def _ask(pid: str, k: str) -> Any:
    """One detail typed at the terminal, asked again (saying why) until it is taken."""
    while True:
        try:
            if k == "consent":
                ans = input(f"{pid}: informed consent noted? [y/N] ").strip().lower()
                return True if ans in ("y", "yes") else None
            typed = input(f"{pid}: {k.replace('_', ' ')}: ").strip()
        except EOFError:
            raise UserError(
                f"participant {pid}: input ended before {k.replace('_', ' ')} was given; give "
                "it as --" + k.replace("_", "-") + " or answer at a terminal"
            ) from None
        try:
            return check_detail(pid, k, typed)
        except UserError as exc:
            print(f"{exc}; type it again", file=sys.stderr, flush=True)


def _vmap(args: argparse.Namespace, ctx: Any) -> Any:
    if args.map is not None:
        return load_map(args.map.expanduser(), require_all=False)
    # lazy: the runtime part loads on first use, not at every haptable start
    from console.plugin_api.runtime import measured_map

    hold_map_for_run(
        ctx.profile, args.study, args.simulate
    )  # held before it is read: no other replaces it

    def progress(frac: float, text: str) -> None:
        print(f"\rvibration map: {frac:4.0%} {text}"[:100], end="", file=sys.stderr, flush=True)

    vmap = measured_map(ctx.profile, ctx.pm, progress)
    print(file=sys.stderr)
    return vmap


def _line(kind: str, info: dict[str, Any]) -> str | None:
    if kind == "done":
        r = info["record"]
        if not r.get("simulated") and r.get("response") is not None:
            # a participant may read the terminal: no right answer shown (it is in the file)
            return (
                f"  {r['participant']} trial {r['trial'] + 1}: answered ({r['replays']} replay(s))"
            )
        what = " ".join(
            str(r[k]) for k in ("phase", "pair", "region", "direction", "condition") if r.get(k)
        )
        if r.get("completion_time_s") is not None or "overshoots" in r:
            ct = r.get("completion_time_s")
            res = (
                f"{'timeout' if ct is None else f'{ct:.2f} s'}, {r.get('overshoots')} overshoot(s)"
            )
        else:
            res = f"{r['response']} ({'correct' if r['correct'] else 'wrong'}, {r['replays']} replay(s))"
        return f"  {r['participant']} trial {r['trial'] + 1}: {what}: {res}"
    if kind in ("aborted", "refused"):
        return f"  {kind}: {info.get('reason') or info.get('why')}"
    if kind == "questionnaire":
        return f"  questionnaire after {info['condition']} ({info['items']} items)"
    return None


class _Count:
    """Trials done of those this run makes, and the time left at the pace so far (the
    line of each trial ends with it: "[12/40, about 1 min 5 s left]")."""

    def __init__(self, done: int, total: int) -> None:
        # lazy: the pace and its words come with the console's plugin API
        from console.plugin_api.tui import Pace

        self.done, self.total, self.pace = done, total, Pace()  # from the first trial's end

    def one_more(self) -> str:
        from console.plugin_api.tui import left_words  # lazy: as above

        self.done += 1
        left = self.pace.left(self.done, self.total)
        words = left_words(left) if self.done < self.total else ""
        return f"{self.done}/{self.total}" + (f", {words}" if words else "")


def run(args: argparse.Namespace, ctx: Any) -> int:
    if args.study_cmd in ("analyze", "analyse"):  # either spelling (the screen's is analyse)
        return analyze_cli.run(args)
    if args.study_cmd == "replay":
        from .trial_replay import replay_study  # lazy: only when replaying

        same, line = replay_study(args.path, ctx)
        print(line)
        return 0 if same else 1
    # lazy: adaptive protocols (threshold_*, jnd_*) load only for a study command
    from . import adaptive_protocol

    if args.study_cmd == "list":
        from .list_table import print_protocols  # lazy: only when listing

        return print_protocols()
    # lazy: this module loads at every haptable start; responders, runner, stimuli only when used
    from .responders import INPUT_ENDED, ObserverResponder, TerminalResponder, observer
    from .runner import Control, run_plan
    from .stimuli import EffectPlayer, check_places, play_on
    from .trial_recording import TrialRecorder, recorded_files, wants_recording

    if adaptive_protocol.is_adaptive(args.study):
        from .adaptive_cli import run as run_adaptive  # lazy: as above

        ids = _ids(args)
        hold_table_for_run(ctx.profile, args.study, args.simulate)  # from its start: no mixing
        return run_adaptive(args, ctx, ids, whole(args.seed, "--seed"), _details, _vmap)
    if args.trials is not None and args.trials < 1:
        raise UserError(f"--trials {args.trials}: give at least 1")
    proto = protocols.load(args.study)
    seed, row = whole(args.seed, "--seed"), whole(args.row, "--row")
    check_seed_row(proto, seed, row)
    ids = _ids(args)
    hold_table_for_run(ctx.profile, args.study, args.simulate)  # from its start: no mixing
    obs = observer(ctx.pm, ctx.profile) if args.simulate and proto.stimulus != "knob" else None
    if proto.stimulus == "knob" and not args.simulate:
        raise UserError(
            "knob study with a person: run it from the console's Studies screen (F10, the "
            "camera turns the knob), or use --simulate here"
        )
    vmap = _vmap(args, ctx) if proto.stimulus != "knob" else None
    from .sensation import resolver  # lazy: as above

    base = EffectPlayer(ctx.pm, ctx.profile, vmap, lambda plan: False).render_base
    resolve = resolver(proto, ctx.profile, base)  # None without a study.level
    control = Control()
    old = signal.getsignal(signal.SIGINT)

    def on_int(signum: int, frame: Any) -> None:
        control.abort("Ctrl-C")

    summaries = []
    flight: dict[str, Any] = {}  # the participant and trial under way
    with (
        says_estopped(flight, quiet=args.json),
        ctx.outputs(fast=True if args.simulate else None) as outputs,
    ):
        hold_for_run(outputs, args.study, args.simulate)
        signal.signal(signal.SIGINT, on_int)
        try:
            for pid in ids:
                details = None
                if not args.simulate and stored_participant(args.out, pid) is None:
                    details = _details(args, pid)
                prep = prepare(
                    args.study,
                    pid,
                    args.out,
                    details=details,
                    simulate=args.simulate,
                    observer=obs,
                    seed=seed,
                    row=row,
                    resolve=resolve,
                )
                if vmap is not None:
                    check_places(prep.plan, vmap)
                files, outs = prep.files, outputs
                if wants_recording(args, ctx.profile):  # each trial into recording/
                    rec = TrialRecorder(
                        files.root,
                        prep.plan,
                        profile=ctx.profile,
                        vmap=vmap,
                        seed=prep.participant_seed,
                    )
                    files, outs = recorded_files(files, rec), rec.watch(outputs)
                player = EffectPlayer(
                    ctx.pm, ctx.profile, vmap, play_on(outs), knob_seed=prep.participant_seed
                )
                responder = (
                    ObserverResponder(obs, prep.participant_seed)
                    if args.simulate
                    else TerminalResponder(prep.plan["responses"])
                )

                st = store_progress(prep.plan, prep.files.events())
                count = _Count(len(st.done), st.total if args.trials is None else
                               min(st.total, len(st.done) + args.trials))  # fmt: skip

                flight.update(pid=pid, trial=None, done=lambda c=count: f"{c.done}/{c.total}")

                def say(kind: str, info: dict[str, Any], count=count) -> None:
                    if kind == "start":
                        flight["trial"] = info["trial"]["index"] + 1
                    line = _line(kind, info)
                    if kind == "done":
                        line = line and f"{line}  [{count.one_more()}]"
                    if line and not args.quiet and not args.json:
                        print(line, flush=True)

                if not args.json:
                    left = count.total - count.done
                    print(
                        f"{pid}: {proto.name} -> {prep.files.root}: {left} trial(s) to run",
                        flush=True,
                    )
                    again = resume_text(prep.plan, prep.files.events())
                    if again:
                        print(f"{pid}: {again}", flush=True)
                try:
                    res = run_plan(
                        files,
                        prep.plan,
                        prep.participant,
                        player=player,
                        responder=responder,
                        control=control,
                        notify=say,
                        limit=args.trials,
                    )
                except UserError as exc:
                    why = estop_reason(outputs)  # the table's e-stop cut a stimulus
                    if why is None:
                        raise
                    raise EStopped(why) from exc
                summaries.append({"participant": pid, "dir": str(prep.files.root), **res})
                if not args.json:
                    print(
                        f"{pid}: {res['done']}/{res['total']} trials done"
                        + (" (finished)" if res["finished"] else "; the same command resumes"),
                        flush=True,
                    )
                if res["aborted"]:
                    break
        finally:
            signal.signal(signal.SIGINT, old)
    if args.json:
        print(json.dumps({"study": proto.name, "participants": summaries}, indent=1))
    with contextlib.suppress(Exception):
        sys.stdout.flush()
    if control.aborted and control.reason == INPUT_ENDED:  # not Ctrl-C: bad input, 2
        last = summaries[-1] if summaries else {}
        raise UserError(
            f"input ended (stdin closed) at {last.get('participant', '?')}'s trial "
            f"{last.get('done', 0) + 1}: the run stopped there; answer at a terminal, the same "
            "command resumes"
        )
    return 130 if any(s["aborted"] for s in summaries) else 0
