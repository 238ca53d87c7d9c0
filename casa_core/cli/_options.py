"""Options and help text that several ``casa`` commands share."""

from __future__ import annotations

import argparse


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
