"""Every registered thing satisfies its kind's Protocol (console/core/contracts.py), and a
plugin that does not is refused with one line naming the plugin, the kind and the
member it lacks."""

from __future__ import annotations

import types
import typing

import numpy as np
import pytest

from console.config.plugins import load_plugins
from console.core import contract_check, contracts
from console.core.errors import UserError
from console.core.hookspecs import hookimpl
from console.core.types import Frame, TunableRange

#: What the built-in registrations offer beyond their kind's contract (kind, name): the
#: capabilities console/ asks for instead of these names.
CAPABILITIES = {
    ("camera", "twin"): (
        contracts.TouchableCamera,
        contracts.SimulatedCamera,
        contracts.RendersBackground,
    ),
    ("classifier", "svm"): (contracts.TouchCalibrating, contracts.OrderedTunables),
    ("effect", "point"): (contracts.PointEffect,),
    ("effect", "flow"): (contracts.FlowEffect, contracts.TableEffect, contracts.MapImporter),
    ("effect", "hand_flow"): (contracts.HandFlowEffect, contracts.PrecomputedHandFlows),
    ("effect", "knob"): (contracts.Conditions, contracts.StreamingEffect, contracts.KnobTrials),
    ("effect", "electrostatic"): (contracts.Presets,),
    ("audio_output", "twin"): (contracts.SimulatedAudio,),
    ("relay_board", "twin"): (contracts.SimulatedRelays,),
}


def _built_class(factory) -> type | None:
    """The class a hardware driver's factory returns, from its return annotation."""
    try:
        ret = typing.get_type_hints(factory).get("return")
    except Exception:
        return None
    return ret if isinstance(ret, type) else None


def _check(obj, proto) -> None:
    assert isinstance(obj, proto), f"{obj!r} is not a {proto.__name__}"
    # the members and each method's signature against the Protocol's (inspect)
    assert contract_check.problems(obj, proto) == [], (obj, proto.__name__)


def _check_profile(pm, profile, *, must_build: bool) -> list[str]:
    checked = []
    for kind, regs in pm.registrations.items():
        for name, reg in regs.items():
            if kind in contracts.FACTORY_CONTRACTS:
                _check(reg.factory, contracts.FACTORY_CONTRACTS[kind])
                checked.append(f"{kind}:{name}")
                continue
            proto = contracts.KIND_CONTRACTS[kind]
            try:
                obj = pm.build(kind, name, profile)
            except UserError as exc:  # hardware absent: the driver's class instead
                if "does not satisfy" in str(exc):
                    raise
                cls = _built_class(reg.factory)
                assert cls is not None, f"{kind} {name!r} neither builds nor names its class"
                assert not must_build or reg.plugin == "drivers", f"{kind} {name}: {exc}"
                assert contract_check.problems(cls, proto) == [], (kind, name)
                checked.append(f"{kind}:{name} (class)")
                continue
            try:
                _check(obj, proto)
                for cap in CAPABILITIES.get((kind, name), ()):
                    _check(obj, cap)
            finally:
                if kind == "camera":
                    obj.close()
            checked.append(f"{kind}:{name}")
    return checked


def test_every_sim_registration_satisfies_its_contract(plugins, profile):
    checked = _check_profile(plugins, profile, must_build=True)
    # every kind has something registered and checked
    assert {c.split(":")[0] for c in checked} == set(contracts.KIND_CONTRACTS)
    assert "camera:twin" in checked and "effect:point" in checked
    assert "observer:twin" in checked  # the simulated participant of the plate twin


def test_the_lab_profile_s_registrations_too(plugins):
    from console.config.profile import load_profile

    lab = load_profile("haptable-lab", plugins)
    checked = _check_profile(plugins, lab, must_build=False)
    assert any(c.endswith("(class)") for c in checked)  # its drivers need the hardware


def test_the_panel_factory_builds_a_panel(plugins, profile):
    ctx = types.SimpleNamespace(profile=profile, plugins=plugins)
    for reg in plugins.of("panel").values():
        panel = reg.factory(types.SimpleNamespace(ctx=ctx))
        _check(panel, contracts.Panel)


def test_capabilities_are_found_by_protocol_not_name(plugins, profile):
    assert plugins.provider("effect", contracts.PointEffect, profile) is plugins.built(
        "effect", "point", profile
    )
    tables = plugins.provider("effect", contracts.TableEffect, profile)
    assert tables is plugins.provider("effect", contracts.MapImporter, profile)  # once
    assert [n for n, _ in plugins.providers("effect", contracts.Conditions, profile)] == ["knob"]
    knob = plugins.provider("effect", contracts.Conditions, profile)
    assert "HD+VF" in knob.conditions
    presets = plugins.provider("effect", contracts.Presets, profile).presets
    assert presets and all("help" in p for p in presets.values())


