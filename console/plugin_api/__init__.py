"""The plugin API: all a plugin may import from the console (its core part).

A plugin, built-in or third-party, imports the console through three modules and no
other (``tests/console/test_plugin_api.py`` holds every module under ``plugins/`` to it,
and takes the root of any other plugin package):

- ``console.plugin_api`` (this module): the values, contracts and helpers below. Light:
  numpy and pluggy, no Textual, no runtime.
- ``console.plugin_api.runtime``: the frame loop's stages, latency, tracking, the
  projector link, the outputs client, session events (loaded name by name, on first use).
- ``console.plugin_api.tui``: the console's Textual helpers a panel uses.

What this module offers, by where it comes from:

- errors: ``UserError``, ``SafetyRefusal``, ``TableBusy`` (refused: another process holds
  the outputs), ``EStopped`` (the table's e-stop stopped the command: exit 4); a message's fix where the user is
  (``console.core.words``): ``Placed`` (a fix per place), ``worded``, ``AT_CLI``,
  ``AT_CONSOLE``, ``listing``, ``counted``; ``OFF_LOOP``, the words for plays planned
  outside the frame loop (Scenes and Latency say them alike)
- the values that cross plugin boundaries (``console.core.types``): ``Frame``, ``Hand`` (its
  ``HandShape``),
  ``Contact``, ``Gesture``, ``GestureScript``, ``GestureStep``, ``OutputPlan`` (its
  ``meta`` a ``PlanInfo`` of ``PlanPart``), ``Segment``, ``OutputDevice``, ``DeviceStatus``, ``TunableRange``, ``PATCHES``,
  ``patches_of``, ``DIRECTIONS``, ``DIRECTIONS_MM``, ``EXCITATIONS``
- the typed capabilities (``console.core.contracts``): ``AdjustableCamera``, ``BeginsRun``, ``WatchesOutputs``, ``BlockSource``, ``Classifier``,
  ``Conditions``, ``FlowEffect``, ``FlowPatchDrives``, ``HandFlowEffect``,
  ``HandFlowGeometry``, ``KnobTrials``,
  ``PrecomputedHandFlows``, ``Presets``, ``SimulatedCamera``, ``SimulatedObserver``,
  ``VisionResult``
- the time left by the console's one rule (``console.core.time_left``): ``JobLeft`` (one
  job's, steady), ``left_words`` ("about 1 min 10 s left")
- the hook marker: ``hookimpl`` (the hooks are documented in ``console.core.hookspecs``)
- plugin manager and profile: ``Plugins``, ``PanelTab``, ``load_plugins``, ``Profile``,
  ``load_profile``, ``profile_file``, ``save_overrides`` (the profile's overrides file)
- settings schema and CLI options: ``Field``, ``KINDS``, ``check``, ``path_problem``;
  ``Parser``, ``BadValue``, ``finite_float``, ``from_field``, ``host_name``, ``integer``,
  ``minutes``, ``port``, ``positive_int``, ``seconds``, ``seed``
- safety: ``Limits``
- outputs: ``ChannelLayout``, ``BUS_CHANNELS``, ``MAX_PLAN_S``, ``check_duration``,
  ``plan_samples``, ``tone``; live streams ``StreamSynth``, ``StreamSpec``, ``StreamSink``,
  ``PulseSpec``, ``Envelope``, ``smooth_square``, ``spec_problem``; the card's inputs
  (``console.core.audio_inputs``): ``InputSpec``, ``input_specs``, ``find_input``
- the vibration map: ``VibrationMap``, ``make_map``, ``map_from_arrays``, ``load_map``,
  ``save_map``, ``grid_points_mm``, ``KEYS``, ``FIX``, ``MAX_FRF_UM_PER_V``
- files: ``write_text_atomic``, ``append_json_line`` and its reader ``read_json_lines``
  (``decode``, ``parse_json``, ``torn``, ``MAX_JSON_DEPTH``), ``read_bytes_capped``,
  ``parse_toml_text``, ``read_npz``, ``npz_keys``, ``json_depth``, ``cache_dir``,
  ``data_dir``, ``cached_arrays``, ``entry_path``, ``input_hash``
- what a run hands its outputs, as a recording keeps it (``console.core.plan_watch``):
  ``WatchedOutputs``, ``plan_line``, ``plan_record``, ``plan_hash``, ``report_clocks``,
  ``json_values``; the kernel's own gate events (``console.core.gate_log``): ``GateLog``,
  ``gate_events_text``, ``read_gate_events``, ``GATE_EVENT_DTYPE``, ``GATE_EVENTS``
- real time and benchmarks: ``realtime_priority``, ``support_priority``,
  ``StallWitness``, ``ORIGINS``, ``machine_info``, ``summarize_s``
"""

