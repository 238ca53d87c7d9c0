"""A corpus of hostile inputs: one dataset folder per case, each breaking one thing.

Every case starts from the same valid dataset (one short trial written with
:func:`casa_core.io.write_trial`, optionally Likert answers written with
:func:`casa_core.io.write_surveys`) and then corrupts one thing: a cell, a key, a
byte, a file name or a symlink. Each case sits in its own folder so that the
outcomes of two cases never mix. Files that a symlink case points to are written to
``.outside/`` next to the case folders: outside every dataset, and hidden, so that no
tool takes that folder for a dataset.

Run as a script to write the corpus for a look by hand::

    python tests/io/hostile/make_corpus.py /tmp/corpus
"""

from __future__ import annotations

import csv
import io
import json
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from casa_core.io import SURVEY_COLUMNS, write_surveys, write_trial
from casa_core.vocabulary import QUESTIONS

#: Ticks per trial: short, so that the DAG over the whole corpus stays fast.
TICKS = 20
#: The control tick of casa-trial/1 (s): 20 Hz, ``docs/data-contracts.md``.
DT = 0.05
CONDITION = {
    "participant": "p01",
    "task": "known_goal",
    "method": "CASA",
    "phase": "no_misspecification",
}
STEM = "p01/known_goal_CASA_no_misspecification"
CSV = f"{STEM}.csv"
JSON = f"{STEM}.json"
SURVEYS = "surveys.csv"
OUTSIDE = ".outside"
_DELETE = object()


@dataclass(frozen=True)
class Case:
    """One hostile input.

    Attributes
    ----------
    name : str
        The case's folder (a valid dataset name of the workflow).
    files : tuple of str
        Every file written, relative to the case's folder (symlinks included).
    outcome : tuple
        ``("error", rule)``, ``("warning", rule)`` or ``("valid",)``.
    file : str
        The file the problem names, relative to the case's folder; ``""`` for the folder.
    report : str
        That file's row in ``validation.csv`` (a trial's problems are filed under its
        ``.csv``).
    """

    name: str
    files: tuple[str, ...]
    outcome: tuple
    file: str
    report: str

    @property
    def rule(self) -> str | None:
        """The rule expected broken, None for a valid case."""
        return self.outcome[1] if len(self.outcome) > 1 else None


# --------------------------------------------------------------------------- the valid base


def trial_frame(*, ticks: int = TICKS) -> pd.DataFrame:
    """A short valid assisted trial: the end effector moves along +x at one step a tick."""
    t = np.arange(ticks) * DT
    belief = np.linspace(0.5, 0.9, ticks)
    return pd.DataFrame(
        {
            "t": t,
            "x": 0.45 + 0.0025 * np.arange(ticks),
            "y": np.full(ticks, -0.22),
            "z": np.full(ticks, 0.38),
            "rot": np.zeros(ticks),
            "keys": ["x+"] * (ticks - 1) + [""],
            "alpha": np.linspace(0.0, 0.5, ticks),
            "beta:green": np.linspace(1.0, 2.0, ticks),
            "beta:purple": np.linspace(1.0, 0.5, ticks),
            "belief:green": belief,
            "belief:purple": 1.0 - belief,
        }
    )


def write_base(folder: Path, *, participant: str = "p01", stem: str = STEM) -> list[str]:
    """Write one valid trial below ``folder``; return its files relative to ``folder``."""
    meta = {
        **CONDITION,
        "participant": participant,
        "source": "human",
        "intents": ["green", "purple"],
        "seed": 0,
    }
    write_trial(folder / stem, meta, trial_frame())
    return [f"{stem}.json", f"{stem}.csv"]


def write_answers(folder: Path, *, participant: str = "p01") -> list[str]:
    """Write valid Likert answers (every question of the base trial's condition)."""
    rows = [{**CONDITION, "participant": participant, "question": q, "score": 5} for q in QUESTIONS]
    write_surveys(folder / SURVEYS, pd.DataFrame(rows, columns=list(SURVEY_COLUMNS)))
    return [SURVEYS]


