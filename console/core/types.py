"""Values that cross plugin boundaries: plain frozen dataclasses and numpy arrays.

Units are in the names: ``_mm`` table millimetres from the glass corner (x along the
long edge, y along the short edge), ``_px`` camera pixels, ``_s`` seconds on the
``time.monotonic()`` clock, ``_v`` volts at the actuator, ``_hz`` hertz.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, TypedDict, get_type_hints

import numpy as np

#: Names of the piezo excitations. ``PALL`` means the four patches in parallel.
PATCHES: tuple[str, ...] = ("PA", "PB", "PC", "PD")
EXCITATIONS: tuple[str, ...] = (*PATCHES, "PALL")


#: Flow directions as unit vectors in table millimetres. The projected image shows the
#: glass with y growing downwards (grid point 1, at the smallest x and y, is top left, as
#: in the paper's Fig. 5b), so "up" on the projection is toward -y: an arrow and the flow
#: it triggers point the same way.
DIRECTIONS_MM: dict[str, tuple[float, float]] = {
    "left": (-1.0, 0.0),
    "right": (1.0, 0.0),
    "up": (0.0, -1.0),
    "down": (0.0, 1.0),
}
#: The flow directions in the order hand-flow maps and their caches index them.
DIRECTIONS: tuple[str, ...] = tuple(DIRECTIONS_MM)


def patches_of(excitation: str) -> frozenset[str]:
    """The patches whose relays close for an excitation name (``PALL`` -> all four)."""
    if excitation == "PALL":
        return frozenset(PATCHES)
    if excitation in PATCHES:
        return frozenset({excitation})
    raise ValueError(f"unknown excitation {excitation!r}: use one of {', '.join(EXCITATIONS)}")


# --------------------------------------------------------------------------- camera
@dataclass(frozen=True)
class Frame:
    """One camera image. ``stamps_s`` collects the time each pipeline stage finished."""

    image: np.ndarray  # (H, W) uint8, rear-DI infrared
    seq: int
    t_capture_s: float
    source: str = ""
    stamps_s: dict[str, float] = field(default_factory=dict, compare=False)

    def stamp(self, stage: str, t_s: float) -> None:
        """Record when ``stage`` finished with this frame (the latency monitor reads it)."""
        self.stamps_s[stage] = t_s


@dataclass(frozen=True)
class Contact:
    """A touching fingertip or blob."""

    id: int
    pos_px: tuple[float, float]
    pos_mm: tuple[float, float] | None = None
    area_px: float = 0.0


class HandShape:
    """A hand's outline descriptors and finger count: given (``HandShape.of``), or made
    by ``make`` when first read. The vision finds them for every hand; only a gesture
    decision's first frames and a screen showing the count read them, so a frame loop
    does not pay for them on every frame. Pickles as its values."""

    __slots__ = ("_make", "_value")

    def __init__(self, make: Callable[[], tuple[np.ndarray, int]]) -> None:
        self._make: Callable[[], tuple[np.ndarray, int]] | None = make
        self._value: tuple[np.ndarray, int] | None = None

    @classmethod
    def of(cls, descriptors: np.ndarray, finger_count: int) -> HandShape:
        shape = cls(lambda: (descriptors, finger_count))
        shape.value()
        return shape

    def value(self) -> tuple[np.ndarray, int]:
        """(descriptors, finger count), made on the first call."""
        if self._value is None:
            assert self._make is not None
            desc, count = self._make()
            self._value, self._make = (np.asarray(desc), int(count)), None
        return self._value

    @property
    def known(self) -> bool:
        """Whether the values are made (read once, or given)."""
        return self._value is not None

    def __reduce__(self):
        return (HandShape.of, self.value())

    def __repr__(self) -> str:
        return f"HandShape(finger_count={self.value()[1]})" if self.known else "HandShape(...)"


@dataclass(frozen=True)
class Hand:
    """A segmented hand: its outline, canonical pose and shape (``descriptors``,
    ``finger_count``: see ``HandShape``)."""

    contour_px: np.ndarray  # (N, 2) float
    center_px: tuple[float, float]
    radius_px: float
    angle_deg: float  # rotation that brings the hand to the canonical orientation
    shape: HandShape = field(compare=False)
    contacts: tuple[Contact, ...] = ()
    center_mm: tuple[float, float] | None = None

    @property
    def descriptors(self) -> np.ndarray:
        """Invariant Fourier descriptors of the canonical outline."""
        return self.shape.value()[0]

    @property
    def finger_count(self) -> int:
        """Fingers spread from the palm."""
        return self.shape.value()[1]


GestureKind = Literal["static", "dynamic"]


@dataclass(frozen=True)
class Gesture:
    """A recognised gesture."""

    name: str
    kind: GestureKind
    confidence: float
    t_s: float
    hand: Hand | None = None


# --------------------------------------------------------------------------- outputs
@dataclass(frozen=True)
class Segment:
    """A stretch of output in volts at the actuators, every channel the same length.

    ``piezo_v`` is the paper's piezo bus: it reaches every patch in ``patches`` (their
    relays are closed while it plays). ``patch_v`` gives patches drives of their own
    (``{"PA": (n,), "PC": (n,)}``); its patches join ``patches``, and a patch in
    ``patches`` without an entry plays ``piezo_v``. A profile whose ``[audio] channels``
    drive each patch on its own plays every drive on its patch's channel; a bus profile
    plays a segment only when all its drives are equal (``bus_drive()``). ``screen`` says
    whether the screen relay is closed. Relays change only in the silent gap between
    segments (the safety gate enforces it).
    """

    piezo_v: np.ndarray  # (n,) float, volts at the patch terminals
    screen_v: np.ndarray  # (n,) float, volts at the screen electrode
    patches: frozenset[str] = frozenset()
    screen: bool = False
    label: str = ""
    patch_v: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        drives = dict(self.patch_v or {})
        object.__setattr__(self, "patch_v", drives)
        object.__setattr__(self, "patches", frozenset(self.patches) | frozenset(drives))

    @classmethod
    def per_patch(
        cls,
        patch_v: Mapping[str, np.ndarray],
        screen_v: np.ndarray | None = None,
        *,
        screen: bool = False,
        label: str = "",
    ) -> Segment:
        """A segment with a drive per patch (the bus silent), e.g. from the per-patch
        amplitude/phase solver. Every drive and ``screen_v`` must have the same length."""
        if not patch_v:
            raise ValueError("a per-patch segment needs at least one patch drive")
        n = len(next(iter(patch_v.values())))
        sv = np.zeros(n) if screen_v is None else screen_v
        return cls(np.zeros(n), sv, frozenset(), screen, label, dict(patch_v))

    @property
    def n_samples(self) -> int:
        return int(len(self.piezo_v))

    @property
    def independent(self) -> bool:
        """True when some patch has a drive of its own (``patch_v``)."""
        return bool(self.patch_v)

    def drives(self) -> dict[str, np.ndarray]:
        """Each connected patch's drive in volts, by patch name (sorted)."""
        return {p: self.patch_v.get(p, self.piezo_v) for p in sorted(self.patches)}

    def bus_drive(self) -> np.ndarray | None:
        """The one drive every connected patch plays (what a bus profile's piezo channel
        plays), or ``None`` when the patches' drives differ."""
        if not self.patch_v:
            return self.piezo_v
        drives = list(self.drives().values())
        first = np.asarray(drives[0])
        if all(np.array_equal(first, np.asarray(d)) for d in drives[1:]):
            return first
        return None