from __future__ import annotations

from console.config.plugins import PanelTab, Plugins, load_plugins
from console.config.profile import Profile, load_profile, save_overrides
from console.config.profile_files import profile_file
from console.core.audio_inputs import InputSpec, find_input, input_specs
from console.core.bench_stats import machine_info, summarize_s
from console.core.channels import BUS_CHANNELS, ChannelLayout
from console.core.contracts import (
    AdjustableCamera,
    BeginsRun,
    BlockSource,
    Classifier,
    Conditions,
    FlowEffect,
    FlowPatchDrives,
    HandFlowEffect,
    HandFlowGeometry,
    KnobTrials,
    PrecomputedHandFlows,
    Presets,
    SimulatedCamera,
    SimulatedObserver,
    VisionResult,
    WatchesOutputs,
)
from console.core.device_buffer import buffer_latency_s as device_buffer_latency_s
from console.core.device_buffer import buffer_periods as device_buffer_periods
from console.core.errors import EStopped, SafetyRefusal, TableBusy, UserError
from console.core.gate_log import DATASET as GATE_EVENTS
from console.core.gate_log import EVENT_DTYPE as GATE_EVENT_DTYPE
from console.core.gate_log import GateLog
from console.core.gate_log import counts_text as gate_events_text
from console.core.gate_log import read_rows as read_gate_events
from console.core.hookspecs import hookimpl
from console.core.options import (
    BadValue,
    Parser,
    finite_float,
    from_field,
    host_name,
    integer,
    minutes,
    port,
    positive_int,
    seconds,
    seed,
)
from console.core.plan_watch import (
    WatchedOutputs,
    json_values,
    plan_hash,
    plan_line,
    plan_record,
    report_clocks,
)
from console.core.realtime import realtime_priority, support_priority
from console.core.schema import KINDS, Field, check, path_problem
from console.core.stall_witness import ORIGINS, StallWitness
from console.core.time_left import JobLeft, left_words
from console.core.types import (
    DIRECTIONS,
    DIRECTIONS_MM,
    EXCITATIONS,
    PATCHES,
    Contact,
    DeviceStatus,
    Frame,
    Gesture,
    GestureScript,
    GestureStep,
    Hand,
    HandShape,
    OutputDevice,
    OutputPlan,
    PlanInfo,
    PlanPart,
    Segment,
    TunableRange,
    patches_of,
)
from console.core.words import AT_CLI, AT_CONSOLE, OFF_LOOP, Placed, counted, listing, worded
from console.files.atomic import append_json_line, write_text_atomic
from console.files.cache_files import cached_arrays, entry_path, input_hash
from console.files.file_read import parse_toml_text, read_bytes_capped
from console.files.json_lines import MAX_DEPTH as MAX_JSON_DEPTH
from console.files.json_lines import decode, parse_json, read_json_lines, torn
from console.files.npz_safe import json_depth, npz_keys, read_npz
from console.files.paths import cache_dir, data_dir
from console.files.vibration_map import (
    FIX,
    KEYS,
    MAX_FRF_UM_PER_V,
    VibrationMap,
    grid_points_mm,
    load_map,
    make_map,
    map_from_arrays,
    save_map,
)
from console.safety.limits import Limits
from console.signals.stream_synth import (
    Envelope,
    PulseSpec,
    StreamSink,
    StreamSpec,
    StreamSynth,
    smooth_square,
    spec_problem,
)
from console.signals.waveforms import MAX_PLAN_S, check_duration, plan_samples, tone