# --------------------------------------------------------------------------- corruptions


def _rows(path: Path) -> list[list[str]]:
    return list(csv.reader(io.StringIO(path.read_text(encoding="utf-8"))))


def _write_rows(path: Path, rows: list[list[str]]) -> None:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    path.write_text(buffer.getvalue(), encoding="utf-8", newline="")


def set_cell(path: Path, line: int, column: str, value: str) -> None:
    """Set one cell of a CSV; ``line`` counts as an editor does (the header is line 1)."""
    rows = _rows(path)
    rows[line - 1][rows[0].index(column)] = value
    _write_rows(path, rows)


def set_column(path: Path, column: str, values) -> None:
    """Replace every value of one column of a CSV."""
    rows = _rows(path)
    j = rows[0].index(column)
    for row, value in zip(rows[1:], values, strict=True):
        row[j] = repr(float(value)) if isinstance(value, float) else str(value)
    _write_rows(path, rows)


def edit_rows(path: Path, edit: Callable[[list[list[str]]], list[list[str]]]) -> None:
    """Rewrite a CSV's rows (header first) through ``edit``."""
    _write_rows(path, edit(_rows(path)))


def set_key(path: Path, key: str, value=_DELETE) -> None:
    """Set a metadata key of a ``.json`` (delete it without ``value``)."""
    meta = json.loads(path.read_text(encoding="utf-8"))
    if value is _DELETE:
        del meta[key]
    else:
        meta[key] = value
    path.write_text(json.dumps(meta, indent=2), encoding="utf-8")


def replace_bytes(path: Path, old: bytes, new: bytes) -> None:
    """Replace the first occurrence of ``old`` in a file's bytes."""
    data = path.read_bytes()
    if old not in data:
        raise ValueError(f"{path}: {old!r} not found")
    path.write_bytes(data.replace(old, new, 1))


# --------------------------------------------------------------------------- the cases

#: Builders of the cases: (name, outcome, file named, build(folder, outside) -> extra files).
#: ``build`` receives the case's folder holding the base trial (and answers when the name
#: starts with ``surveys_``) and returns the files it added beyond them.
Builder = Callable[[Path, Path], list[str]]
_BUILDERS: list[tuple[str, tuple, str, Builder]] = []


def case(name: str, outcome: tuple, file: str = CSV):
    """Register a builder under ``name``."""

    def register(build: Builder) -> Builder:
        _BUILDERS.append((name, outcome, file, build))
        return build

    return register


def _cell(line: int, column: str, value: str) -> Builder:
    def build(folder: Path, outside: Path) -> list[str]:
        set_cell(folder / CSV, line, column, value)
        return []

    return build


def _key(key: str, value=_DELETE, *, file: str = JSON) -> Builder:
    def build(folder: Path, outside: Path) -> list[str]:
        set_key(folder / file, key, value)
        return []

    return build


def _times(values) -> Builder:
    def build(folder: Path, outside: Path) -> list[str]:
        set_column(folder / CSV, "t", [float(v) for v in values])
        return []

    return build


def _survey_cell(line: int, column: str, value: str) -> Builder:
    def build(folder: Path, outside: Path) -> list[str]:
        set_cell(folder / SURVEYS, line, column, value)
        return []

    return build


def _edit(edit: Callable[[list[list[str]]], list[list[str]]], file: str = CSV) -> Builder:
    def build(folder: Path, outside: Path) -> list[str]:
        edit_rows(folder / file, edit)
        return []

    return build


def _nothing(folder: Path, outside: Path) -> list[str]:
    return []


ERROR, WARNING = "error", "warning"
TICK_T = np.arange(TICKS) * DT

case("valid", ("valid",))(_nothing)
case("surveys_valid", ("valid",))(_nothing)


@case("valid_crlf", ("valid",))
def _crlf(folder, outside):
    path = folder / CSV
    path.write_bytes(path.read_bytes().replace(b"\n", b"\r\n"))
    return []


