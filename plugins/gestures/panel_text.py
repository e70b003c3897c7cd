"""The Gestures panel's text blocks: the dataset and model files, the result after
training, and a plugin's message as the panel says it (worded for the console, paths as
the panel writes them)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from console.plugin_api import AT_CONSOLE, worded
from console.plugin_api.tui import escape, short_path


def mb(n: int | None) -> str:
    return "?" if n is None else f"{n / 1e6:.1f} MB"


def pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.1f} %"


def in_panel(exc: BaseException | str, *shown: Path) -> str:
    """A message of the plugin as the panel says it: worded for the console (its fix
    names this panel's keys: ``console.core.words``) with its paths written as the
    panel writes them (``short_path``)."""
    text = exc if isinstance(exc, str) else worded(exc, AT_CONSOLE)
    for path in shown:
        for form in {str(path), str(path.expanduser()), str(path.expanduser().resolve())}:
            text = text.replace(form, short_path(path))
    return text


def describe(info: dict[str, Any], evaluation_below: bool = False) -> str:
    """The files block of the panel from ``jobs.describe_files``; ``evaluation_below``:
    the model's evaluation is the result block's (said there, once)."""
    d, m = info.get("dataset", {}), info.get("model", {})
    lines = [f"[b]dataset[/b] {escape(short_path(d.get('path', '?')))}"]
    if "error" in d:  # a refusal first: s and t say the same
        lines.append(f"  [red]{escape(in_panel(d['error'], Path(d.get('path', '?'))))}[/]")
    elif not d.get("exists"):
        lines.append("  none yet: s synthesizes one from the camera twin")
    else:
        subj = d["subjects"]
        lines.append(
            escape(
                f"  {d['samples']} samples, {mb(d.get('bytes'))}: {len(subj)} subject(s) "
                f"({', '.join(subj[:6])}{' ...' if len(subj) > 6 else ''}), "
                f"{d['gestures']} gestures, {d['reps']} reps"
            )
        )
    lines.append(f"[b]model[/b] {escape(short_path(m.get('path', '?')))}")
    if "error" in m:
        lines.append(f"  [red]{escape(in_panel(m['error'], Path(m.get('path', '?'))))}[/]")
    elif not m.get("exists"):
        lines.append("  none yet: t trains and evaluates one")
    else:
        ev = m.get("evaluation") or {}
        lines.append(escape(f"  {mb(m.get('bytes'))}, trained on {m.get('n_samples')} samples"))
        if ev and evaluation_below:
            lines.append("  its evaluation: the result below")
        elif ev:
            lines.append(
                escape(
                    f"  {ev.get('cv')}: static {pct(ev.get('static_accuracy'))}, "
                    f"dynamic {pct(ev.get('dynamic_accuracy'))}; folds "
                    + ", ".join(pct(f["accuracy"]) for f in ev.get("folds", []))
                )
            )
            lines.append(escape(f"  {ev.get('procedure', 'procedure not recorded')}"))
        else:
            lines.append("  no evaluation in its metadata (trained by the CLI)")
    return "\n".join(lines)


def fold_lines(res: dict[str, Any]) -> str:
    """The result block after training: accuracy per fold and overall."""
    lines = [
        f"[b]{escape(res['cv'])}[/b] on {escape(res['n_samples'])} samples: static "
        f"{escape(pct(res['static_accuracy']))}, dynamic {escape(pct(res['dynamic_accuracy']))}",
        escape(f"  {res.get('procedure', '?')} (as `haptable gestures eval`)"),
    ]
    for i, f in enumerate(res["folds"], 1):
        who = f" (subject {f['subject']})" if "subject" in f else ""
        lines.append(
            escape(
                f"  fold {i}{who}: {pct(f['accuracy'])} of {f['n_test']} "
                f"(static {pct(f['static_accuracy'])}, dynamic {pct(f['dynamic_accuracy'])})"
            )
        )
    lines.append(escape(f"model saved to {short_path(res['model'])} ({mb(res['bytes'])})"))
    return "\n".join(lines)