@dataclass(frozen=True)
class OutputPlan:
    """Timed segments an effect asks to play, with a silent gap between them."""

    sample_rate_hz: int
    segments: tuple[Segment, ...]
    name: str = ""
    gap_s: float = 0.0  # extra silence between segments beyond the relay guard gap
    meta: dict[str, Any] = field(default_factory=dict, compare=False)  # a ``PlanInfo``

    def __post_init__(self) -> None:
        # a plan is a value: a changed plan is a new plan (the gate plays what it checked)
        object.__setattr__(self, "segments", tuple(self.segments))

    @property
    def duration_s(self) -> float:
        return sum(s.n_samples for s in self.segments) / self.sample_rate_hz


class PlanPart(TypedDict, total=False):
    """One part of a plan as its effect describes it: the patch it drives
    (``actuator``), at ``frequency_hz`` and ``amplitude_v`` (peak), the map's
    displacement per volt there (``um_per_v``), the 3-JND line (``x_um``) and the margin
    over it (``margin_db``)."""

    actuator: str
    frequency_hz: float
    amplitude_v: float
    um_per_v: float
    x_um: float
    margin_db: float


class PlanInfo(PlanPart, total=False):
    """What an effect says of its plan (``OutputPlan.meta``), the keys the console reads:
    ``kind`` (``point``, ``flow``, ``hand_flow``, ``two_point`` ...), ``method`` (how it
    was rendered: ``paper``, ``independent`` ...), ``rule`` (the tables' rule, when it
    used them), ``predicted_contrast_db`` (active over passive; of a flow in parts the
    weaker part's) and ``parts`` (``PlanPart``, in playing order). A one-part plan (a
    point) carries its part's keys at the top level. An effect may add keys of its own;
    the console reads none of them."""

    kind: str
    method: str
    rule: str
    predicted_contrast_db: float
    parts: list[PlanPart]