# Metadata: keys and values.
case("meta_missing_task", (ERROR, "required-key"), JSON)(_key("task"))
case("meta_unknown_key", (ERROR, "unknown-key"), JSON)(_key("operator", "me"))
case("meta_wrong_schema", (ERROR, "schema"), JSON)(_key("schema", "casa-trial/2"))
case("meta_task_enum", (ERROR, "enum"), JSON)(_key("task", "Known Goal"))
case("meta_source_enum", (ERROR, "enum"), JSON)(_key("source", "robot"))
case("meta_empty_participant", (ERROR, "non-empty-string"), JSON)(_key("participant", "  "))
case("meta_task_phase", (ERROR, "task-phase"), JSON)(_key("phase", "before_learning"))
case("meta_phase_method", (ERROR, "phase-method"), JSON)(_key("phase", "demonstration"))
case("meta_intents_not_list", (ERROR, "intent-names"), JSON)(_key("intents", "green"))
case("meta_intents_twice", (ERROR, "intent-names"), JSON)(_key("intents", ["green", "green"]))
case("meta_max_duration_zero", (ERROR, "positive-number"), JSON)(_key("max_duration", 0))


@case("meta_max_duration_nan", (ERROR, "positive-number"), JSON)
def _nan_duration(folder, outside):
    # Python's json reads NaN (not JSON): the value must still be refused.
    replace_bytes(folder / JSON, b'"seed": 0', b'"max_duration": NaN')
    return []


# JSON lists where a string is expected (unhashable values).
case("meta_task_list", (ERROR, "enum"), JSON)(_key("task", ["known_goal"]))
case("meta_phase_list", (ERROR, "enum"), JSON)(_key("phase", ["no_misspecification"]))
case("meta_participant_list", (ERROR, "non-empty-string"), JSON)(_key("participant", ["p01"]))
case("meta_seed_string", (ERROR, "integer"), JSON)(_key("seed", "42"))
# Participant ids that would become paths or be confused with another.
case("participant_dotdot", (ERROR, "participant-id"), JSON)(_key("participant", "../x"))
case("participant_slash", (ERROR, "participant-id"), JSON)(_key("participant", "a/b"))
case("participant_spaces", (ERROR, "participant-id"), JSON)(_key("participant", " p01 "))


@case(
    "participant_case",
    (WARNING, "participant-case"),
    "p02/known_goal_CASA_no_misspecification.json",
)
def _participant_case(folder, outside):
    # Same condition, participant ids differing only by case: one person or two?
    return write_base(folder, participant="P01", stem="p02/known_goal_CASA_no_misspecification")


# The metadata file itself.
@case("meta_not_object", (ERROR, "json-object"), JSON)
def _not_object(folder, outside):
    (folder / JSON).write_text('["casa-trial/1"]\n', encoding="utf-8")
    return []


@case("meta_truncated", (ERROR, "json"), JSON)
def _truncated(folder, outside):
    path = folder / JSON
    path.write_bytes(path.read_bytes()[:40])
    return []


@case("meta_latin1", (ERROR, "utf-8"), JSON)
def _meta_latin1(folder, outside):
    set_key(folder / JSON, "notes", "caf\u00e9")
    replace_bytes(folder / JSON, b"caf\\u00e9", b"caf\xe9")
    return []


@case("lone_csv", (ERROR, "pair"), JSON)
def _lone_csv(folder, outside):
    (folder / JSON).unlink()
    return []


@case("lone_json", (ERROR, "pair"))
def _lone_json(folder, outside):
    (folder / CSV).unlink()
    return []


# The trial CSV as a table.
@case("csv_empty", (ERROR, "csv-format"))
def _csv_empty(folder, outside):
    (folder / CSV).write_bytes(b"")
    return []


case("csv_ragged", (ERROR, "csv-format"))(_edit(lambda r: [*r[:3], r[3][:4], *r[4:]]))
case("csv_header_only", (ERROR, "non-empty"))(_edit(lambda r: r[:1]))
case("csv_column_twice", (ERROR, "unique-columns"))(_edit(lambda r: [[*row, row[1]] for row in r]))
case("csv_missing_column", (ERROR, "required-column"))(
    _edit(lambda r: [row[:3] + row[4:] for row in r])  # no z
)
case("csv_unknown_column", (ERROR, "unknown-column"))(
    _edit(lambda r: [[*r[0], "speed"], *[[*row, "1"] for row in r[1:]]])
)