def test_a_missing_capability_names_it_and_the_plugin_to_enable(profile):
    pm = load_plugins(builtins={"electrostatic": "plugins.electrostatic"})
    with pytest.raises(UserError) as err:
        pm.provider("effect", contracts.PointEffect, profile, plugin_hint="vibrotactile")
    msg = str(err.value)
    assert "\n" not in msg
    assert "PointEffect" in msg and "render_point" in msg and "vibrotactile" in msg


def test_effects_are_built_once_per_profile(plugins, profile):
    from console.config.profile import load_profile

    a = plugins.built("effect", "flow", profile)
    assert plugins.built("effect", "flow", profile) is a
    other = load_profile("sim", plugins)
    assert plugins.built("effect", "flow", other) is not a
    assert plugins.build("effect", "flow", profile) is not a  # build: always fresh


# ------------------------------------------------------------------ refusals
class _NoRender:
    def stream(self, **request):
        return None


class _SceneWithoutState:
    needs: dict = {}

    def update(self, event: dict) -> None:
        pass


def _one_line(exc: pytest.ExceptionInfo, *words: str) -> None:
    msg = str(exc.value)
    assert "\n" not in msg, msg
    for w in words:
        assert w in msg, (w, msg)


def test_an_effect_without_render_is_refused_when_built(profile):
    class Broken:
        @hookimpl
        def haptable_register_effects(self, register):
            register("wobble", lambda profile: _NoRender())

    pm = load_plugins(extra={"wobbly": Broken()})
    with pytest.raises(UserError) as err:
        pm.build("effect", "wobble", profile)
    _one_line(err, "'wobbly'", "effect", "'wobble'", "render", "Effect")


def test_a_scene_class_without_state_is_refused_at_registration():
    class Broken:
        @hookimpl
        def haptable_register_scenes(self, register):
            register("blank", _SceneWithoutState)

    with pytest.raises(UserError) as err:
        load_plugins(extra={"blanker": Broken()})
    _one_line(err, "'blanker'", "scene", "'blank'", "no state")


def test_a_demo_without_status_lines_is_refused_at_registration():
    class Broken:
        @hookimpl
        def haptable_register_demos(self, register):
            register("mute", lambda profile, plugins, outputs, **params: None)

    with pytest.raises(UserError) as err:
        load_plugins(extra={"mutedemo": Broken()})
    _one_line(err, "'mutedemo'", "demo", "'mute'", "status_lines", "DemoFactory")


def test_a_frame_sink_factory_without_force_is_refused_at_registration():
    class Broken:
        @hookimpl
        def haptable_register_frame_sinks(self, register):
            register("deaf", lambda profile: None)

    with pytest.raises(UserError) as err:
        load_plugins(extra={"deafsink": Broken()})
    _one_line(err, "'deafsink'", "frame sink", "'deaf'", "force")


def test_a_method_with_the_wrong_signature_is_no_capability(profile):
    class HalfPoint:
        def render(self, **request):
            return None

        def render_point(self, point):  # no vmap
            return None

    bad = contract_check.problems(HalfPoint(), contracts.PointEffect)
    assert len(bad) == 1 and "render_point" in bad[0] and "vmap" in bad[0]

    class Broken:
        @hookimpl
        def haptable_register_effects(self, register):
            register("half", lambda profile: HalfPoint())

    pm = load_plugins(builtins={}, extra={"halfpoint": Broken()})
    assert pm.build("effect", "half", profile) is not None  # an Effect all the same
    with pytest.raises(UserError) as err:
        pm.provider("effect", contracts.PointEffect, profile)
    _one_line(err, "PointEffect", "half")


def test_a_required_parameter_the_contract_does_not_pass_is_a_problem():
    class Needy:
        def measure(self, progress=None, *, laser):
            return {}

    (bad,) = contract_check.problems(Needy(), contracts.Vibrometer)
    assert "laser" in bad


