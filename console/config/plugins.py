"""Plugin manager: built-in plugins and the ``haptable`` entry-point group, one code path.

Built-ins are registered with ``pm.register`` exactly like third-party plugins found in
the ``haptable`` entry-point group. ``HAPTABLE_BLOCK_PLUGINS=name,name`` blocks plugins
by name (a name also blocks its dotted children: ``twin`` blocks ``twin.plate``).
``HAPTABLE_LOAD_ENTRYPOINTS=0`` keeps installed third-party plugins out (tests do this).

What a registration builds is checked against its kind's Protocol
(``console.core.contracts.KIND_CONTRACTS``): a factory whose own contract is known (a demo's,
a frame sink's, a panel's, or a class) when it is registered, the built thing when it is
built (``Plugins.build``). console/ asks for capabilities, not names:
``plugins.provider("effect", contracts.PointEffect, profile)`` is the first registered
effect offering ``render_point`` (built once per profile).
"""

from __future__ import annotations

import importlib
import os
import threading
import types
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import Any

import pluggy

from console.config import core_sections
from console.core import contract_check, contracts, hookspecs
from console.core.errors import UserError
from console.core.suggest import suggestion

ENTRY_POINT_GROUP = "haptable"

#: Built-in plugins: name -> module. Registered like any third-party plugin.
BUILTIN_PLUGINS: dict[str, str] = {
    "twin": "plugins.twin",
    "twin.plate": "plugins.twin.plate",
    "twin.camera": "plugins.twin.camera",
    "vibrotactile": "plugins.vibrotactile",
    "gestures": "plugins.gestures",
    "electrostatic": "plugins.electrostatic",
    "projector": "plugins.projector",
    "drivers": "plugins.drivers",
    "demos": "plugins.demos",
    "tuio": "plugins.tuio",
    "recording": "plugins.recording",
    "studies": "plugins.studies",
}

#: The kinds a table's outputs process (``console.kernel``) builds: its sound card, its
#: relay board, and the vibrometer whose plate a simulated card's sensors read.
KERNEL_KINDS = ("audio_output", "relay_board", "vibrometer")

#: The built-in plugins registering ``KERNEL_KINDS``: the only built-ins the outputs
#: process loads (a test checks that no other registers one), so that it starts in a
#: fraction of the time; entry-point and extra plugins load as everywhere.
KERNEL_BUILTINS = ("twin", "twin.plate", "drivers")

#: The console's own screens, registered beside the core plugin as ``core.panels``.
CORE_PANELS = "console.tui.core_panels"

#: The profile section whose ``driver`` picks each device kind.
DRIVER_SECTIONS: dict[str, str] = {
    "camera": "camera",
    "audio_output": "audio",
    "relay_board": "relays",
    "vibrometer": "vibrometer",
}

#: Registration kinds and the hook that fills each.
KINDS: dict[str, str] = {
    "camera": "haptable_register_cameras",
    "classifier": "haptable_register_classifiers",
    "effect": "haptable_register_effects",
    "audio_output": "haptable_register_audio_outputs",
    "relay_board": "haptable_register_relay_boards",
    "scene": "haptable_register_scenes",
    "projector": "haptable_register_projectors",
    "vibrometer": "haptable_register_vibrometers",
    "demo": "haptable_register_demos",
    "panel": "haptable_register_panels",
    "frame_sink": "haptable_register_frame_sinks",
    "observer": "haptable_register_observers",
    "recording_reader": "haptable_register_recording_readers",
}


@dataclass(frozen=True)
class PanelTab:
    """How a panel shows as one of the console's tabs: its ``title``, the ``key`` that
    opens it (``"f6"``; empty: none) and its ``order`` among the tabs (lower first)."""

    title: str
    key: str = ""
    order: int = 100


@dataclass(frozen=True)
class Registration:
    """Something a plugin provides: a factory and how to describe and probe it (a panel:
    ``tab``, how it shows as a tab; None: in the command palette only)."""

    kind: str
    name: str
    plugin: str
    factory: Callable[..., Any]
    description: str = ""
    probe: Callable[..., Any] | None = None
    tab: PanelTab | None = None
    #: audio outputs: ``devices(profile) -> list[OutputDevice]``, what it can open
    devices: Callable[..., Any] | None = None


