"""``haptable study analyze DIR... [--json] [--report out.html] [--exclude P03]``.

DIR is a study's ``--out`` folder (every participant in it) or a participant's folder;
several may be given (one experiment). Prints the accuracy tables and the ANOVA (or, with
``--json``, everything ``analysis.analyze`` returns); ``--report`` writes the HTML page
with the figures (``report.py``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any


def add_parser(sub: Any) -> None:
    a = sub.add_parser(
        "analyze",
        aliases=["analyse"],  # the console's Studies screen says "Analyse"
        help="accuracy, RM-ANOVA, figures of finished (or partial) runs (also: analyse)",
    )
    a.add_argument("dirs", nargs="+", type=Path, help="--out folders or participant folders")
    a.add_argument("--json", action="store_true", help="print the analysis as JSON")
    a.add_argument("--report", type=Path, default=None, help="write an HTML report here")
    a.add_argument(
        "--exclude", action="append", default=[], metavar="ID", help="leave a participant out"
    )


def _lines(res: dict[str, Any]) -> list[str]:
    # lazy: this module loads at every haptable start; summary only when used
    from .summary import undefined_notes

    out = [f"{res['experiment']}: {len(res['participants'])} participant(s)"]
    out += [f"  note: {n}" for n in res.get("notes", [])]
    if "accuracy" in res:
        acc = res["accuracy"]
        if acc["overall_pct"] is None:
            out.append(f"accuracy (main phase): {acc['main_phase']}")
        else:
            out.append(f"accuracy (main phase): {acc['overall_pct']:.1f} %")
        for ph, pct in acc.get("practice", {}).items():
            out.append(f"  {ph} phase (apart from the accuracy): {pct:.1f} %")
        for key in [k for k in acc if k.startswith("by_") and acc[k]]:
            name = key[3:]
            out.append(f"  per {name}:")
            for r in acc[key]:
                sd = "" if r["sd_pct"] is None else f" (SD {r['sd_pct']:.1f})"
                out.append(f"    {str(r[name]):<15} {r['accuracy_pct']:5.1f} %{sd}")
        aov = res["anova"]
        if "skipped" in aov:
            out.append(aov["skipped"])
        else:
            out.append(
                f"{' x '.join(aov['factors'])} RM-ANOVA ({aov['participants']} participants):"
            )
            out.append(
                f"  {'source':<22} {'df':>9} {'F':>8} {'p':>9} {'np2':>6} {'Mauchly p':>9} "
                f"{'eps':>5} {'p (GG)':>9}"
            )
            for r in aov["anova"]:
                out.append(
                    f"  {r['source']:<22} {r['df1']:>3}, {r['df2']:<4} {_f(r['f'], '8.2f')} "
                    f"{_f(r['p'], '9.2g')} {_f(r['np2'], '6.3f')} "
                    f"{_f(r.get('mauchly_p'), '9.3f')} {_f(r.get('eps_gg'), '5.2f')} "
                    f"{_f(r.get('p_gg'), '9.2g')}  ({r['sphericity']})"
                )
            out += [f"  note: {n}" for n in undefined_notes(aov)]
    if "knob" in res:
        for m, r in res["knob"]["measures"].items():
            a = r.get("anova", r)
            if "skipped" in a:
                out.append(a["skipped"])
                continue
            out.append(f"{m}: three-way RM-ANOVA ({a['participants']} participants)")
            for row in a["rows"]:
                out.append(
                    f"  {row['source']:<36} F({row['df1']}, {row['df2']}) = {_f(row['f'], '.2f')}, "
                    f"p = {_f(row['p_reported'], '.2g')} ({row['sphericity']}), "
                    f"np2 = {_f(row['np2'], '.3f')}"
                )
            out += [f"  note: {row['note']}" for row in a["rows"] if row.get("note")]
        q = res["knob"]["questionnaire"]
        if "skipped" in q:
            out.append(q["skipped"])
        for c, r in q.items() if "skipped" not in q else ():
            a = r["anova"]
            if isinstance(a, dict):
                out.append(f"questionnaire {c}: {a['skipped']}")
            else:
                row = a[0]
                out.append(
                    f"questionnaire {c}: F({row['DF']}, {a[1]['DF'] if len(a) > 1 else '-'}) = "
                    f"{_f(row.get('F'), '.2f')}, "
                    f"p = {_f(row['p_reported'], '.2g')} ({row['sphericity']}), "
                    f"np2 = {_f(row.get('np2'), '.3f')}"
                )
                if row.get("note"):
                    out.append(f"  note: {row['note']}")
    return out


def _f(v: Any, fmt: str) -> str:
    """A number as ``fmt``; None (undefined: the notes say why) as "-" of the same width."""
    if v is None:
        width = fmt.split(".")[0]
        return f"{'-':>{width}}" if width else "-"
    return format(v, fmt)


def _check_excluded(dirs: list[Path], exclude: tuple[str, ...]) -> None:
    """An ``--exclude`` id no participant in ``dirs`` has: a one-line error naming it and
    the participants there (a typo would otherwise leave everyone in, silently)."""
    if not exclude:
        return
    # lazy: this module loads at every haptable start
    from console.plugin_api import UserError

    from . import records, runs
    from . import threshold_analysis as thresholds

    ids = [f.name for f in thresholds.run_folders(dirs)]
    if thresholds.has_plans(dirs) or not ids:
        for d in runs.participant_dirs(dirs):
            ids.append(str(records.load_plan(d / "plan.json").get("participant") or d.name))
    ids = sorted(set(ids))
    unknown = [x for x in dict.fromkeys(exclude) if x not in ids]
    if unknown:
        where = ", ".join(map(str, dirs))
        raise UserError(
            f"--exclude {', '.join(unknown)}: no such participant in {where}; "
            f"the participants are {', '.join(ids) or 'none'}"
        )


def run(args: argparse.Namespace) -> int:
    # lazy: this module loads at every haptable start; analysis, report only when used
    from . import analysis, report
    from . import threshold_analysis as thresholds  # threshold runs: fits, curves

    _check_excluded(list(args.dirs), tuple(args.exclude))
    extra = None
    if thresholds.run_folders(list(args.dirs)):
        if not thresholds.has_plans(list(args.dirs)):
            return thresholds.run(args)
        extra = thresholds.run(args, embedded=True)  # both kinds here: thresholds first
    study = analysis.load(list(args.dirs), exclude=tuple(args.exclude))
    res = analysis.analyze(study)
    if extra is not None:
        res["thresholds"] = extra
    if args.report is not None:
        path = report.write(res, args.report)
        res["report"] = str(path)
    if args.json:
        print(json.dumps(res, indent=1, default=str))
    else:
        print("\n".join(_lines(res)))
        if args.report is not None:
            print(f"report: {res['report']}")
    return 0
