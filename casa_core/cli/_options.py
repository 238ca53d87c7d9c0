"""Options and help text that several ``casa`` commands share."""

from __future__ import annotations

import argparse
import difflib
import math
from pathlib import Path


def scene_option(command) -> None:
    """``--scene YAML``; the default is the package's scene, so commands work from any folder."""
    command.add_argument(
        "--scene", metavar="YAML", help="scene file (default: the package's config/scene.yaml)"
    )


def trial_options(command) -> None:
    """The options naming one trial a command records: ``--task``, ``--method``,
    ``--participant``, ``--out`` and ``--phase``."""
    from casa_core import vocabulary

    command.add_argument(
        "--task", required=True, choices=vocabulary.TASKS, help="the task the trial records"
    )
    command.add_argument(
        "--method",
        required=True,
        choices=vocabulary.METHODS,
        help="the assistance method: NA (none), PBA or CASA",
    )
    command.add_argument(
        "--participant", required=True, metavar="ID", help="participant id in the log, e.g. P07"
    )
    command.add_argument("--out", required=True, metavar="DIR", help="folder of the log")
    command.add_argument(
        "--phase", choices=vocabulary.PHASES, help="log phase (default: the task's first)"
    )


def learned_intent_option(command) -> None:
    """``--intent FILE``, repeatable: the learned intents the robot knows besides its own."""
    command.add_argument(
        "--intent",
        action="append",
        default=[],
        metavar="FILE",
        help="a learned intent (casa-intent file) the robot also knows; repeatable "
        "(for the after_learning phase)",
    )


def input_options(command, *, default: str | None) -> None:
    """``--input DEVICE`` and ``--device-trace FILE``: what the person drives the arm with."""
    from casa_core.vocabulary import INPUTS

    told = "(default %(default)s)" if default else "(default: the config's session.input)"
    command.add_argument(
        "--input",
        choices=INPUTS,
        default=default,
        help=f"drive with the keyboard, a gamepad or joystick, or a SpaceMouse {told}; "
        "a device needs the extra casa[devices] (docs/session.md)",
    )
    command.add_argument(
        "--device-trace",
        metavar="FILE",
        help="play a recorded trace of the device (docs/devices.md) instead of reading it: "
        "for tests and demonstrations; the log is written as the device's",
    )


def open_input_device(kind: str, *, deadzone: float, trace: str | None):
    """The open device of ``kind``, or None for the keyboard.

    Raises
    ------
    ValueError
        A trace without a device, or a device that cannot be opened (its message).
    """
    if kind == "keyboard":
        if trace is not None:
            raise ValueError(
                "--device-trace plays a device's trace: choose --input gamepad or spacemouse"
            )
        return None
    from casa_core.robot.devices import DeviceUnavailable, open_device

    try:
        return open_device(kind, deadzone=deadzone, trace=trace)
    except DeviceUnavailable as error:
        raise ValueError(str(error)) from None


def dataset_scene_option(command, folder: str) -> None:
    """``--scene YAML`` of a command on a dataset ``folder`` (its metavar): see
    :func:`dataset_scene`."""
    from casa_core.io.contract import SCENE_NAME

    command.add_argument(
        "--scene",
        metavar="YAML",
        help=f"scene file (default: {folder}/{SCENE_NAME} if the dataset has one, as an "
        "imported dataset does, else the package's config/scene.yaml)",
    )


def dataset_scene(folder, given: str | None) -> Path | None:
    """The scene file of a command on a dataset: ``given``, else the dataset's own, else None.

    None is the package's scene (:func:`casa_core.scene.load_scene`'s default), so
    that the command works from any folder, as the workflow builds a dataset.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> dataset_scene(folder, None), dataset_scene(folder, "mine.yaml")
    (None, PosixPath('mine.yaml'))
    >>> _ = (folder / "scene.yaml").write_text("{}")
    >>> dataset_scene(folder, None) == folder / "scene.yaml"
    True
    """
    from casa_core.io.contract import SCENE_NAME

    if given:
        return Path(given)
    own = Path(folder) / SCENE_NAME
    return own if own.is_file() else None


class CommandParser(argparse.ArgumentParser):
    """A parser that refuses an unknown argument itself, with its usage and the closest option.

    argparse leaves a subcommand's unknown arguments to the top-level parser, which
    prints its own usage (``casa [-h] ...``) and no hint; here the subcommand's parser,
    the one that knows the options, says it. Subcommands take the class of their parent.

    Examples
    --------
    >>> parser = CommandParser(prog="casa validate")
    >>> _ = parser.add_argument("--allow-invalid", action="store_true")
    >>> parser.unknown(["--alow-invalid", "x"])
    'unrecognized arguments: --alow-invalid (did you mean --allow-invalid?), x'
    """

    def parse_known_args(self, args=None, namespace=None):
        namespace, extras = super().parse_known_args(args, namespace)
        if extras:
            self.error(self.unknown(extras))  # exit status 2, this command's usage
        return namespace, extras

    def unknown(self, extras: list[str]) -> str:
        """The message for arguments no option of this parser takes."""
        options = [name for action in self._actions for name in action.option_strings]
        named = []
        for extra in extras:
            close = difflib.get_close_matches(extra.split("=", 1)[0], options, n=1)
            hint = f" (did you mean {close[0]}?)" if extra.startswith("-") and close else ""
            named.append(extra + hint)
        return f"unrecognized arguments: {', '.join(named)}"