def test_the_register_callbacks_are_typed():
    from console.core import hookspecs

    hints = {
        name: typing.get_type_hints(fn)["register"]
        for name, fn in vars(hookspecs).items()
        if name.startswith("haptable_")
    }
    assert hints["haptable_register_commands"] is hookspecs.RegisterCommand
    assert hints["haptable_register_benchmarks"] is hookspecs.RegisterBenchmark
    assert hints["haptable_profile_sections"] is hookspecs.RegisterSection
    assert hints["haptable_register_effects"] is hookspecs.RegisterFactory
    for name, fn in vars(hookspecs).items():  # each kind's hook names its Protocol
        if name.startswith("haptable_register_") and name not in (
            "haptable_register_commands",
            "haptable_register_benchmarks",
        ):
            assert "contracts." in fn.__doc__, name


# ------------------------------------------------------------------ the members
def test_the_classifier_s_tunables_and_vision_result(plugins, profile):
    clf = plugins.build("classifier", "svm", profile)
    values = clf.tunables()
    ranges = clf.tunable_ranges()
    assert set(values) == set(ranges) and values
    name = next(iter(values))
    rng = ranges[name]
    assert isinstance(rng, TunableRange) and rng.min_value <= values[name] <= rng.max_value
    clf.set_tunable(name, rng.clamp(values[name] + rng.step))
    assert clf.tunables()[name] == pytest.approx(values[name] + rng.step)
    with pytest.raises(ValueError, match=name):
        clf.set_tunable(name, rng.max_value + 1)
    with pytest.raises(ValueError, match="not tunable"):
        clf.set_tunable("no_such_threshold", 1.0)
    assert clf.n_frames >= 0

    img = np.full((480, 640), 20, np.uint8)
    clf.set_background(img)
    res = clf.process(Frame(image=img, seq=0, t_capture_s=0.0))
    assert isinstance(res, contracts.VisionResult)
    assert res.hands == () and all(res.view(v) is not None for v in clf.views)
    assert res.view("no such image") is None


def test_the_twin_camera_maps_table_points_to_its_image(plugins, profile):
    cam = plugins.build("camera", "twin", profile)
    try:
        w, h = float(profile.get("table.width_mm")), float(profile.get("table.height_mm"))
        x, y = cam.mm_to_px((w / 2, h / 2))
        assert 0 < x < 640 and 0 < y < 480
        left, _ = cam.mm_to_px((0.0, h / 2))
        right, _ = cam.mm_to_px((w, h / 2))
        assert left != right
    finally:
        cam.close()


def test_the_demo_formats_its_own_snapshot(plugins):
    factory = plugins.get("demo", "flow").factory
    snap = {
        "demo": "flow",
        "running": True,
        "flow": {
            "direction": "up",
            "flows": 1,
            "last": [{"kind": "flow", "center_mm": [300.0, 200.0], "parts": []}],
        },
        "hand": {"hands": 1, "contacts": 2, "gesture": "open_hand", "rest_mm": [10.0, 20.0]},
    }
    lines = factory.status_lines(snap)
    assert lines[0].startswith("[b]flow[/b] running")
    assert "hand resting at 10,20 mm, 2 contacts, gesture open_hand" in lines
    assert any(line.startswith("flow up: 1 played") for line in lines)
    del snap["hand"]
    assert not any("hand" in line for line in factory.status_lines(snap))


# ------------------------------------------------------------------ probes
PROBE_LIMIT = 15


def _stdlib_modules(tree) -> set[str]:
    """Names a module binds to stdlib modules (``import os``, ``import socket as so``)."""
    import ast
    import sys

    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] in sys.stdlib_module_names:
                    out.add(alias.asname or alias.name.split(".")[0])
    return out


def probes() -> list[str]:
    """``getattr``/``hasattr`` calls in console/ on anything but a stdlib module the file
    imports (``getattr(os, "O_CLOEXEC", 0)`` asks the platform, not a plugin). The
    contract checker itself (console/core/contract_check.py) reads members by name: that is its
    job."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    out = []
    for path in sorted((root / "console").rglob("*.py")):
        if path.name == "contract_check.py" and path.parent.name == "core":
            continue
        tree = ast.parse(path.read_text(), str(path))
        modules = _stdlib_modules(tree)
        for node in ast.walk(tree):
            if not (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Name)
                and node.func.id in ("getattr", "hasattr")
                and node.args
            ):
                continue
            first = node.args[0]
            if isinstance(first, ast.Name) and first.id in modules:
                continue
            where = f"{path.relative_to(root)}:{node.lineno}"
            out.append(f"{where}: {ast.unparse(node)}")
    return sorted(out)


def test_few_probes():
    found = probes()
    assert len(found) < PROBE_LIMIT, (
        f"{len(found)} getattr/hasattr probes in console/ (ask for a capability of "
        "console/core/contracts.py instead):\n" + "\n".join(found)
    )
