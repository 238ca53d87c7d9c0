"""Options that several ``casa`` commands share."""

from __future__ import annotations


def scene_option(command) -> None:
    """``--scene YAML``; the default is the package's scene, so commands work from any folder."""
    command.add_argument(
        "--scene", metavar="YAML", help="scene file (default: the package's config/scene.yaml)"
    )
