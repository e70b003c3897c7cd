"""Whether a designed signal can ever play on this table: what ``haptable signals add``
and the Signals screen ask before saving one.

``never_plays(node, limits)`` is ``None`` or one line saying why no target could take
the signal, with the profile setting behind the limit:

- a frequency (a waveform's, a chirp's ends, a low-pass cutoff) at or above half the
  sample rate (``[audio] sample_rate_hz``);
- no length of its own, not in volts, longer than ``[limits] max_plan_s`` or shorter than
  two samples;
- a shape that does not render (an ``adsr`` longer than what it shapes, not a number);
- its lowest and highest volts fit neither the patches (``[limits] piezo_min_v`` ..
  ``piezo_max_v``) nor the screen (``[limits] screen_max_vpp``).

The start/end ramps and the slew limit are left to the gate at play time: they depend on
the target's load, and the operator fixes them in the expression (``ramp(...)``,
``lowpass(...)``), which the Signals screen offers. The peak is found without building the
whole signal: a repeat or a sequence is as high as its highest part, a gain scales its
part, a waveform peaks at its amplitude; only sums, products and filters are rendered
(each within ``max_plan_s``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from console.core.errors import UserError
from console.core.plain_numbers import plain_s
from console.signals.design import Chirp, Gain, Lowpass, Mix, Node, Noise, Seq, Silence, Wave
from console.signals.waveforms import check_duration

if TYPE_CHECKING:
    from console.safety import Limits


def _frequencies(node: Node) -> list[tuple[str, float]]:
    """(the part as written, a frequency it plays) for every frequency in the tree."""
    out, todo = [], [node]
    while todo:
        n = todo.pop()
        if isinstance(n, Wave):
            out.append((n.text or n.kind, n.freq_hz))
        elif isinstance(n, Chirp):
            out += [(n.text or "chirp", n.f0_hz), (n.text or "chirp", n.f1_hz)]
        elif isinstance(n, Lowpass):
            out.append((n.text or "lowpass", n.cutoff_hz))
        if isinstance(n, (Gain, Lowpass)):
            todo.append(n.part)
        elif isinstance(n, (Mix, Seq)):
            todo += n.parts
    return out


def volt_range(node: Node, fs: int) -> tuple[float, float]:
    """The lowest and highest volts ``node`` (with a length) reaches at ``fs``."""
    if isinstance(node, Silence):
        return 0.0, 0.0
    if isinstance(node, (Wave, Chirp, Noise)):
        return -abs(node.amp_v), abs(node.amp_v)
    if isinstance(node, Gain):
        lo, hi = volt_range(node.part, fs)
        return (node.factor * lo, node.factor * hi)[:: 1 if node.factor >= 0 else -1]
    if isinstance(node, Seq):
        ranges = [volt_range(p, fs) for p in node.parts if p.duration_s() is not None]
        return min((r[0] for r in ranges), default=0.0), max((r[1] for r in ranges), default=0.0)
    n = node.n_samples(fs) or 0
    x = node.render(fs, n)
    if x.size and not np.all(np.isfinite(x)):
        raise UserError(f"{node.text or 'signal'}: not a number; check its values")
    return (float(x.min()), float(x.max())) if x.size else (0.0, 0.0)


def never_plays(node: Node, limits: Limits) -> str | None:
    """Why ``node`` can play on no target within ``limits``; ``None`` when some may take it."""
    fs = limits.sample_rate_hz
    for part, f in _frequencies(node):
        if f >= fs / 2:
            return (
                f"{part}: {f:g} Hz is at or above {fs / 2:g} Hz, half the outputs' sample rate "
                f"([audio] sample_rate_hz = {fs}); give a lower frequency"
            )
    d = node.duration_s()
    if d is None:
        return f"{node.text}: an envelope alone has no length; multiply it by a signal"
    if not node.volts:
        return f"{node.text}: a ratio, not volts; give the signal an amplitude in V"
    try:
        check_duration(d, limits.max_plan_samples / fs, "the signal")
        if round(d * fs) < 2:
            return f"{plain_s(d)} is shorter than two samples at {fs} Hz; give it a length"
        lo, hi = volt_range(node, fs)
    except UserError as exc:
        return str(exc)
    piezo = limits.piezo_min_v - 1e-9 <= lo and hi <= limits.piezo_max_v + 1e-9
    screen = max(-lo, hi) <= limits.screen_max_v + 1e-9
    if piezo or screen:
        return None
    return (
        f"it reaches {lo:.4g}..{hi:.4g} V, beyond every output: the patches take "
        f"{limits.piezo_min_v:g}..{limits.piezo_max_v:g} V ([limits] piezo_min_v, "
        f"piezo_max_v) and the screen {2 * limits.screen_max_v:g} Vpp ([limits] "
        "screen_max_vpp); lower the amplitude"
    )