def plan_parts(meta: PlanInfo) -> list[PlanPart]:
    """The parts a plan's ``meta`` describes (a one-part plan: itself)."""
    return list(meta.get("parts") or [meta])


def plan_info_problems(meta: dict[str, Any]) -> list[str]:
    """Where ``meta`` disagrees with ``PlanInfo``: a declared key of another type
    (numbers may be ints; ``parts`` a list or tuple of ``PlanPart``)."""
    out = []
    hints = get_type_hints(PlanInfo)
    part_hints = get_type_hints(PlanPart)
    want = {str: (str,), float: (int, float)}
    for key, hint in hints.items():
        if key not in meta or key == "parts":
            continue
        if not isinstance(meta[key], want[hint]) or isinstance(meta[key], bool):
            out.append(f"{key}: {type(meta[key]).__name__}, not {hint.__name__}")
    parts = meta.get("parts", ())
    if not isinstance(parts, list | tuple):
        return [*out, f"parts: {type(parts).__name__}, not a list"]
    for i, part in enumerate(parts):
        for key, hint in part_hints.items():
            if key in part and not isinstance(part[key], want[hint]):
                out.append(f"parts[{i}].{key}: {type(part[key]).__name__}, not {hint.__name__}")
    return out


@dataclass(frozen=True)
class TunableRange:
    """Where a tunable may go (``min_value`` .. ``max_value``) and one operator step."""

    min_value: float
    max_value: float
    step: float

    def clamp(self, value: float) -> float:
        return min(self.max_value, max(self.min_value, float(value)))


# --------------------------------------------------------------------------- devices
@dataclass(frozen=True)
class DeviceStatus:
    """One line of ``haptable doctor``."""

    kind: str
    name: str
    state: Literal["ok", "missing", "error", "simulated"]
    why: str = ""
    fix: str = ""


@dataclass(frozen=True)
class OutputDevice:
    """A device an audio output driver can open, as the Devices screen lists it; ``name``
    is what ``[audio] device`` takes to pick it. ``note`` says why it cannot be used
    (too few output channels), empty when it can."""

    driver: str
    name: str
    host_api: str = ""
    output_channels: int = 0
    low_latency_s: float = float("nan")  # the device's default low / high output latency
    high_latency_s: float = float("nan")
    default: bool = False  # the system's default output
    note: str = ""


# --------------------------------------------------------------------------- simulation
@dataclass(frozen=True)
class GestureStep:
    """One gesture a scripted hand performs: ``gesture`` (a name the camera knows, e.g.
    ``open_hand``, ``rotate``), whose hand (``subject`` name, seeded by the camera),
    which hand (``side`` = ``"left"``/``"right"``, ``None``: the subject's dominant one)
    and for how many camera frames (``frames``; ``None``: the camera's default)."""

    gesture: str
    subject: str = "s1"
    side: str | None = None
    frames: int | None = None


@dataclass(frozen=True)
class GestureScript:
    """What a simulated camera shows: ``steps`` in turn, ``gap_frames`` of empty table
    before each, looping if ``loop``; ``seed`` seeds the performance's variations.

    A camera that can act scripts out is a ``console.core.contracts.SimulatedCamera``
    (the camera twin); a real camera is not (the operator's hand does it).
    """

    steps: tuple[GestureStep, ...]
    gap_frames: int = 30
    loop: bool = True
    seed: int = 0
