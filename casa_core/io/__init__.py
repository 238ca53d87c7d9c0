"""Files: the trial-log contract, its reader and writer, validation, and atomic output.

``from casa_core.io import read_trial, write_trial, check_paths, LogError`` is all most
code needs; the contract is ``docs/data-contracts.md``. The modules, each with one job:

- :mod:`~casa_core.io.contract`: casa-trial/1 and the surveys file as data;
- :mod:`~casa_core.io.metadata`: the rules of a trial's metadata;
- :mod:`~casa_core.io.validation`: the rules, reporting through
  :mod:`~casa_core.io.problems` (:class:`Problem`, :class:`LogError`);
- :mod:`~casa_core.io.trial_log`: the one reader and writer of trials and surveys;
- :mod:`~casa_core.io.folders`: checking files and folders of a dataset;
- :mod:`~casa_core.io.atomic`: the one atomic writer of every output;
- :mod:`~casa_core.io.tables`: the processed tables read back, and tidy tables' input checks;
- :mod:`~casa_core.io.original`: the original implementation's session files;
- :mod:`~casa_core.io.population`: the operator population file of `casa calibrate`;
- :mod:`~casa_core.io.workflow_log`: why a workflow run failed, from Snakemake's log.
"""

from casa_core.io.atomic import (
    atomic_path,
    atomic_write_bytes,
    atomic_write_text,
    frame_to_csv_text,
    write_csv,
)
from casa_core.io.contract import (
    COMMAND_COLUMNS,
    CONDITION_KEYS,
    FRAME_REQUIRED,
    JOINTS,
    META_OPTIONAL,
    META_REQUIRED,
    SCHEMA,
    SURVEY_COLUMNS,
    SURVEY_OPTIONAL,
    SURVEYS_NAME,
)
from casa_core.io.folders import FileCheck, check_files, check_paths, find_files, validate_paths
from casa_core.io.tables import read_table
from casa_core.io.trial_log import (
    load_meta,
    load_surveys,
    load_trial,
    read_surveys,
    read_trial,
    trial_files,
    trial_stem,
    write_surveys,
    write_trial,
)
from casa_core.io.validation import (
    LogError,
    Problem,
    check_meta,
    parse_surveys_csv,
    parse_trial_csv,
)

__all__ = [
    "COMMAND_COLUMNS",
    "CONDITION_KEYS",
    "FRAME_REQUIRED",
    "JOINTS",
    "META_OPTIONAL",
    "META_REQUIRED",
    "SCHEMA",
    "SURVEYS_NAME",
    "SURVEY_COLUMNS",
    "SURVEY_OPTIONAL",
    "FileCheck",
    "LogError",
    "Problem",
    "atomic_path",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_files",
    "check_meta",
    "check_paths",
    "find_files",
    "frame_to_csv_text",
    "load_meta",
    "load_surveys",
    "load_trial",
    "parse_surveys_csv",
    "parse_trial_csv",
    "read_surveys",
    "read_table",
    "read_trial",
    "trial_files",
    "trial_stem",
    "validate_paths",
    "write_csv",
    "write_surveys",
    "write_trial",
]