@dataclass(frozen=True)
class Command:
    name: str
    plugin: str
    configure: Callable[..., None]
    run: Callable[..., int]
    help: str = ""


@dataclass(frozen=True)
class Benchmark:
    name: str
    plugin: str
    run: Callable[..., dict]
    help: str = ""


@dataclass
class Plugins:
    """The loaded plugin manager and everything its plugins registered."""

    pm: pluggy.PluginManager
    registrations: dict[str, dict[str, Registration]] = field(default_factory=dict)
    commands: dict[str, Command] = field(default_factory=dict)
    benchmarks: dict[str, Benchmark] = field(default_factory=dict)
    sections: dict[str, tuple[dict, bool, str, str]] = field(default_factory=dict)
    #: a section's check across keys and sections (``register(..., check=)``): called
    #: with the validated profile at load, raises ``UserError`` naming the key
    section_checks: dict[str, Callable[[Any], None]] = field(default_factory=dict)
    #: plugins registered with ``load_plugins(extra=...)`` that are modules: (name, module
    #: name, file) -- what another process (a table's kernel) loads to have the same ones
    extra_modules: tuple[tuple[str, str, str], ...] = ()
    _built: dict[tuple[str, str, int], tuple[Any, Any]] = field(default_factory=dict, repr=False)
    _build_lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def of(self, kind: str) -> dict[str, Registration]:
        """Registrations of one kind (``camera``, ``audio_output`` ...) by name."""
        return self.registrations.get(kind, {})

    def get(self, kind: str, name: str) -> Registration:
        regs = self.of(kind)
        if name not in regs:
            known = ", ".join(sorted(regs)) or "none"
            raise UserError(f"no {kind.replace('_', ' ')} named {name!r}; available: {known}")
        return regs[name]

    def plugin_names(self) -> list[str]:
        return sorted(n for n, p in self.pm.list_name_plugin() if n and p is not None)

    def simulated(self, kind: str, profile: Any) -> bool:
        """Whether the profile's driver of ``kind`` is a simulation (the twin): its
        registration's probe says ``"simulated"``, without opening it."""
        reg = self.of(kind).get(profile.get(f"{DRIVER_SECTIONS[kind]}.driver"))
        if reg is None or reg.probe is None:
            return False
        try:
            return reg.probe(profile).state == "simulated"
        except Exception:  # a probe that fails says nothing is simulated
            return False

    # ------------------------------------------------------------ capabilities
    def build(self, kind: str, name: str, profile: Any) -> Any:
        """Build registration ``name`` of ``kind`` for ``profile`` (fresh each call) and
        check it against its kind's contract: a ``UserError`` names the plugin, the kind
        and the missing member."""
        reg = self.get(kind, name)
        obj = reg.factory(profile)
        proto = contracts.KIND_CONTRACTS.get(kind)
        if proto is not None and kind not in contracts.FACTORY_CONTRACTS:
            refuse(reg, obj, proto)
        return obj

    def built(self, kind: str, name: str, profile: Any) -> Any:
        """``build``, once per (kind, name, profile): effects are built once."""
        key = (kind, name, id(profile))
        with self._build_lock:
            hit = self._built.get(key)
            if hit is not None and hit[0] is profile:
                return hit[1]
        obj = self.build(kind, name, profile)
        with self._build_lock:
            hit = self._built.setdefault(key, (profile, obj))  # a racing build: keep one
            return hit[1] if hit[0] is profile else obj

    def providers(self, kind: str, proto: type, profile: Any) -> list[tuple[str, Any]]:
        """Every registration of ``kind`` whose built object satisfies the capability
        ``proto`` (a ``console.core.contracts`` Protocol), as ``(name, object)`` in
        registration order; objects are built once per profile."""
        return [
            (name, obj)
            for name in self.of(kind)
            if contract_check.satisfies(obj := self.built(kind, name, profile), proto)
        ]

    def provider_name(self, kind: str, proto: type, profile: Any, *, plugin_hint: str = "") -> str:
        """The name of the first registration of ``kind`` offering ``proto``. None does:
        a ``UserError`` naming the capability and its members, and ``plugin_hint`` (the
        plugin to enable) when the caller knows one."""
        found = self.providers(kind, proto, profile)
        if found:
            return found[0][0]
        what = ", ".join(m for m in contract_check.members(proto) if m != "__call__")
        have = ", ".join(self.of(kind)) or "none"
        enable = f"install/enable {plugin_hint}" if plugin_hint else "install/enable a plugin"
        raise UserError(
            f"no {kind.replace('_', ' ')} plugin offers {contract_check.summary(proto)} "
            f"({proto.__name__}: {what}): {enable} (registered: {have})"
        )

    def provider(
        self, kind: str, proto: type, profile: Any, *, plugin_hint: str = "", fresh: bool = False
    ) -> Any:
        """The first registration of ``kind`` offering ``proto`` (``provider_name``),
        built for ``profile`` once; ``fresh``: a new object of it, for a caller whose
        state must not be shared."""
        name = self.provider_name(kind, proto, profile, plugin_hint=plugin_hint)
        return self.build(kind, name, profile) if fresh else self.built(kind, name, profile)


