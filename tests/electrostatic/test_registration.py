"""What the electrostatic registrations offer an operator's screen: the knob's
``conditions`` and the friction ``presets``, each playable as registered."""

from __future__ import annotations

import numpy as np


def test_knob_conditions_are_the_names_render_takes(plugins, profile):
    from plugins.electrostatic.synth import parse_condition

    knob = plugins.get("effect", "knob").factory(profile)
    assert {"V", "HD", "HD+CF", "HD+VF"} <= set(knob.conditions)
    assert [parse_condition(c).name for c in knob.conditions] == list(knob.conditions)


def test_friction_presets_render_inside_the_limits(plugins, profile):
    from console.safety import Limits

    eff = plugins.get("effect", "electrostatic").factory(profile)
    lo, hi = Limits.from_profile(profile).screen_range()
    assert eff.presets
    for name, p in eff.presets.items():
        kw = {k: v for k, v in p.items() if k != "help"}
        plan = eff.render(duration_s=0.2, **kw)
        v = plan.segments[0].screen_v
        assert abs(np.ptp(v) - p["vpp"]) < 0.01 * p["vpp"], name
        assert lo <= v.min() and v.max() <= hi, name
        assert plan.meta["force_mean_n"] > 0 and p["help"], name
