"""The intent library: one versioned file per learned intent (format ``casa-intent``).

Lifelong learning keeps what it learned: each learned intent is one file
``<name>.intent.json`` in a library folder, holding the cost network's weights
and what a reader needs to trust and reuse them: name, task, participant, input
features, scene objects, seed, SHA-256 hashes of the demonstrations, the IRL
settings and the training history.

Format ``casa-intent``, version :data:`VERSION`: a JSON object with the keys of
:data:`REQUIRED_KEYS`. The weights are stored per parameter as shape, dtype and base64
of the little-endian bytes, so the file is plain text and self-describing. The key
``checksum`` is the SHA-256 of the canonical JSON (sorted keys, no spaces) of
every other key: a truncated, edited or bit-flipped file is detected. Files are
written atomically (:mod:`casa_core.io.atomic`). The format is described for readers
in docs/data-contracts.md.

Reading a library never fails as a whole: :func:`scan_library` returns the good
entries and, separately, one :class:`LibraryError` per bad file, naming the file
and the rule it breaks.

Examples
--------
>>> import tempfile
>>> from casa_core.learning import IRLConfig, NeuralIntent, cost_network
>>> network = cost_network(16, hidden=8, negative_slope=0.01, seed=0)
>>> intent = NeuralIntent(
...     "red_p01", network, objects={"red": (0.4, 0.22, 0.12)}, cost_scale=1.0, length_scale=0.1
... )
>>> folder = tempfile.mkdtemp()
>>> path = save_intent(
...     folder, intent, task="unknown_goal", participant="p01", seed=0, demos=[], history=[],
...     config=IRLConfig(hidden=8),
... )
>>> path.name
'red_p01.intent.json'
>>> entries, problems = scan_library(folder)
>>> entries[0].intent, problems
(NeuralIntent('red_p01', objects=['red']), [])
"""

from __future__ import annotations

import base64
import hashlib
import json
import re
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import torch

from casa_core.io.atomic import atomic_write_text
from casa_core.io.contract import INTENT_SUFFIX
from casa_core.learning import IRLConfig, NeuralIntent, cost_network, feature_names
from casa_core.learning.maxent import kept_record, stop_reason
from casa_core.learning.network import network_shape
from casa_core.planning import PlannerConfig

FORMAT = "casa-intent"
VERSION = 2  # 2: cost_offset
SUFFIX = INTENT_SUFFIX
#: Every key of a file, in the order the format lists them.
REQUIRED_KEYS = tuple(
    """format version name task participant seed features objects network cost_scale
    cost_offset length_scale planner guides demo_hashes irl_config history weights
    checksum""".split()
)
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")
#: The keys' JSON types, checked on reading: (what the message says, Python type, keys).
_KINDS = (
    ("a JSON string", str, ("name", "task", "participant")),
    ("a JSON integer", int, ("seed",)),
    ("a JSON list", list, ("demo_hashes", "history", "objects", "guides")),
    ("a JSON object", dict, ("network", "planner", "weights", "irl_config")),
    ("a JSON number", (int, float), ("cost_scale", "cost_offset", "length_scale")),
)


class LibraryError(ValueError):
    """A library file that cannot be used; the message names the file and the rule broken."""

    def __init__(self, path: Path | str, rule: str, message: str):
        self.path = Path(path)
        self.rule = rule
        super().__init__(f"{self.path}: [{rule}] {message}")