def blocked_names() -> set[str]:
    raw = os.environ.get("HAPTABLE_BLOCK_PLUGINS", "")
    return {n.strip() for n in raw.split(",") if n.strip()}


def is_blocked(name: str, blocked: set[str]) -> bool:
    return any(name == b or name.startswith(b + ".") for b in blocked)


def _plugin_name(pm: pluggy.PluginManager, impl: Any) -> str:
    return pm.get_name(impl.plugin) or repr(impl.plugin)


def _check_hooks(pm: pluggy.PluginManager) -> None:
    """Fail at start-up, naming the plugin, when a hook implementation matches no spec."""
    known = [n for n in dir(hookspecs) if n.startswith("haptable_")]
    for name, caller in sorted(vars(pm.hook).items()):  # the relay's hook callers
        if not name.startswith("haptable_"):
            continue
        if caller.spec is None:
            impls = caller.get_hookimpls()
            who = ", ".join(sorted({_plugin_name(pm, i) for i in impls}))
            hint = suggestion(name, known)
            raise UserError(
                f"plugin {who!r} implements unknown hook {name!r}{hint}; "
                f"the hooks are listed in console/core/hookspecs.py"
            )
    try:
        pm.check_pending()
    except pluggy.PluginValidationError as exc:
        raise UserError(f"plugin {exc.plugin!r}: {exc}") from None


def refuse(reg: Registration, obj: Any, proto: type) -> None:
    """One line naming the plugin, the kind and what ``obj`` lacks of ``proto``."""
    bad = contract_check.problems(obj, proto)
    if bad:
        kind = reg.kind.replace("_", " ")
        raise UserError(
            f"plugin {reg.plugin!r} registers {kind} {reg.name!r} that does not satisfy "
            f"console.core.contracts.{proto.__name__}: {'; '.join(bad)}"
        )


def check_registration(reg: Registration) -> None:
    """What can be checked before anything is built: the factory's own contract (a
    demo's, a frame sink's, a panel's) or, for a class, its methods."""
    if not callable(reg.factory):
        raise UserError(
            f"plugin {reg.plugin!r} registers {reg.kind.replace('_', ' ')} {reg.name!r} "
            f"with a factory that is not callable: {reg.factory!r}"
        )
    factory_proto = contracts.FACTORY_CONTRACTS.get(reg.kind)
    if factory_proto is not None:
        refuse(reg, reg.factory, factory_proto)
    elif isinstance(reg.factory, type) and reg.kind in contracts.KIND_CONTRACTS:
        lacking = contract_check.missing(reg.factory, contracts.KIND_CONTRACTS[reg.kind])
        if lacking:
            refuse(reg, reg.factory, contracts.KIND_CONTRACTS[reg.kind])


def _registrar(regs: dict[str, Registration], kind: str, owner: str) -> hookspecs.RegisterFactory:
    def register(
        name: str,
        factory: Callable[..., Any],
        *,
        description: str = "",
        probe: Callable[..., Any] | None = None,
        tab: PanelTab | None = None,
        devices: Callable[..., Any] | None = None,
    ) -> None:
        if tab is not None and kind != "panel":
            raise UserError(f"plugin {owner!r}: {kind} {name!r}: only a panel shows as a tab")
        if devices is not None and kind != "audio_output":
            raise UserError(
                f"plugin {owner!r}: {kind} {name!r}: only an audio output lists devices"
            )
        reg = Registration(kind, name, owner, factory, description, probe, tab, devices)
        check_registration(reg)
        regs[name] = reg

    return register


