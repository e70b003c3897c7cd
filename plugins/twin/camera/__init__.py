"""Camera twin plugin: a rear-DI infrared camera of hands on the table (paper Sec. 2-3).

Registers the camera driver ``twin`` (``[camera] driver = "twin"``) and the profile
section ``[twin_camera]``. Other plugins reach it only through that registration: the
camera it builds is a ``console.core.contracts.SimulatedCamera`` (``set_script(GestureScript)``
for a scripted hand on the stream, as the demos do; ``render_sample`` and
``render_background`` offline, as ``gestures synth`` does, with ``mapping``).

Within this plugin (each module imported where used: numpy/cv2 load with them):

- ``sample.render_sample(gesture, subject, rep, rng, ...) -> (frames, truth)``: one
  gesture performance as uint8 frames with per-frame ground truth.
- ``camera.TwinCamera``: the streaming camera (``read``/``status``/``close``), with scripts
  (``IdleScript``, ``SequenceScript``, ``TouchScript``, ``demo_script``), ``perform()``
  and ``set_target()`` (touch calibration), and ``truth`` of the last frame.
- ``render.Rig``, ``geometry.TableMapping``: the camera set-up and the explicit mm <-> px
  mapping; ``factory.make_camera(profile)``: the camera a profile describes.
- ``gestures.GESTURES``, ``STATIC``, ``DYNAMIC``; ``sample.HARD_CASES``.
"""

from __future__ import annotations

from console.plugin_api import hookimpl

from .factory import make_camera, probe
from .settings import FIELDS, SECTION


@hookimpl
def haptable_profile_sections(register) -> None:
    register(SECTION, FIELDS, help="the camera twin (used when [camera] driver = 'twin')")


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def run(ctx, quick: bool) -> dict:
        from .bench import run as bench  # lazy: numpy and cv2 load when the bench runs

        return bench(ctx, quick)

    register("twin-camera", run, help="camera twin: frame and sample render time")


@hookimpl
def haptable_register_cameras(register) -> None:
    register(
        "twin",
        make_camera,
        description="rear-DI IR camera twin: scripted hands, ground truth, 640 x 480 at 60 fps",
        probe=probe,
    )