@dataclass(frozen=True)
class LibraryEntry:
    """A learned intent read from the library.

    Attributes
    ----------
    path : Path
        Its file.
    intent : NeuralIntent
        The intent, ready for an :class:`casa_core.assist.assistant.Assistant`.
    metadata : dict
        Every key of the file but ``weights`` and ``checksum``.
    """

    path: Path
    intent: NeuralIntent
    metadata: dict

    def summary(self) -> str:
        """One line: name, task, participant, seed, demos, how IRL ran (data-contracts.md)."""
        m = self.metadata
        history, kept = m["history"], kept_record(m["history"]) or {}
        most, match = m["irl_config"].get("max_iterations", "?"), kept.get("verified_match")
        return (
            f"{m['name']}\ttask={m['task']}\tparticipant={m['participant']}\tseed={m['seed']}"
            f"\tdemos={len(m['demo_hashes'])}\titerations={len(history)}/{most}"
            f"\tstopped={stop_reason(history)}\tkept={kept.get('iteration', '-')}"
            f"\tend_match_m={'-' if match is None else f'{match:.4f}'}\tfile={self.path.name}"
        )


def demo_hash(demo) -> str:
    """SHA-256 of a demonstration ``(n, 5)``: its shape and float64 little-endian bytes."""
    array = np.ascontiguousarray(np.asarray(demo, dtype="<f8"))
    digest = hashlib.sha256(repr(array.shape).encode())
    digest.update(array.tobytes())
    return digest.hexdigest()


def intent_path(library: Path | str, name: str) -> Path:
    """The file of intent ``name`` in ``library``."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(
            f"intent name {name!r} cannot name a file: use letters, digits, '_', '-', '.'"
        )
    return Path(library) / f"{name}{SUFFIX}"


def _canonical(payload: dict) -> bytes:
    return json.dumps(payload, sort_keys=True, separators=(",", ":"), allow_nan=False).encode()


def _encode_weights(network: torch.nn.Module) -> dict:
    weights = {}
    for key, tensor in network.state_dict().items():
        array = tensor.detach().cpu().numpy()
        weights[key] = {
            "shape": list(array.shape),
            "dtype": str(array.dtype),
            "data": base64.b64encode(
                array.astype(array.dtype.newbyteorder("<")).tobytes()
            ).decode(),
        }
    return weights


def save_intent(
    library: Path | str,
    intent: NeuralIntent,
    *,
    task: str,
    participant: str,
    seed: int,
    demos,
    history: list[dict],
    config: IRLConfig,
) -> Path:
    """Write a learned intent to ``<library>/<name>.intent.json`` atomically.

    Parameters
    ----------
    library : path
        The library folder (created if missing).
    intent : NeuralIntent
        The learned intent (``MaxEntIRL.intent_``, :class:`casa_core.learning.MaxEntIRL`).
    task, participant : str
        Where the demonstrations came from (free text; "" if unknown).
    seed : int
        The seed it was learned with.
    demos : list of array_like
        The demonstrations ``(n, 5)``; only their hashes are stored.
    history : list of dict
        The training history (``MaxEntIRL.history_``).
    config : IRLConfig
        The settings it was learned with.

    Returns
    -------
    Path
        The file written.
    """
    path = intent_path(library, intent.name)
    payload = {
        "format": FORMAT,
        "version": VERSION,
        "name": intent.name,
        "task": str(task),
        "participant": str(participant),
        "seed": int(seed),
        "features": intent.features,
        "objects": [
            {"name": n, "position": p.tolist()}
            for n, p in zip(intent.object_names, intent.objects, strict=True)
        ],
        "network": network_shape(intent.network),
        "cost_scale": intent.cost_scale,
        "cost_offset": intent.cost_offset,
        "length_scale": intent.length_scale,
        "planner": asdict(intent.planner),
        "guides": [g.tolist() for g in intent.guides],
        "demo_hashes": [demo_hash(d) for d in demos],
        "irl_config": {k: v for k, v in asdict(config).items() if k != "planner"},
        # Measured times stay out, so that one config gives the same file on every run.
        "history": [{k: v for k, v in h.items() if k != "seconds"} for h in history],
        "weights": _encode_weights(intent.network),
    }
    payload["checksum"] = hashlib.sha256(_canonical(payload)).hexdigest()
    text = json.dumps(payload, indent=1, sort_keys=True, allow_nan=False) + "\n"
    return atomic_write_text(path, text)


def _require(path: Path, ok: bool, rule: str, message: str) -> None:
    if not ok:
        raise LibraryError(path, rule, message)


def load_intent(path: Path | str) -> LibraryEntry:
    """Read and check one library file.

    Raises
    ------
    LibraryError
        Naming the file and the rule broken: unreadable, not JSON (e.g.
        truncated), wrong format or version, missing keys, checksum mismatch,
        or weights that do not fit the network.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise LibraryError(path, "readable", f"cannot be read: {error}") from None
    try:
        payload = json.loads(text, parse_constant=_finite_float, parse_float=_finite_float)
    except _NotFinite as error:
        raise LibraryError(path, "finite", f"{error}: every number must be finite") from None
    except (json.JSONDecodeError, RecursionError) as error:
        raise LibraryError(
            path, "json", f"is not valid JSON (truncated or damaged?): {error}"
        ) from None
    _require(path, isinstance(payload, dict), "json", "must hold a JSON object")
    _require(
        path,
        payload.get("format") == FORMAT,
        "format",
        f"format must be {FORMAT!r}, got {payload.get('format')!r}",
    )
    _require(
        path,
        payload.get("version") == VERSION,
        "version",
        f"version {payload.get('version')!r} is not supported (this casa reads {VERSION})",
    )
    missing = [key for key in REQUIRED_KEYS if key not in payload]
    _require(path, not missing, "required-key", f"missing key(s): {', '.join(missing)}")
    body = {k: v for k, v in payload.items() if k != "checksum"}
    _require(
        path,
        hashlib.sha256(_canonical(body)).hexdigest() == payload["checksum"],
        "checksum",
        "checksum does not match the content: the file was damaged or edited",
    )
    for expected, kind, keys in _KINDS:
        for key in keys:
            value = payload[key]
            # A JSON true is a Python int: refused where a number is expected.
            ok = isinstance(value, kind) and not isinstance(value, bool)
            _require(path, ok, "content", f"{key} must be {expected}, got {type(value).__name__}")
    _require(
        path,
        all(isinstance(record, dict) for record in payload["history"]),
        "content",
        "history must be a list of objects",
    )
    try:
        intent = _build_intent(path, payload)
    except LibraryError:
        raise
    except KeyError as error:
        raise LibraryError(path, "required-key", f"an inner object lacks key {error}") from None
    except (TypeError, ValueError, RuntimeError, AttributeError, ArithmeticError) as error:
        raise LibraryError(path, "content", f"does not describe a usable intent: {error}") from None
    metadata = {k: v for k, v in payload.items() if k not in ("weights", "checksum")}
    return LibraryEntry(path=path, intent=intent, metadata=metadata)


