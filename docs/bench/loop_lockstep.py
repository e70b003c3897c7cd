"""The camera loop's per-frame cost of checkouts side by side, in lockstep (issue 28).

One process per checkout processes the same saved frames; every frame goes to each in
turn (the order alternating per frame and per pass), so a change of the machine's load
hits them alike. Each process reports the thread CPU of its ``vision`` + ``classify``
stages per frame (OpenCV runs on the calling thread: ``[vision] opencv_threads = 1``).
The summary pairs the checkouts frame by frame: the median of the per-frame ratios and
its 95 % interval, bootstrapped over rounds (fresh processes: one tree against itself
differs by up to 2-3 % between two processes) and frames.

  python docs/bench/loop_lockstep.py save DIR   (with a checkout's python) the twin's knob
        (2 s) and flow (5 s) replays as ``bench loop`` renders them, 4 s of the empty table
  python docs/bench/loop_lockstep.py run DIR OUT.json ROUNDS PASSES REF NEW   each
        checkout with its own .venv, else this python with PYTHONPATH=the checkout
  python docs/bench/loop_lockstep.py summary OUT.json   NEW against REF

Two checkouts at a time, swapping places every other round: of three taking turns, the
middle one never runs twice in a row (the ends do, their caches warm): it read 2-7 %
dearer than it is.
"""

import json
import os
import subprocess
import sys
import tempfile
import time

DEMOS = ("knob", "flow", "empty")


def save(folder: str) -> None:
    import numpy as np

    from console.config.plugins import load_plugins
    from console.runtime.context import Context
    from console.runtime.stages import open_camera
    from plugins.demos.bench import render_script
    from plugins.twin.camera.scripts import IdleScript

    ctx = Context(None, load_plugins())
    for demo, secs in (("knob", 2.0), ("flow", 5.0)):
        cam = render_script(ctx, demo, secs)
        np.savez(
            f"{folder}/{demo}.npz", images=np.array(cam.images), bg=np.asarray(cam.background())
        )
    cam = open_camera(ctx.profile, ctx.pm)
    try:
        cam.realtime = False
        cam.set_script(IdleScript())
        images = np.array([cam.read().image for _ in range(240)])
        np.savez(f"{folder}/empty.npz", images=images, bg=np.asarray(cam.background()))
    finally:
        cam.close()


def child(frames: str) -> None:
    """Reads ``reset`` or a frame's index per line; answers the frame's CPU times."""
    import numpy as np

    try:
        from console.config.plugins import load_plugins
        from console.core.types import Frame
        from console.runtime.context import Context
    except ImportError:  # the layout before the console's packages moved (524bcd1)
        from console.plugins import load_plugins
        from console.types import Frame

        from console.cli import Context
    from console.runtime.stages import base_stages, open_classifier

    ctx = Context(None, load_plugins())
    z = np.load(frames)
    images, bg = list(z["images"]), z["bg"]
    stages = None
    clock = time.thread_time_ns
    print("ready", len(images), flush=True)
    for line in sys.stdin:
        cmd = line.strip()
        if cmd == "reset":
            clf = open_classifier(ctx.profile, ctx.pm)
            clf.set_background(bg)
            stages = base_stages(clf)
            print("ok", flush=True)
            continue
        k = int(cmd)
        frame, work, ts = Frame(images[k], k, k / 60.0), {}, []
        for _, stage in stages:
            c0 = clock()
            stage(frame, work)
            ts.append(clock() - c0)
        print(ts[0], ts[1], len(work["hands"]), flush=True)


def run(folder: str, out: str, rounds: int, passes: int, trees: list[str]) -> None:
    """``rounds`` x (fresh processes, a warm-up pass, ``passes`` passes) per demo."""
    if len(trees) != 2:
        raise SystemExit("lockstep: two checkouts, REF and NEW")
    # each process starts in its checkout: the paths from here
    folder, trees = os.path.abspath(folder), [os.path.abspath(t) for t in trees]
    res = {"load_start": os.getloadavg(), "trees": trees, "rounds": rounds, "passes": passes}
    res["cpu"] = _cpu()
    for demo in DEMOS:
        res[demo] = [
            [] for _ in trees
        ]  # per tree: round x pass x frame x (vision, classify, hands)
        for k in range(rounds):
            # every other round the checkouts swap places (started first, first in turn):
            # alone, the second place read 0.5-1 % cheaper
            step = -1 if k % 2 else 1
            got = _round(folder, demo, passes, trees[::step])[::step]
            for i in range(len(trees)):
                res[demo][i].append(got[i])
    res["load_end"] = os.getloadavg()
    with open(out, "w") as f:
        json.dump(res, f)