@case("csv_tab_separated", (ERROR, "csv-format"))
def _tabs(folder, outside):
    path = folder / CSV
    path.write_bytes(path.read_bytes().replace(b",", b"\t"))
    return []


@case("csv_latin1", (ERROR, "utf-8"))
def _csv_latin1(folder, outside):
    # One latin-1 byte in a cell: a recording script that wrote 'x\xe9' in its locale.
    set_cell(folder / CSV, 3, "keys", "KEY")
    replace_bytes(folder / CSV, b"KEY", b"x+\xe9")
    return []


@case("csv_utf16", (ERROR, "utf-8"))
def _csv_utf16(folder, outside):
    path = folder / CSV
    path.write_bytes(path.read_text(encoding="utf-8").encode("utf-16"))
    return []


# Cells.
case("csv_x_text", (ERROR, "finite-number"))(_cell(3, "x", "far"))
case("csv_x_nan", (ERROR, "finite-number"))(_cell(3, "x", "nan"))
case("csv_y_inf", (ERROR, "finite-number"))(_cell(4, "y", "inf"))
case("csv_x_1e308", (ERROR, "range"))(_cell(5, "x", "1e308"))
case("csv_z_out_of_reach", (ERROR, "range"))(_cell(5, "z", "3.8"))
case("csv_alpha_above_1", (ERROR, "range"))(_cell(3, "alpha", "1.5"))
case("csv_beta_negative", (ERROR, "range"))(_cell(3, "beta:green", "-1"))
case("csv_keys_unknown", (ERROR, "keys"))(_cell(3, "keys", "w"))
case("csv_keys_twice", (ERROR, "keys"))(_cell(3, "keys", "x+ x+"))


@case("csv_belief_sum", (ERROR, "belief-sum"))
def _belief_sum(folder, outside):
    set_cell(folder / CSV, 3, "belief:green", "0.3")
    set_cell(folder / CSV, 3, "belief:purple", "0.3")
    return []


@case("csv_intent_not_listed", (ERROR, "intent-name"))
def _intent_not_listed(folder, outside):
    edit_rows(
        folder / CSV,
        lambda r: [[*row[:-1], "belief:blue" if i == 0 else row[-1]] for i, row in enumerate(r)],
    )
    return []


# The time column.
case("t_decreasing", (ERROR, "t-increasing"))(_times(np.r_[TICK_T[:5], TICK_T[3], TICK_T[6:]]))
case("t_negative", (ERROR, "range"))(_times(TICK_T - DT))
case("t_milliseconds", (ERROR, "tick-rate"))(_times(TICK_T * 1000))
case("t_10hz", (ERROR, "tick-rate"))(_times(TICK_T * 2))
case("t_epoch", (ERROR, "t-start"))(_times(1.7e9 + TICK_T))
case("t_last_huge", (ERROR, "range"))(_times(np.r_[TICK_T[:-1], 1e12]))
case("t_irregular", (WARNING, "tick-irregular"))(_times(np.r_[TICK_T[:10], TICK_T[10:] + 0.02]))


# File names and links.
@case("upper_case_extension", (ERROR, "suffix"), "p02/known_goal_CASA_no_misspecification.CSV")
def _upper_case(folder, outside):
    # A second participant's trial named .JSON/.CSV: skipped silently unless reported.
    stem = "p02/known_goal_CASA_no_misspecification"
    for name in write_base(folder, participant="p02", stem=stem):
        (folder / name).rename(folder / name.replace(".json", ".JSON").replace(".csv", ".CSV"))
    return [f"{stem}.JSON", f"{stem}.CSV"]


