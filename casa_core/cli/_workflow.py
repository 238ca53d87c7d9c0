"""The workflow config of ``casa simulate`` and ``casa case-study``: its option, read once."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from casa_core.scene import Scene


#: The config the workflow commands read when no --config is given (working directory).
WORKFLOW_CONFIG = "config/config.yaml"


def load_workflow_config(args) -> tuple[dict, Scene]:
    """The validated workflow config (``--config``, repeatable) and the scene it names.

    Read once, here, at the edge; a ConfigError or SceneError names the file and the key.
    """
    from casa_core.config import load_config
    from casa_core.scene import load_scene

    config = load_config(*(args.config or [WORKFLOW_CONFIG]))
    return config, load_scene(config["scene"])


def add_config_option(command) -> None:
    """``--config YAML``, repeatable: the files :func:`load_workflow_config` reads."""
    command.add_argument(
        "--config",
        action="append",
        metavar="YAML",
        help=f"workflow config (default {WORKFLOW_CONFIG}); repeat to overlay files in order, "
        "e.g. --config config/config.yaml --config config/ci.yaml",
    )