class _NotFinite(ValueError):
    """A number of a library file that is NaN or infinite."""


def _finite_float(text: str) -> float:
    # json reads NaN, Infinity and -Infinity, which are not JSON, and 1e999 as inf.
    value = float(text)
    if not np.isfinite(value):
        raise _NotFinite(f"holds {text}")
    return value


def _decode_weights(path: Path, stored: dict) -> dict[str, np.ndarray]:
    arrays = {}
    for key, entry in stored.items():
        data = base64.b64decode(entry["data"], validate=True)
        array = np.frombuffer(data, dtype=np.dtype(entry["dtype"]).newbyteorder("<"))
        array = array.reshape(entry["shape"]).astype(np.float32)
        if not np.isfinite(array).all():
            raise LibraryError(path, "finite", f"weight {key} is not finite")
        arrays[key] = array
    return arrays


def _build_intent(path: Path, payload: dict) -> NeuralIntent:
    object_names = [obj["name"] for obj in payload["objects"]]
    if not all(isinstance(name, str) for name in object_names):
        raise ValueError(f"object names {object_names} must be strings")
    if len(set(object_names)) != len(object_names):
        raise ValueError(f"objects {object_names} repeat a name")
    objects = {obj["name"]: obj["position"] for obj in payload["objects"]}
    if payload["features"] != feature_names(object_names):
        raise ValueError("features do not match the objects (an incompatible feature set)")
    spec = payload["network"]
    if spec["inputs"] != len(payload["features"]):
        raise ValueError(f"network has {spec['inputs']} inputs for {len(payload['features'])}")
    arrays = _decode_weights(path, payload["weights"])
    hidden = spec["hidden"]
    # hidden**2 weights: a size the stored data cannot fill is refused before allocating it.
    if not (isinstance(hidden, int) and 1 <= hidden**2 <= sum(a.size for a in arrays.values())):
        raise ValueError(f"network hidden={hidden!r} does not fit the stored weights")
    network = cost_network(
        spec["inputs"], hidden=hidden, negative_slope=spec["negative_slope"], seed=0
    )
    expected = network.state_dict()
    if set(arrays) != set(expected):
        raise ValueError(f"weights {sorted(arrays)} do not match the network {sorted(expected)}")
    state = {}
    for key, array in arrays.items():
        if tuple(array.shape) != tuple(expected[key].shape):
            raise ValueError(
                f"weight {key} has shape {array.shape}, expected {tuple(expected[key].shape)}"
            )
        state[key] = torch.from_numpy(array.copy())
    network.load_state_dict(state)
    intent = NeuralIntent(
        payload["name"],
        network,
        objects=objects,
        cost_scale=payload["cost_scale"],
        length_scale=payload["length_scale"],
        planner=PlannerConfig(**payload["planner"]),
        guides=[np.asarray(g, dtype=float) for g in payload["guides"]],
        cost_offset=payload["cost_offset"],
    )
    # Values in range can still overflow the network (a tiny length_scale): its cost at the
    # objects and along the guides must be finite, or inference would later meet NaN.
    probe = np.vstack(
        [np.column_stack([intent.objects, np.zeros(len(intent.objects))]), *intent.guides]
    )
    if not np.isfinite(intent.costs_of(probe)).all():
        raise LibraryError(path, "finite", "the cost is not finite at the objects or the guides")
    return intent


