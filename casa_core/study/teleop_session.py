"""The GUI session of ``casa teleop``: a person's trial in a window, then any demonstrations.

:func:`run_teleop` opens the pybullet window (:mod:`casa_core.robot.teleop`), runs one
trial through the same closed loop as the simulated study
(:func:`casa_core.study.closed_loop.run_trial`) and writes its casa-trial/1 log.
:func:`teleop_session` adds the protocol's step after a CASA trial before learning:
when misspecification is detected it asks for demonstrations and records them.
"""

from __future__ import annotations

from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path

from casa_core.assist.presets import DEFAULT_PRESET, Preset
from casa_core.defaults import DEMONSTRATIONS, EPSILON
from casa_core.io import SCHEMA, check_meta, read_trial
from casa_core.io.contract import TRIAL_SUFFIXES
from casa_core.robot.sim import ArmSimulation
from casa_core.robot.teleop import KeyboardKeys, Window
from casa_core.scene import Scene
from casa_core.study.closed_loop import default_phase, run_trial
from casa_core.study.command_sources import DeviceCommands
from casa_core.study.key_sources import KeySource
from casa_core.study.protocol import TrialSpec, demonstrations, misspecification_detected
from casa_core.vocabulary import TASK_LABELS


def run_teleop(
    scene: Scene,
    task: str,
    method: str,
    participant: str,
    out: Path | str,
    *,
    phase: str | None = None,
    gui: bool = True,
    key_source=None,
    countdown: int = 3,
    realtime: bool = True,
    max_duration: float = 60.0,
    intents=None,
    repeat: int = 0,
    title: str | None = None,
    inference: Preset | str = DEFAULT_PRESET,
    assistant_options: dict | None = None,
    device=None,
    input: str = "keyboard",
) -> Path:
    """Run one teleoperated trial and write its log; return the log's stem.

    The log goes to ``OUT/<task>_<phase>_<method>`` (``_<repeat + 1>`` added for a
    demonstration), the protocol's naming (:class:`casa_core.study.protocol.TrialSpec`).

    Parameters
    ----------
    scene : Scene
        The task scene.
    task, method, participant, phase :
        As in :func:`casa_core.study.closed_loop.run_trial`.
    out : path
        Folder of the log (created); an existing log there is never overwritten.
    gui : bool
        Open a window; False runs headless (tests).
    key_source : KeySource, optional
        Default the window's keyboard (:class:`~casa_core.robot.teleop.KeyboardKeys`); a
        scripted source makes the trial reproducible and its log's source "simulated".
    countdown : int
        Seconds of countdown before the trial starts.
    realtime : bool
        Pace the loop at 20 Hz in the window (off for tests).
    max_duration : float
        Seconds after which the trial ends if Enter was not pressed.
    intents : sequence of Intent, optional
        What the robot knows; default the known goals green and purple.
    repeat : int
        Which demonstration this is (0-based), for the log's name.
    title : str, optional
        Shown in the window before the countdown; default the task's name (never the
        method's).
    inference : Preset or str, default "casa"
        The inference preset (:mod:`casa_core.assist.presets`).
    assistant_options : dict, optional
        Extra keyword arguments of :class:`~casa_core.assist.assistant.Assistant`.
    device : Device, optional
        An open continuous device (:func:`casa_core.robot.devices.open_device`) of kind
        ``input``, read in place of the keyboard (whose Enter still ends the trial).
    input : str
        The device's kind, written to the log's ``input``.

    Raises
    ------
    TrialCutShort
        If the device was lost mid-trial: the arm was stopped and the trial written as
        far as it ran.
    FileExistsError
        If the log already exists in ``out``.
    ValueError
        If task, method, phase or participant would not make a casa-trial/1 log.
    """
    phase = default_phase(task) if phase is None else phase
    stem = Path(out) / TrialSpec(task, method, phase, repeat).stem
    source_kind = "human" if key_source is None else "simulated"
    # Refuse before the person starts, not after: the log must be writable.
    planned = {"schema": SCHEMA, "participant": participant, "task": task, "method": method}
    problems = check_meta({**planned, "phase": phase, "source": source_kind}, f"{stem}.json")
    if problems:
        raise ValueError("cannot run this trial: " + "; ".join(str(x) for x in problems))
    for suffix in TRIAL_SUFFIXES:
        if stem.with_suffix(suffix).exists():
            raise FileExistsError(
                f"{stem.with_suffix(suffix)} exists; logs are never overwritten: "
                "choose another --out or move the old log"
            )
    with ArmSimulation(scene, gui=gui) as sim:
        window = Window(sim, realtime)
        source = _source(sim, key_source, device, input)
        # The method is not shown: the participant must not know which one drives.
        window.intro(title or TASK_LABELS[task], countdown)
        started = datetime.now(UTC).isoformat(timespec="seconds")
        result = run_trial(
            scene,
            task,
            method,
            source,
            participant=participant,
            intents=intents,
            phase=phase,
            source_kind=source_kind,
            max_duration=max_duration,
            sim=sim,
            inference=inference,
            assistant_options=assistant_options,
            on_tick=window.on_tick,
        )
        result.meta["started_at"] = started
        lost = getattr(source, "lost", None)
        if lost:
            result.meta["notes"] = f"ended early, the arm stopped: {lost}"
        result.write(stem)
        window.finish(f"saved {stem.name}")
    if lost:
        raise TrialCutShort(
            f"{lost}: the arm was stopped and the trial kept as far as it ran, in "
            f"{stem}.json and {stem}.csv"
        )
    return stem


