"""``casa bench``: one simulated participant's whole protocol, and its learning, timed.

:func:`participant_benchmark` runs the simulated study's protocol
(:mod:`casa_core.study.simulate`: the trials before learning and the demonstrations,
learning each unknown task's intent, the trials after learning) for a few
participants of the study's config (:func:`casa_core.study.simulate.simulate_protocol`,
as the power target's jobs run it) in a temporary folder, and measures the CPU
time of this process for each participant's protocol (``participant_cpu_s``) and for
each learning step in it (``irl_s``: reading the 5 demonstrations, deep max-ent IRL,
saving the intent and planning its optimum for ``learning.csv``; slightly more than
the IRL alone). The power analysis runs this protocol once per simulated participant,
so ``participant_cpu_s`` is its cost per participant on one core. Where that time goes
is measured in the same run (:data:`~casa_core.bench.stages.PROTOCOL_STAGES`): the
protocol's trials, its learning, its logging and the rest, in CPU seconds
(``protocol_split_s``, medians over the participants).

:data:`TARGETS` holds the targets of every benchmark; :func:`target_met` judges one.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from casa_core.scene import Scene

#: Target of each benchmark key: (comparison, bound). Medians, CPU time of one core.
TARGETS = {
    "participant_cpu_s": ("<=", 5.0),
    "irl_s": ("<=", 2.0),
    "trial_realtime_factor": (">=", 300.0),
    "trial_cost_over_physics": ("<=", 2.0),
    "step_us_neural1": ("<=", 2000.0),
    "step_us_goal3": ("<=", 100.0),
}


def target_met(key: str, value) -> bool | None:
    """Whether ``value`` meets the target of ``key`` (None without a value or target).

    Examples
    --------
    >>> target_met("irl_s", 1.5), target_met("trial_realtime_factor", 250.0)
    (True, False)
    >>> target_met("irl_s", None) is None
    True
    """
    if key not in TARGETS or value is None:
        return None
    comparison, bound = TARGETS[key]
    return bool(value <= bound) if comparison == "<=" else bool(value >= bound)


def participant_benchmark(scene: Scene, *, config: dict, participants=(0,)) -> dict:
    """CPU seconds of each participant's protocol and of each learning step in it.

    Parameters
    ----------
    scene : Scene
        The task scene.
    config : dict
        A validated workflow config (:func:`casa_core.config.load_config`), read once
        into :class:`~casa_core.study.settings.StudySettings`, as ``casa simulate`` does.
    participants : sequence of int
        0-based participant indices to run.

    Returns
    -------
    dict
        ``participant_cpu_s`` and ``irl_s`` (medians), ``participant_cpu_s_all`` and
        ``irl_s_all`` (every measurement), and ``protocol_split_s``: per stage
        (``trials``, ``learning``, ``logging``, ``rest``) the median CPU seconds.
    """
    from casa_core.bench.stages import PROTOCOL_STAGES, StageClock
    from casa_core.study import simulate
    from casa_core.study.settings import StudySettings
    from casa_core.vocabulary import UNKNOWN_TASKS

    settings = StudySettings.from_config(config)  # read once, here, at the edge
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # one core, as in the targets
    totals, learning, splits = [], [], []
    try:
        for index in participants:
            with tempfile.TemporaryDirectory() as folder:
                work = Path(folder)
                start = time.process_time()
                with StageClock(PROTOCOL_STAGES) as clock:
                    run = simulate.simulate_protocol(
                        index,
                        scene,
                        settings=settings,
                        before_dir=work / "before",
                        after_dir=work / "after",
                        libraries={task: work / "intents" / task for task in UNKNOWN_TASKS},
                    )
                learning += run.learning_cpu_s
                totals.append(time.process_time() - start)
                stages = {stage: clock.seconds[stage] for _, _, stage in PROTOCOL_STAGES}
                splits.append({**stages, "rest": totals[-1] - sum(stages.values())})
    finally:
        torch.set_num_threads(threads)
    return {
        "participant_cpu_s": float(np.median(totals)),
        "irl_s": float(np.median(learning)),
        "participant_cpu_s_all": totals,
        "irl_s_all": learning,
        "protocol_split_s": {
            stage: float(np.median([split[stage] for split in splits])) for stage in splits[0]
        },
    }