def find_libraries(folder: Path | str) -> list[Path]:
    """The libraries at or below ``folder``: itself if it holds intent files, else those below.

    A folder of participant folders, each a library, lists each of them (sorted); a
    folder without intent files anywhere below gives ``[]``.

    Examples
    --------
    >>> import tempfile
    >>> root = Path(tempfile.mkdtemp())
    >>> for part in ("p2/unknown_goal", "p1/unknown_goal"):
    ...     (root / part).mkdir(parents=True)
    ...     _ = (root / part / f"red{SUFFIX}").write_text("{}")
    >>> [path.relative_to(root).as_posix() for path in find_libraries(root)]
    ['p1/unknown_goal', 'p2/unknown_goal']
    >>> find_libraries(root / "p1" / "unknown_goal") == [root / "p1" / "unknown_goal"]
    True
    """
    folder = Path(folder)
    if any(folder.glob(f"*{SUFFIX}")):
        return [folder]
    return sorted({path.parent for path in folder.rglob(f"*{SUFFIX}")})


def scan_library(library: Path | str) -> tuple[list[LibraryEntry], list[LibraryError]]:
    """Every ``*.intent.json`` in ``library`` (sorted): the good ones and the problems.

    A bad file never hides the others. A missing folder is one problem.
    """
    library = Path(library)
    if not library.is_dir():
        return [], [LibraryError(library, "folder", "is not a folder")]
    entries, problems = [], []
    names: dict[str, Path] = {}
    for path in sorted(library.glob(f"*{SUFFIX}")):
        try:
            entry = load_intent(path)
        except LibraryError as error:
            problems.append(error)
            continue
        name = entry.metadata["name"]
        if name in names:
            problems.append(
                LibraryError(path, "unique-name", f"intent {name!r} is also in {names[name]}")
            )
            continue
        names[name] = path
        entries.append(entry)
    return entries, problems
