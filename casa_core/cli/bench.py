"""``casa bench``: time the assistance step and a whole simulated trial."""

from __future__ import annotations

from casa_core.cli._options import example, nonnegative_int, scene_option


def register(commands) -> None:
    """Add ``casa bench`` to the ``casa`` subcommands."""
    command = commands.add_parser(
        "bench",
        help="time the assistance step and a whole simulated trial",
        description="Print a table and notes on reading it; with --json, also one JSON object "
        "on the last line with step_us_goal3, step_us_neural1, scaling (n_intents, step_us, "
        "assisting), trial_realtime_factor, trial_realtime_factor_wall, "
        "trial_realtime_factor_new_sim, trial_physics_realtime_factor (the same trial's "
        "pybullet calls alone), trial_cost_over_physics (the trial's CPU over theirs), "
        "participant_cpu_s, irl_s (and their _all lists), protocol_split_s (trials, "
        "learning, logging, rest) and targets_met (CPU time of one thread or process; see "
        "casa_core.bench.suite).",
        **example("casa bench --json | tail -n 1 > bench.json"),
    )
    command.add_argument("--json", action="store_true", help="print the JSON line last")
    scene_option(command)
    command.add_argument("--seed", type=nonnegative_int, default=0, help="seed (default 0)")
    command.add_argument(
        "--participants",
        type=nonnegative_int,
        default=3,
        help="simulated participants whose whole protocol is timed (default 3; 0 skips it)",
    )
    command.set_defaults(func=_bench)


def _bench(args) -> int:
    import json

    import torch

    from casa_core.bench import suite as bench
    from casa_core.config import load_config
    from casa_core.scene import load_scene

    scene = load_scene(args.scene)  # a SceneError is reported by casa_core.cli.main
    torch.set_num_threads(1)  # the targets are for one core
    results = bench.run_benchmarks(
        scene,
        seed=args.seed,
        config=load_config() if args.participants else None,  # the package's defaults
        participants=tuple(range(args.participants)),
    )
    print(bench.format_table(results))
    if args.json:
        print(json.dumps(results))
    return 0