@case("symlink_file_outside", (ERROR, "symlink"))
def _symlink_file(folder, outside):
    # The trial's CSV is a link to a file outside the dataset, which must not be read.
    target = outside / f"{folder.name}.csv"
    target.write_bytes((folder / CSV).read_bytes())
    (folder / CSV).unlink()
    (folder / CSV).symlink_to(os.path.relpath(target, (folder / CSV).parent))
    return []


@case("symlink_folder_outside", (ERROR, "symlink"), "p02")
def _symlink_folder(folder, outside):
    target = outside / folder.name
    write_base(target, participant="p02", stem="known_goal_CASA_no_misspecification")
    (folder / "p02").symlink_to(os.path.relpath(target, folder))
    return ["p02"]


@case("only_readme", (ERROR, "non-empty"), "")
def _only_readme(folder, outside):
    for name in (JSON, CSV):
        (folder / name).unlink()
    (folder / "p01").rmdir()
    (folder / "README.md").write_text("recorded on Monday\n", encoding="utf-8")
    return ["README.md"]


@case("duplicate_condition", (ERROR, "unique-condition"))
def _duplicate(folder, outside):
    return write_base(folder, stem="p01/known_goal_CASA_no_misspecification_again")


# Surveys.
case("surveys_score_8", (ERROR, "likert-score"), SURVEYS)(_survey_cell(3, "score", "8"))
case("surveys_score_float", (ERROR, "likert-score"), SURVEYS)(_survey_cell(2, "score", "5.0"))
case("surveys_question_enum", (ERROR, "enum"), SURVEYS)(_survey_cell(2, "question", "fun"))
case("surveys_empty_participant", (ERROR, "non-empty-string"), SURVEYS)(
    _survey_cell(2, "participant", "")
)
case("surveys_participant_path", (ERROR, "participant-id"), SURVEYS)(
    _survey_cell(2, "participant", "../p01")
)
case("surveys_answer_twice", (ERROR, "unique-answer"), SURVEYS)(
    _survey_cell(3, "question", "understood")
)
case("surveys_missing_column", (ERROR, "required-column"), SURVEYS)(
    _edit(lambda r: [row[:-1] for row in r], SURVEYS)  # no score
)
case("surveys_header_only", (WARNING, "no-answers"), SURVEYS)(_edit(lambda r: r[:1], SURVEYS))
case("surveys_without_trial", (WARNING, "survey-trial"), SURVEYS)(
    _survey_cell(2, "participant", "p09")
)
case("surveys_method_without_trial", (WARNING, "survey-trial"), SURVEYS)(
    _survey_cell(2, "method", "PBA")
)


@case("surveys_latin1", (ERROR, "utf-8"), SURVEYS)
def _surveys_latin1(folder, outside):
    set_cell(folder / SURVEYS, 2, "participant", "PID")
    replace_bytes(folder / SURVEYS, b"PID", b"p\xe901")
    return []


def planned() -> list[tuple[str, tuple]]:
    """The cases' names and expected outcomes, in corpus order, without writing anything."""
    return [(name, outcome) for name, outcome, _, _ in _BUILDERS]


def make_corpus(folder: Path | str) -> list[Case]:
    """Write every case below ``folder`` (one dataset folder each); return the cases.

    Parameters
    ----------
    folder : path
        Created if needed; each case is written to ``folder / case.name``, the targets
        of symlink cases to ``folder / ".outside"``.

    Returns
    -------
    list of Case
        In a fixed order.
    """
    folder = Path(folder)
    outside = folder / OUTSIDE
    outside.mkdir(parents=True, exist_ok=True)
    cases = []
    for name, outcome, file, build in _BUILDERS:
        root = folder / name
        files = write_base(root)
        if name.startswith("surveys_"):
            files += write_answers(root)
        files += build(root, outside)
        written = tuple(sorted(f for f in files if os.path.lexists(root / f)))
        report = f"{file.removesuffix('.json')}.csv" if file.endswith(".json") else file
        cases.append(Case(name, written, outcome, file, report or "."))
    return cases


if __name__ == "__main__":
    corpus = make_corpus(sys.argv[1] if len(sys.argv) > 1 else "corpus")
    for item in corpus:
        print(item.name, *item.outcome)
