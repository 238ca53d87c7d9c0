"""Intermittent control of the predictive operator: bouts, pauses and planning.

Closed-loop Known Goal trials without assistance, by the study's first three participants
(config/config.yaml, seed 2021) on their own random streams, with and without each
parameter of intermittent control (docs/departures.md, "Simulated operators").
"""

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from casa_core.analysis import effort
from casa_core.assist.tasks import intended_trajectory
from casa_core.config import load_config
from casa_core.scene import load_scene
from casa_core.study import simulate
from casa_core.study.closed_loop import run_trial
from casa_core.study.participants import (
    BOUT,
    PredictiveParticipant,
    draw_participants,
    make_participant,
)
from casa_core.study.settings import Lognormal, StudySettings

SETTINGS = StudySettings.from_config(load_config("config/config.yaml"))
SCENE = load_scene()
REFERENCE = intended_trajectory("known_goal", SCENE)
PARTICIPANTS = range(3)


def params_of(index, **intermittent):
    params = simulate.participant_params(index, SETTINGS.seed, SETTINGS.population)
    return dataclasses.replace(params, **intermittent)


def run(sim, index, source=None, **intermittent):
    """The trial's frame and the participant that made it (``source``, or made here)."""
    if source is None:
        rng = np.random.default_rng([2021, index, 1])
        source = make_participant(
            params_of(index, **intermittent), REFERENCE, rng=rng, operator="predictive"
        )
    frame = run_trial(
        SCENE, "known_goal", "NA", source, participant="p", sim=sim, max_duration=40.0
    ).frame
    return frame, source


def measures(frame):
    """Presses per second, the share of ticks with a key held, the first press's time."""
    keys = frame["keys"].fillna("").tolist()
    held = np.array([bool(cell.split()) for cell in keys])
    duration = float(frame["t"].iloc[-1])
    return effort.key_presses(keys) / duration, held.mean(), float(frame["t"][held.argmax()])


def test_the_operator_of_bout_1_s_without_pause_or_planning_is_the_operator_without_them(sim):
    # The same logs, and the same random stream left over: no draw is added.
    old, old_source = run(sim, 0)
    params = params_of(0)
    explicit = PredictiveParticipant(
        params, REFERENCE, rng=np.random.default_rng([2021, 0, 1]), bout=BOUT, pause=0, planning=0
    )
    new, new_source = run(sim, 0, explicit)
    pd.testing.assert_frame_equal(old, new)
    assert old_source.rng.bit_generator.state == new_source.rng.bit_generator.state
    fields, _ = run(sim, 0, bout=1.0, pause=0.0, planning=0.0)
    pd.testing.assert_frame_equal(old, fields)


def test_a_population_without_intermittent_control_draws_what_it_drew_and_with_it_draws_last():
    population = SETTINGS.population
    assert population.bout is None and population.pause is None and population.planning is None
    with_them = dataclasses.replace(
        population, bout=Lognormal(2.0, 0.3), pause=Lognormal(0.5, 0.3), planning=Lognormal(1, 0)
    )
    plain = draw_participants(3, population, np.random.default_rng(5))
    drawn = draw_participants(3, with_them, np.random.default_rng(5))
    assert [(p.bout, p.pause, p.planning) for p in plain] == [(BOUT, 0.0, 0.0)] * 3
    strip = {"bout": BOUT, "pause": 0.0, "planning": 0.0}
    assert [dataclasses.replace(p, **strip) for p in drawn] == plain
    assert all(p.planning == 1.0 and p.bout != BOUT and p.pause > 0 for p in drawn)


def test_a_longer_pause_gives_fewer_presses_and_fewer_ticks_with_a_key_held(sim):
    # Measured: 2.7-3.1 presses/s and 64-74% of ticks held without a pause; 1.6-1.7/s
    # and 41-43% with a pause of 1 s.
    for index in PARTICIPANTS:
        rate, share, _ = measures(run(sim, index)[0])
        paused_rate, paused_share, _ = measures(run(sim, index, pause=1.0)[0])
        assert paused_rate < 0.8 * rate, (index, paused_rate, rate)
        assert paused_share < 0.8 * share, (index, paused_share, share)


def test_planning_delays_the_first_press_by_its_length(sim):
    # Closed form: no press before the reaction time (the first sight) plus the planning;
    # the first press comes at the first tick after it (a tick is 0.05 s).
    for index in PARTICIPANTS:
        params = params_of(index)
        _, _, first = measures(run(sim, index)[0])
        _, _, planned = measures(run(sim, index, planning=1.5)[0])
        assert planned >= params.reaction_time + 1.5 - 1e-9, (index, planned)
        assert abs(planned - first - 1.5) <= 0.1, (index, planned, first)


def test_without_a_bout_limit_the_operator_never_lets_go_to_look(sim):
    # bout = inf and no pause: continuous control, no watch at any tick; the default
    # bout watches at least once in the same trial.
    frame, continuous = run(sim, 0, bout=math.inf)
    assert continuous._watch_until == -np.inf
    _, intermittent = run(sim, 0)
    assert intermittent._watch_until > 0
    _, share, _ = measures(frame)
    assert share > 0.9, share


@pytest.mark.parametrize(
    ("option", "match"),
    [
        ({"bout": 0}, "bout = 0 s"),
        ({"pause": -0.5}, "pause = -0.5 s"),
        ({"planning": math.nan}, "planning = nan s"),
        ({"pause": math.inf}, "pause = inf s"),
    ],
)
def test_invalid_intermittent_control_is_refused_naming_the_parameter(option, match):
    with pytest.raises(ValueError, match=match):
        PredictiveParticipant(params_of(0), REFERENCE, rng=np.random.default_rng(0), **option)