__all__ = [
    # the time left, by the console's one rule (``console.core.time_left``)
    "JobLeft",
    "left_words",
    # errors, and their fix where the user is
    "EStopped",
    "SafetyRefusal",
    "TableBusy",
    "UserError",
    "InputSpec",
    "find_input",
    "input_specs",
    "AT_CLI",
    "AT_CONSOLE",
    "Placed",
    "listing",
    "counted",
    "worded",
    "OFF_LOOP",
    # values (console.core.types)
    "DIRECTIONS",
    "DIRECTIONS_MM",
    "EXCITATIONS",
    "PATCHES",
    "Contact",
    "DeviceStatus",
    "Frame",
    "Gesture",
    "GestureScript",
    "GestureStep",
    "Hand",
    "HandShape",
    "OutputDevice",
    "OutputPlan",
    "PlanInfo",
    "PlanPart",
    "Segment",
    "TunableRange",
    "patches_of",
    # capabilities (console.core.contracts)
    "AdjustableCamera",
    "BeginsRun",
    "WatchesOutputs",
    "BlockSource",
    "Classifier",
    "Conditions",
    "FlowEffect",
    "FlowPatchDrives",
    "HandFlowEffect",
    "HandFlowGeometry",
    "KnobTrials",
    "PrecomputedHandFlows",
    "Presets",
    "SimulatedCamera",
    "SimulatedObserver",
    "VisionResult",
    # hooks, plugin manager, profile
    "hookimpl",
    "PanelTab",
    "Plugins",
    "load_plugins",
    "Profile",
    "load_profile",
    "profile_file",
    "save_overrides",
    # settings schema, CLI options
    "KINDS",
    "Field",
    "check",
    "path_problem",
    "BadValue",
    "Parser",
    "finite_float",
    "from_field",
    "host_name",
    "integer",
    "minutes",
    "port",
    "positive_int",
    "seconds",
    "seed",
    # safety
    "Limits",
    # outputs: channels, plans, live streams
    "BUS_CHANNELS",
    "ChannelLayout",
    "MAX_PLAN_S",
    "check_duration",
    "plan_samples",
    "tone",
    "Envelope",
    "PulseSpec",
    "StreamSink",
    "StreamSpec",
    "StreamSynth",
    "smooth_square",
    "spec_problem",
    # the vibration map
    "FIX",
    "KEYS",
    "MAX_FRF_UM_PER_V",
    "VibrationMap",
    "grid_points_mm",
    "load_map",
    "make_map",
    "map_from_arrays",
    "save_map",
    # files
    "append_json_line",
    "WatchedOutputs",
    "json_values",
    "GateLog",
    "GATE_EVENTS",
    "GATE_EVENT_DTYPE",
    "gate_events_text",
    "read_gate_events",
    "plan_hash",
    "plan_line",
    "plan_record",
    "report_clocks",
    "write_text_atomic",
    "parse_toml_text",
    "read_bytes_capped",
    "read_json_lines",
    "decode",
    "parse_json",
    "torn",
    "MAX_JSON_DEPTH",
    "json_depth",
    "npz_keys",
    "read_npz",
    "cache_dir",
    "data_dir",
    "cached_arrays",
    "entry_path",
    "input_hash",
    # real time, benchmarks
    "realtime_priority",
    "support_priority",
    "ORIGINS",
    "StallWitness",
    "machine_info",
    "device_buffer_latency_s",
    "device_buffer_periods",
    "summarize_s",
]