class TrialCutShort(RuntimeError):
    """A trial ended early because its device was lost; its log was written."""


def _source(sim: ArmSimulation, key_source, device, input: str):
    """The trial's source: a given key source, the device, or the window's keyboard."""
    if key_source is not None:
        return key_source
    if device is None:
        return KeyboardKeys(sim.client)
    keyboard = KeyboardKeys(sim.client) if sim.gui else None  # Enter, in a window
    return DeviceCommands.in_scene(device, sim.scene, input=input, keyboard=keyboard)


def teleop_session(
    scene: Scene,
    task: str,
    method: str,
    participant: str,
    out: Path | str,
    *,
    n_demonstrations: int = DEMONSTRATIONS,
    epsilon: float = EPSILON,
    make_key_source: Callable[[], KeySource] | None = None,
    **options,
) -> tuple[list[Path], bool]:
    """A teleoperated trial and, if CASA finds its intents misspecified, the demonstrations.

    After a CASA trial of the ``before_learning`` phase in which every known
    intent's beta_hat stayed below ``epsilon`` at the end
    (:func:`casa_core.study.protocol.misspecification_detected`), the robot asks the
    person, in the window, for ``n_demonstrations`` demonstrations of the task
    without assistance, and records each (phase ``demonstration``, method NA),
    as the protocol does for simulated participants.

    Parameters
    ----------
    make_key_source : callable, optional
        Makes the key source of each trial; default the window's keyboard.
    **options
        Passed to :func:`run_teleop` for every trial (``phase``, ``gui``,
        ``countdown``, ``realtime``, ``max_duration``, ``intents``, ``inference``,
        ``assistant_options``).

    Returns
    -------
    stems : list of Path
        The logs written, the trial's first.
    detected : bool
        Whether misspecification was detected (and demonstrations recorded).
    """

    def source():
        return None if make_key_source is None else make_key_source()

    stem = run_teleop(scene, task, method, participant, out, key_source=source(), **options)
    stems = [stem]
    _, frame = read_trial(stem)
    phase = options.get("phase") or default_phase(task)
    detected = (
        method == "CASA"
        and phase == "before_learning"
        and n_demonstrations > 0
        and misspecification_detected(frame, epsilon)
    )
    if detected:
        demo_options = {**options, "phase": "demonstration", "intents": None}
        for spec in demonstrations(task, n_demonstrations):
            title = (
                "The robot could not tell what you wanted. Please show it: "
                f"demonstration {spec.repeat + 1} of {n_demonstrations}, no assistance"
            )
            stems.append(
                run_teleop(
                    scene,
                    task,
                    "NA",
                    participant,
                    out,
                    key_source=source(),
                    repeat=spec.repeat,
                    title=title,
                    **demo_options,
                )
            )
    return stems, detected
