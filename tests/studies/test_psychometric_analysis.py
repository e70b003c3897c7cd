"""``haptable study analyze`` on threshold runs (plugins/studies/threshold_analysis.py):
a fit per participant and frequency that recovers the simulated observers' thresholds,
the procedure's estimate beside it, and the threshold-vs-frequency figure with the
population curve."""

from __future__ import annotations

import argparse
import json

import numpy as np

from plugins.studies import analyze_cli
from plugins.studies import threshold_analysis as ta
from plugins.studies.adaptive_pf import p_correct
from plugins.studies.thresholds import save_curve

TRUTH = {"P01": {100.0: 2.0, 250.0: -14.0}, "P02": {100.0: 14.0, 250.0: -2.0}}


def _run(folder, pid, truth, seed):
    folder.mkdir(parents=True)
    tracks = {f"f{int(f)}": {"freq_hz": f, "waveform": None} for f in truth}
    run = {"experiment": "threshold_vibrotactile", "kind": "adaptive", "measure": "detection"}
    run |= {"task": "2afc", "reference": "dB re 1 um", "participant": pid, "tracks": tracks}
    (folder / "adaptive.json").write_text(json.dumps(run))
    rng = np.random.default_rng(seed)
    lines, n = [], 0
    for name, tr in tracks.items():
        t = truth[tr["freq_hz"]]
        for lv in np.round(t + rng.normal(0, 5, 120)):  # levels clustered near threshold
            ok = bool(rng.random() < p_correct(lv, "weibull", t, 3.0, 0.5, 0.02))
            lines.append(
                {"event": "done", "trial": n, "track": name, "level_db": lv, "correct": ok}
            )
            n += 1
    lines.insert(3, {"event": "start", "trial": 3})
    (folder / "adaptive_trials.jsonl").write_text("".join(json.dumps(x) + "\n" for x in lines))
    curve = {
        "modality": "vibrotactile",
        "waveform": None,
        "point": "25",
        "reference": "dB re 1 um",
        "freq_hz": sorted(truth),
        "threshold_db": [truth[f] + 0.5 for f in sorted(truth)],
        "ci_db": None,
        "procedure": "quest+",
        "protocol_sha256": "",
    }
    save_curve(folder, curve)


def test_fits_recover_each_observers_thresholds_and_draw_the_curves(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(ta, "N_BOOT", 15)
    for k, (pid, truth) in enumerate(TRUTH.items()):
        _run(tmp_path / pid, pid, truth, seed=k)
    res = ta.analyze([tmp_path])
    assert [p["participant"] for p in res["participants"]] == ["P01", "P02"]
    for p in res["participants"]:
        for r in p["tracks"]:
            truth = TRUTH[p["participant"]][r["freq_hz"]]
            assert abs(r["threshold_db"] - truth) < 2.5 and r["trials"] == 120
            assert r["ci_db"][0] < r["threshold_db"] < r["ci_db"][1]
            assert r["procedure_db"] == truth + 0.5
    fig = ta.figure(res)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert {"P01", "P02"} <= set(labels) and any("Verrillo" in t for t in labels)
    # through the analyze command: a table and the report page
    args = argparse.Namespace(dirs=[tmp_path], json=False, report=tmp_path / "r.html", exclude=[])
    assert analyze_cli.run(args) == 0
    out = capsys.readouterr().out
    assert "threshold_vibrotactile: 2 participant(s)" in out and "P02 (dB re 1 um, 2afc)" in out
    assert "data:image/png;base64," in (tmp_path / "r.html").read_text()
