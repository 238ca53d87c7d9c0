"""The original implementation's session files: reading them and importing them as casa-trial/1.

The modules, each with one job:

- :mod:`~casa_core.io.original.sessions`: The original implementation's session files, read
  and converted to casa-trial/1 trials.
- :mod:`~casa_core.io.original.importer`: A folder of the original implementation's session
  files as a casa-trial/1 dataset.
"""

from casa_core.io.original.importer import (
    METHOD_LETTERS,
    ORIGINAL_SCENE,
    TASK_NUMBERS,
    ImportResult,
    SessionName,
    describe,
    goal_names,
    import_original,
    parse_name,
)
from casa_core.io.original.sessions import (
    KEY_FRACTION,
    REFERENCE_ANGLES,
    REQUIRED_KEYS,
    Converted,
    Session,
    SessionError,
    command_keys,
    convert_session,
    read_session,
    reference_q,
    started_at,
)

__all__ = [
    "Converted",
    "ImportResult",
    "KEY_FRACTION",
    "METHOD_LETTERS",
    "ORIGINAL_SCENE",
    "REFERENCE_ANGLES",
    "REQUIRED_KEYS",
    "Session",
    "SessionError",
    "SessionName",
    "TASK_NUMBERS",
    "command_keys",
    "convert_session",
    "describe",
    "goal_names",
    "import_original",
    "parse_name",
    "read_session",
    "reference_q",
    "started_at",
]
