"""Options and help text that several ``casa`` commands share."""

from __future__ import annotations

import argparse
import math


def scene_option(command) -> None:
    """``--scene YAML``; the default is the package's scene, so commands work from any folder."""
    command.add_argument(
        "--scene", metavar="YAML", help="scene file (default: the package's config/scene.yaml)"
    )


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


def _number(text: str, low: float, *, strict: bool) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and (value > low if strict else value >= low)):
        bound = f"{'>' if strict else '>='} {low:g}"
        raise argparse.ArgumentTypeError(f"must be a finite number {bound}, got {text!r}")
    return value