def counted(parts: list[tuple[int, str]]) -> str:
    """What a command's summary line counts, each count named, those of 0 left out.

    Examples
    --------
    >>> counted([(253, "trial(s)"), (0, "scene file(s)"), (11, "survey file(s)")])
    '253 trial(s) and 11 survey file(s)'
    >>> counted([(0, "trial(s)"), (0, "survey file(s)")])
    '0 trial(s)'
    """
    named = [f"{count} {word}" for count, word in parts if count] or [f"0 {parts[0][1]}"]
    return " and ".join([", ".join(named[:-1]), named[-1]] if len(named) > 1 else named)


class ExampleFormatter(argparse.RawDescriptionHelpFormatter):
    """Help that wraps the description but keeps the example's lines as written."""

    def _fill_text(self, text, width, indent):
        if text.startswith("Example:"):
            return super()._fill_text(text, width, indent)
        return argparse.HelpFormatter._fill_text(self, text, width, indent)


def example(*lines: str) -> dict:
    """Keyword arguments of ``add_parser`` that end a command's ``--help`` with an example.

    Examples
    --------
    >>> parser = argparse.ArgumentParser(prog="casa x", **example("casa x --flag"))
    >>> parser.format_help().splitlines()[-2:]
    ['Example:', '  casa x --flag']
    """
    return {
        "epilog": "Example:\n" + "\n".join(f"  {line}" for line in lines),
        "formatter_class": ExampleFormatter,
    }


def _integer(text: str, low: int) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= {low}, got {text!r}") from None
    if value < low:
        raise argparse.ArgumentTypeError(f"must be an integer >= {low}, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """An argparse ``type``: an integer >= 1 (counts, 1-based numbers), else a clear error.

    Examples
    --------
    >>> positive_int("3")
    3
    >>> positive_int("0")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: must be an integer >= 1, got '0'
    """
    return _integer(text, 1)


def nonnegative_int(text: str) -> int:
    """An argparse ``type``: an integer >= 0 (seeds, counts where 0 means none).

    Examples
    --------
    >>> nonnegative_int("0")
    0
    >>> nonnegative_int("-1")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: must be an integer >= 0, got '-1'
    """
    return _integer(text, 0)


def positive_float(text: str) -> float:
    """An argparse ``type``: a finite number > 0 (durations, thresholds); NaN and inf refused.

    Examples
    --------
    >>> positive_float("0.5")
    0.5
    >>> positive_float("nan")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: must be a finite number > 0, got 'nan'
    """
    return _number(text, 0.0, strict=True)


def nonnegative_float(text: str) -> float:
    """An argparse ``type``: a finite number >= 0 (a prior's rate, where 0 means none).

    Examples
    --------
    >>> nonnegative_float("0")
    0.0
    >>> nonnegative_float("-1")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: must be a finite number >= 0, got '-1'
    """
    return _number(text, 0.0, strict=False)


def one_sided_level(text: str) -> float:
    """An argparse ``type``: a one-sided significance level, a number in (0, 0.5).

    Examples
    --------
    >>> one_sided_level("0.025")
    0.025
    >>> one_sided_level("0.5")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: must be a number in (0, 0.5), got '0.5'
    """
    value = _number(text, 0.0, strict=True)
    if not value < 0.5:
        raise argparse.ArgumentTypeError(f"must be a number in (0, 0.5), got {text!r}")
    return value


def _number(text: str, low: float, *, strict: bool) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and (value > low if strict else value >= low)):
        bound = f"{'>' if strict else '>='} {low:g}"
        raise argparse.ArgumentTypeError(f"must be a finite number {bound}, got {text!r}")
    return value


def provenance_options(command) -> None:
    """``--config-files`` and ``--effective-config``: the configuration an output names.

    The workflow passes both (workflow/rules/common.smk, ``provenance_options``), so that
    a table or figure says which configuration built it; see :func:`provenance`.
    """
    command.add_argument(
        "--config-files",
        nargs="+",
        metavar="YAML",
        help="the config files layered, in order, as named in the output (e.g. "
        "config/config.yaml config/ci.yaml); needs --effective-config",
    )
    command.add_argument(
        "--effective-config",
        metavar="YAML",
        help="the effective, validated config (data/interim/config.yaml), whose sha256 the "
        "output names; needs --config-files",
    )


def provenance(args):
    """The :class:`casa_core.config.Provenance` the options of :func:`provenance_options`
    give, or None without them.

    Raises
    ------
    ValueError
        If only one of the two options is given.
    OSError
        If the effective config cannot be read.
    """
    from casa_core.config import Provenance

    if not args.config_files and not args.effective_config:
        return None
    if not args.config_files or not args.effective_config:
        raise ValueError("--config-files and --effective-config go together: give both")
    return Provenance.of(args.config_files, args.effective_config)


def validation_option(command) -> None:
    """``--validation``: the dataset's validation.csv, for what the build left out."""
    command.add_argument(
        "--validation",
        metavar="CSV",
        help="the dataset's validation.csv: the page says how many trials it left out "
        "(allow_invalid=true) and names this file for the list (optional)",
    )


def left_out(args) -> str:
    """The sentence on what the build left out (:func:`casa_core.stats.descriptives.left_out`),
    from ``--validation``; "" without it.

    Raises
    ------
    ValueError, OSError
        If the file cannot be read or lacks a column.
    """
    from casa_core.io import read_table
    from casa_core.stats.descriptives import left_out as sentence

    if not args.validation:
        return ""
    return sentence(read_table(args.validation), args.validation)