def _round(folder: str, demo: str, passes: int, trees: list[str]) -> list[list]:
    procs = []
    for t in trees:
        env = dict(os.environ, HOME=tempfile.mkdtemp(), XDG_RUNTIME_DIR=tempfile.mkdtemp())
        env.pop("PYTHONPATH", None)
        py = f"{t}/.venv/bin/python"
        if not os.path.exists(py):  # a checkout without its own: this one's, importing t
            py, env["PYTHONPATH"] = sys.executable, t
        p = subprocess.Popen(
            [py, os.path.abspath(__file__), "child", f"{folder}/{demo}.npz"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            cwd=t,
            env=env,
        )
        n = int(p.stdout.readline().split()[1])
        procs.append(p)
    rows: list[list] = [[] for _ in trees]
    for ps in range(passes + 1):  # the first pass warms up
        for p in procs:
            p.stdin.write("reset\n")
            p.stdin.flush()
            p.stdout.readline()
        cur: list[list] = [[] for _ in trees]
        for k in range(n):
            order = list(enumerate(procs))
            if (k + ps) % 2:
                order.reverse()
            for i, p in order:
                p.stdin.write(f"{k}\n")
                p.stdin.flush()
                cur[i].append([int(x) for x in p.stdout.readline().split()])
        if ps:
            for i in range(len(trees)):
                rows[i].append(cur[i])
    for p in procs:
        p.stdin.close()
        p.wait()
    return rows


def _cpu() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        return next(
            ln.split(":", 1)[1].strip() for ln in out.splitlines() if ln.startswith("Model name")
        )
    except (OSError, StopIteration):
        return "?"


def summary(out: str, seed: int = 1) -> None:
    """NEW against REF."""
    with open(out) as f:
        r = json.load(f)
    print(
        f"{r['cpu']}, {os.cpu_count()} cores; load {r['load_start']} -> {r['load_end']}; "
        f"{r['rounds']} rounds of fresh processes x {r['passes']} passes (+1 warm-up)"
    )
    _pair(r, 0, 1, seed)


def _pair(r: dict, i: int, j: int, seed: int) -> None:
    import numpy as np

    print(f"\n{r['trees'][j]} / {r['trees'][i]}: thread CPU of vision + classify per frame")
    print(
        f"{'frames':12s}{'old ms':>8s}{'new ms':>8s}  {'paired median ratio [95 %]':28s}"
        f"{'per round':36s}pairs"
    )
    rng = np.random.default_rng(seed)
    for demo in DEMOS:
        if demo not in r:
            continue
        a = np.array(r[demo][i], float)  # round x pass x frame x 3
        b = np.array(r[demo][j], float)
        hands = b[0, 0, :, 2]
        for kind, sel in (("hand", hands > 0), ("empty", hands == 0)):
            if not sel.any():
                continue
            ta = (a[..., sel, 0] + a[..., sel, 1]) / 1e6
            tb = (b[..., sel, 0] + b[..., sel, 1]) / 1e6
            ratio = tb / ta  # round x pass x frame
            nr, _, nf = ratio.shape
            boots = []
            for _ in range(1000):  # rounds and frames resampled (a frame's passes together)
                pick = ratio[rng.integers(0, nr, nr)]
                boots.append(np.median(pick[:, :, rng.integers(0, nf, nf)]))
            lo, hi = np.percentile(boots, [2.5, 97.5])
            rounds = " ".join(f"{np.median(x):.3f}" for x in ratio)
            print(
                f"{demo + ' ' + kind:12s}{np.median(ta):8.3f}{np.median(tb):8.3f}  "
                f"x{np.median(ratio):.3f} [{lo:.3f}, {hi:.3f}]{'':8s}{rounds:36s}{ratio.size}"
            )


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "save":
        save(sys.argv[2])
    elif cmd == "child":
        child(sys.argv[2])
    elif cmd == "run":
        run(sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), sys.argv[6:])
    else:
        summary(sys.argv[2])