def _collect(plugins: Plugins) -> None:
    pm = plugins.pm
    for kind, hook_name in KINDS.items():
        regs: dict[str, Registration] = {}
        for impl in reversed(vars(pm.hook)[hook_name].get_hookimpls()):
            impl.function(register=_registrar(regs, kind, _plugin_name(pm, impl)))
        plugins.registrations[kind] = regs

    for impl in reversed(pm.hook.haptable_register_commands.get_hookimpls()):
        owner = _plugin_name(pm, impl)

        def reg_cmd(name, configure, run, *, help="", _owner=owner):  # noqa: A002
            plugins.commands[name] = Command(name, _owner, configure, run, help)

        impl.function(register=reg_cmd)

    for impl in reversed(pm.hook.haptable_register_benchmarks.get_hookimpls()):
        owner = _plugin_name(pm, impl)

        def reg_bench(name, run, *, help="", _owner=owner):  # noqa: A002
            plugins.benchmarks[name] = Benchmark(name, _owner, run, help)

        impl.function(register=reg_bench)

    for impl in reversed(pm.hook.haptable_profile_sections.get_hookimpls()):
        owner = _plugin_name(pm, impl)

        def reg_section(
            section,
            fields,
            *,
            per_item=False,
            help="",
            check=None,
            _owner=owner,  # noqa: A002
        ):
            plugins.sections[section] = (fields, per_item, help, _owner)
            if check is not None:
                plugins.section_checks[section] = check

        impl.function(register=reg_section)


def import_extra(modules: Any) -> dict[str, Any]:
    """The plugin modules ``Plugins.extra_modules`` names, imported here (by name, else
    from their file): another process loads the plugins a client process was given."""
    import importlib.util
    import sys

    out = {}
    for name, modname, file in modules:
        try:
            out[name] = importlib.import_module(modname)
            continue
        except ImportError:
            pass
        spec = importlib.util.spec_from_file_location(modname, file)
        if spec is None or spec.loader is None:
            raise UserError(f"plugin {name!r}: cannot load {file}")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[modname] = mod
        spec.loader.exec_module(mod)
        out[name] = mod
    return out


def load_plugins(
    *,
    core: Any = None,
    builtins: dict[str, str] | None = None,
    entrypoints: bool | None = None,
    extra: dict[str, Any] | None = None,
) -> Plugins:
    """Build the manager: core hooks, built-in plugins, then entry-point plugins.

    ``core`` is the plugin registered as ``core``: by default ``console.config.core_sections``
    (the core's profile sections); the CLI passes ``console.cli.core_commands``, which adds the
    core commands and benchmarks and sits above this layer, so it is given, not imported.
    ``extra`` registers plugin objects by name (tests use it to add a plugin).
    """
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    blocked = blocked_names()
    for name in blocked:
        pm.set_blocked(name)

    pm.register(core_sections if core is None else core, name="core")
    # the console's own screens: a tui module, registered by name as the built-in plugins
    # are (this layer imports neither)
    pm.register(importlib.import_module(CORE_PANELS), name="core.panels")
    for name, module in (BUILTIN_PLUGINS if builtins is None else builtins).items():
        if not is_blocked(name, blocked):
            pm.register(importlib.import_module(module), name=name)

    if entrypoints is None:
        entrypoints = os.environ.get("HAPTABLE_LOAD_ENTRYPOINTS", "1") != "0"
    if entrypoints:
        for ep in entry_points(group=ENTRY_POINT_GROUP):
            if is_blocked(ep.name, blocked) or pm.get_plugin(ep.name) is not None:
                continue
            try:
                plugin = ep.load()
            except Exception as exc:  # a broken third-party plugin must not hide the rest
                raise UserError(
                    f"plugin {ep.name!r} (entry point {ep.value}) failed to import: {exc}; "
                    f"fix or uninstall it, or block it with HAPTABLE_BLOCK_PLUGINS={ep.name}"
                ) from None
            pm.register(plugin, name=ep.name)

    portable = []
    for name, plugin in (extra or {}).items():
        if not is_blocked(name, blocked):
            pm.register(plugin, name=name)
            file = vars(plugin).get("__file__") if isinstance(plugin, types.ModuleType) else None
            if file:
                portable.append((name, plugin.__name__, str(file)))

    _check_hooks(pm)
    plugins = Plugins(pm, extra_modules=tuple(portable))
    _collect(plugins)
    return plugins
