"""``haptable study analyze DIR`` for threshold runs: a psychometric fit per participant
and frequency, and the threshold-vs-frequency figure.

A threshold run is a participant folder with ``adaptive.json`` (``measure`` =
``detection``) and ``adaptive_trials.jsonl`` (the adaptive procedures' files,
``adaptive_run.py``). Each track's ``done`` trials (the last per trial number; a line a
crash cut short skipped) are fitted by ``psychometric.fit_trials`` (Weibull in dB, the
task's guess rate, lapse 0..0.1; 95 % intervals by a seeded parametric bootstrap) and
set beside the procedure's own estimate (``thresholds.json``). The figure draws every
participant's fitted thresholds (with their intervals) over log frequency, and for
vibrotactile curves in dB re 1 um the population curve (``POPULATION``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError, write_text_atomic

from . import textfiles
from . import thresholds as th
from .psychometric import fit_trials

RUN = "adaptive.json"
LOG = "adaptive_trials.jsonl"
N_BOOT = 100
#: the population's fingertip detection threshold (dB re 1 um peak): FACTS.md "Human
#: vibrotactile sensitivity", palm model (Verrillo 1963, 1966; [recalled]) + 6 dB
#: fingertip, the values of the profile's [perception] defaults
POPULATION = {
    "freq_hz": [10.0, 40.0, 63.0, 100.0, 160.0, 250.0, 400.0, 500.0, 700.0],
    "threshold_db": [18.0, 18.0, 10.0, 2.0, -6.0, -14.0, -9.0, -6.0, 0.0],
    "label": "population, fingertip (Verrillo 1963/1966 palm + 6 dB; FACTS.md, recalled)",
}
FIX = "restore the file, or rerun the participant in a new --out"


def _folders(dirs: list[Path], name: str) -> list[Path]:
    out: list[Path] = []
    for d in map(Path, dirs):
        if (d / name).is_file():
            out.append(d)
        elif d.is_dir():
            out += sorted(p for p in d.iterdir() if (p / name).is_file())
    return out


def run_folders(dirs: list[Path]) -> list[Path]:
    """The threshold-run participant folders in ``dirs`` (a folder or its subfolders)."""
    return _folders(dirs, RUN)


def has_plans(dirs: list[Path]) -> bool:
    """Whether ``dirs`` hold fixed-plan runs (``plan.json``) too."""
    return bool(_folders(dirs, "plan.json"))


def _done_trials(folder: Path) -> list[dict[str, Any]]:
    path = folder / LOG
    if not path.exists():
        return []
    last: dict[int, dict[str, Any]] = {}
    for n, e in textfiles.jsonl_lines(
        path, what="adaptive trials file", fix=FIX, file_fix="restore the file"
    ):
        if e is None or not isinstance(e, dict) or e.get("event") != "done":
            continue
        for key, kinds in (("trial", int), ("track", str), ("level_db", (int, float))):
            v = e.get(key)
            if isinstance(v, bool) or not isinstance(v, kinds):
                raise UserError(f"{path}: line {n}: {key} = {v!r:.40}: wrong type; {FIX}")
        if not isinstance(e.get("correct"), bool):
            raise UserError(f"{path}: line {n}: correct = {e.get('correct')!r:.40}; {FIX}")
        last[e["trial"]] = e
    return [last[k] for k in sorted(last)]


def analyze_participant(folder: Path, *, n_boot: int | None = None) -> dict[str, Any]:
    """One participant's tracks: ``freq_hz``, ``waveform``, ``trials``, the fit
    (``threshold_db``, ``ci_db``, ``slope``, ``lapse``) and ``procedure_db``."""
    run = textfiles.read_json(folder / RUN, what="adaptive run (adaptive.json)", fix=FIX)
    if not isinstance(run, dict) or not isinstance(run.get("tracks"), dict):
        raise UserError(f"{folder / RUN}: tracks is missing or not an object; {FIX}")
    if run.get("measure", "detection") != "detection":
        raise UserError(
            f"{folder / RUN}: measure = {run.get('measure')!r}: the threshold analysis fits "
            "detection runs; analyse the threshold_* runs"
        )
    task = run.get("task", "2afc")
    trials = _done_trials(folder)
    curves = th.load_curves(folder)
    rows, notes = [], []
    for name, tr in run["tracks"].items():
        mine = [t for t in trials if t["track"] == name]
        row: dict[str, Any] = {
            "track": name,
            "freq_hz": float(tr["freq_hz"]),
            "waveform": tr.get("waveform"),
            "trials": len(mine),
        }
        proc = th.find_curve(curves, run.get("modality") or _modality(run), tr.get("waveform"))
        if proc is not None and float(tr["freq_hz"]) in proc["freq_hz"]:
            row["procedure_db"] = proc["threshold_db"][proc["freq_hz"].index(float(tr["freq_hz"]))]
        levels = {float(t["level_db"]) for t in mine}
        if len(levels) == 1:
            top = tr.get("max_level_db")
            at = "" if top is None else f" (the gate's largest level is {top:g} dB)"
            notes.append(
                f"{folder.name} {name}: all {len(mine)} trials at {levels.pop():g} dB{at}: "
                "no fit; the threshold is above what the table can play there"
            )
            row["above_db"] = float(mine[0]["level_db"])  # the one level: at least this
            rows.append(row)
            continue
        try:
            f = fit_trials(
                mine, task=task, n_boot=N_BOOT if n_boot is None else n_boot, seed=len(rows)
            )
        except UserError as exc:
            notes.append(f"{folder.name} {name}: no fit ({exc})")
            rows.append(row)
            continue
        row.update(
            threshold_db=f.threshold_db,
            ci_db=list(f.ci.get("threshold_db", (None, None))),
            slope=f.slope,
            lapse=f.lapse,
            fit=f.as_dict(),
        )
        rows.append(row)
    rows.sort(key=lambda r: (r["freq_hz"], str(r["waveform"])))
    return {
        "participant": folder.name,
        "experiment": run.get("experiment"),
        "reference": run.get("reference"),
        "task": task,
        "tracks": rows,
        "notes": notes,
    }


def _modality(run: dict[str, Any]) -> str:
    return "electrovibration" if run.get("reference") == "dB re 1 V" else "vibrotactile"


def analyze(dirs: list[Path], exclude: tuple[str, ...] = ()) -> dict[str, Any]:
    """Every threshold run in ``dirs``: per participant ``analyze_participant``."""
    folders = [f for f in run_folders(dirs) if f.name not in exclude]
    if not folders:
        raise UserError(f"{', '.join(map(str, dirs))}: no threshold run ({RUN}) in it")
    parts = [analyze_participant(f) for f in folders]
    exps = {p["experiment"] for p in parts}
    if len(exps) > 1:
        raise UserError(
            f"{', '.join(map(str, dirs))}: runs of {sorted(exps)}; analyse one at a time"
        )
    return {
        "experiment": exps.pop(),
        "kind": "threshold",
        "fit": f"Weibull in dB, ML; 95 % CI: parametric bootstrap ({N_BOOT} resamples)",
        "participants": parts,
        "notes": [n for p in parts for n in p["notes"]],
    }


def figure(res: dict[str, Any]):
    """Threshold vs frequency: each participant's fits (95 % CI bars; an open triangle:
    above the largest level played) and, for a vibrotactile curve in dB re 1 um, the
    population curve."""
    # lazy: matplotlib loads only for a figure
    from .report import _plt

    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for k, p in enumerate(res["participants"]):
        rows = [r for r in p["tracks"] if r.get("threshold_db") is not None]
        if not rows:
            continue
        f = np.array([r["freq_hz"] for r in rows]) * (1 + 0.015 * k)  # side by side
        t = np.array([r["threshold_db"] for r in rows])
        lo = np.array([r["ci_db"][0] for r in rows])
        hi = np.array([r["ci_db"][1] for r in rows])
        bars = ax.errorbar(
            f, t, yerr=[t - lo, hi - t], marker="o", capsize=2, label=p["participant"]
        )
        up = [r for r in p["tracks"] if r.get("above_db") is not None]
        if up:  # never detected at the largest level the table plays: above it
            fu = np.array([r["freq_hz"] for r in up]) * (1 + 0.015 * k)
            color = bars.lines[0].get_color()
            ax.plot(fu, [r["above_db"] for r in up], "^", color=color, mfc="none")
    ref = res["participants"][0]["reference"] if res["participants"] else ""
    if ref == "dB re 1 um":
        ax.plot(POPULATION["freq_hz"], POPULATION["threshold_db"], "k--", label=POPULATION["label"])
    ax.set_xscale("log")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"detection threshold ({ref})")
    ax.set_title(f"{res['experiment']}: thresholds per participant (ML fit, 95 % CI)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.15), fontsize=7, ncol=2)
    return fig


def lines(res: dict[str, Any]) -> list[str]:
    out = [f"{res['experiment']}: {len(res['participants'])} participant(s); {res['fit']}"]
    out += [f"  note: {n}" for n in res["notes"]]
    for p in res["participants"]:
        out.append(f"{p['participant']} ({p['reference']}, {p['task']}):")
        out.append(
            f"  {'freq_hz':>8} {'wave':>6} {'n':>4} {'threshold':>9} {'95 % CI':>16} "
            f"{'slope':>6} {'lapse':>6} {'procedure':>9}"
        )
        for r in p["tracks"]:
            if r.get("threshold_db") is None:
                out.append(f"  {r['freq_hz']:8g} {str(r['waveform']):>6} {r['trials']:4d}  no fit")
                continue
            ci = f"[{r['ci_db'][0]:.1f}, {r['ci_db'][1]:.1f}]"
            proc = r.get("procedure_db")
            out.append(
                f"  {r['freq_hz']:8g} {str(r['waveform']):>6} {r['trials']:4d} "
                f"{r['threshold_db']:9.1f} {ci:>16} {r['slope']:6.2f} {r['lapse']:6.3f} "
                f"{'-' if proc is None else format(proc, '9.1f'):>9}"
            )
    return out


def write_report(res: dict[str, Any], path: Path) -> Path:
    """An HTML page with the figure and the table (``.png``: the figure only)."""
    # lazy: as above
    from .report import _png

    fig = figure(res)
    path = Path(path)
    if path.suffix.lower() == ".png":
        fig.savefig(path, dpi=110, bbox_inches="tight")
        return path
    png = _png(fig)
    text = "\n".join(lines(res)).replace("&", "&amp;").replace("<", "&lt;")
    html = (
        f"<!doctype html><meta charset='utf-8'><title>{res['experiment']}</title>"
        f"<h1>{res['experiment']}: detection thresholds</h1>"
        f"<img alt='threshold vs frequency' src='data:image/png;base64,{png}'>"
        f"<pre>{text}</pre>"
    )
    write_text_atomic(path, html)
    return path


def run(args: Any, *, embedded: bool = False) -> Any:
    """The ``analyze`` command for threshold runs; ``embedded`` (fixed-plan runs in the
    same folders): the text printed unless ``--json``, the report to
    ``<report>-thresholds.html``, and the result returned for the other analysis's JSON."""
    res = analyze(list(args.dirs), exclude=tuple(args.exclude))
    if args.report is not None:
        rep = Path(args.report)
        if embedded:
            rep = rep.with_name(f"{rep.stem}-thresholds{rep.suffix or '.html'}")
        res["report"] = str(write_report(res, rep))
    if args.json and not embedded:
        print(json.dumps(res, indent=1, default=str))
    elif not args.json:
        print("\n".join(lines(res)))
        if args.report is not None:
            print(f"report: {res['report']}")
    return res if embedded else 0
