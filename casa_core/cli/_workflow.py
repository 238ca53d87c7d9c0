"""The workflow config of ``casa simulate``, ``casa case-study``, ``casa stats`` and
``casa session``: its option, read once."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from casa_core.scene import Scene

#: What the commands read when no --config is given, as their help says it.
NO_CONFIG = (
    "the package's own settings, the defaults of casa_core/config.schema.yaml, which are "
    "the repository's config/config.yaml, and the package's scene, from any folder"
)


def load_workflow_config(args) -> tuple[dict, Scene]:
    """The validated workflow config (``--config``, repeatable) and the scene it names,
    driven by the config's ``teleop.mode`` where it sets one.

    Without ``--config``, the package's defaults (:func:`casa_core.config.load_config`
    of no file) and its own scene, so that the command works from any folder. Read
    once, here, at the edge; a ConfigError or SceneError names the file and the key.
    """
    from casa_core.config import load_config
    from casa_core.scene import load_scene

    config = load_config(*(args.config or ()))
    return config, load_scene(config["scene"]).with_teleop_mode(config["teleop"]["mode"])


def add_config_option(command, what: str = "workflow config") -> None:
    """``--config YAML``, repeatable: the files :func:`load_workflow_config` reads.

    ``what`` says what of the config the command uses.
    """
    command.add_argument(
        "--config",
        action="append",
        metavar="YAML",
        help=f"{what}; default: {NO_CONFIG}. Repeat to overlay files in order, "
        "e.g. --config config/config.yaml --config config/ci.yaml",
    )
