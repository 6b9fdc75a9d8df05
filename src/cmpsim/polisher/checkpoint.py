"""The checkpoint of a lot: what an interrupted lot needs to go on as if it had never stopped (issue 38).

After its set-up (the monitor wafers, the incoming profiles, the zone response) and after every
wafer, :func:`cmpsim.polisher.lot.run_lot` writes one JSON file, atomically
(:func:`cmpsim.io.atomic_write_text`: a kill -9 leaves the last complete checkpoint, never a
partial one). It holds:

- ``inputs``: every input that decides the lot's numbers (the recipe as parsed, the wafer count,
  conditioning, control and its weights, seed, overrides, idle time, time step, qualification,
  worn summits, a digest of given incoming profiles, the cmpsim version); a checkpoint whose
  inputs differ is refused, naming them (:class:`CheckpointMismatch`);
- ``next_wafer`` (0-based) and the ``records`` of the wafers done;
- the state carried from wafer to wafer: the pad (temperature column, worn volume, times), the rate
  estimator, the controller's own model of the pad's life (``model_life``: the worn volume it
  predicts from the polish times it commanded), the zone feedback's pressures and shape;
- the set-up, so that it is not recomputed: the rings' radii and area weights, the incoming
  profiles, the qualification record, the zone response.

Every float is written with ``repr`` (Python's shortest round-trip form), so a resumed lot
continues from bit-identical numbers. The solves of the last wafer (a cache that saves time, not
numbers) are not kept: the first wafer after a resume solves its equilibrium again.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._version import __version__
from ..io import atomic_write_text
from ..physics.padlife import PadLifeState
from ..physics.thermal import PadThermalState
from .engine import PadState

__all__ = ["FORMAT", "NAME", "LotCheckpoint", "CheckpointMismatch", "read_checkpoint", "write_checkpoint", "pad_state_to_dict",
           "pad_state_from_dict", "life_to_dict", "life_from_dict", "digest", "VERSION"]

#: The checkpoint's format tag.
FORMAT = "cmpsim-lot-checkpoint/2"
#: The checkpoint's file name in ``cmpsim lot --out DIR``.
NAME = "lot.checkpoint.json"
#: The code version a checkpoint is tied to (a resumed lot must run the same code to be identical).
VERSION = __version__


class CheckpointMismatch(ValueError):
    """A checkpoint written for other inputs (or another format or version) than the lot asked for."""


def digest(array) -> str | None:
    """SHA-256 of an array's float64 bytes and shape (given incoming profiles), or None."""
    if array is None:
        return None
    a = np.ascontiguousarray(np.asarray(array, dtype=float))
    return hashlib.sha256(repr(a.shape).encode() + a.tobytes()).hexdigest()


def pad_state_to_dict(pad: PadState) -> dict:
    """The pad carried between wafers as JSON-able lists and floats."""
    thermal = None if pad.thermal is None else {"temperature": np.asarray(pad.thermal.temperature, dtype=float).tolist(),
                                                "time": float(pad.thermal.time)}
    return {"thermal": thermal, "life": life_to_dict(pad.life), "time": float(pad.time)}


def life_to_dict(life) -> dict | None:
    """A pad-life state (worn volume, polish time) as JSON-able lists and floats; None for none."""
    if not isinstance(life, PadLifeState):
        return None
    worn = life.worn_volume
    return {"worn_volume": np.asarray(worn, dtype=float).tolist(), "array": isinstance(worn, np.ndarray) and np.ndim(worn) > 0,
            "polish_time": float(life.polish_time)}


def life_from_dict(data: dict | None) -> PadLifeState | None:
    """The inverse of :func:`life_to_dict`."""
    if data is None:
        return None
    worn = data["worn_volume"]
    worn = np.asarray(worn, dtype=float) if data["array"] else np.float64(worn)
    return PadLifeState(worn, float(data["polish_time"]))


def pad_state_from_dict(data: dict) -> PadState:
    """The inverse of :func:`pad_state_to_dict`."""
    thermal = None
    if data["thermal"] is not None:
        thermal = PadThermalState(np.asarray(data["thermal"]["temperature"], dtype=float), float(data["thermal"]["time"]))
    return PadState(thermal, life_from_dict(data["life"]), float(data["time"]))


@dataclass
class LotCheckpoint:
    """A lot's state between two wafers (see the module's docstring); JSON-able throughout."""

    inputs: dict
    next_wafer: int
    setup: dict
    pad_state: dict
    estimator: dict | None
    zones: dict | None
    records: list = field(default_factory=list)
    solves: int = 0
    #: the controller's model of the pad's life (:func:`life_to_dict`; None without control)
    model_life: dict | None = None
    #: the refitting controller's memory (:meth:`cmpsim.polisher.refit.RefitState.to_dict`; None without ``refit_model``)
    refit: dict | None = None

    def to_json(self) -> str:
        return json.dumps({"format": FORMAT, "version": VERSION, "inputs": self.inputs, "next_wafer": self.next_wafer,
                           "setup": self.setup, "pad_state": self.pad_state, "estimator": self.estimator, "zones": self.zones,
                           "records": self.records, "solves": self.solves, "model_life": self.model_life,
                           "refit": self.refit})


def write_checkpoint(path, checkpoint: LotCheckpoint) -> None:
    """Write ``checkpoint`` to ``path`` atomically."""
    atomic_write_text(Path(path), checkpoint.to_json())


def read_checkpoint(path, inputs: dict) -> LotCheckpoint | None:
    """The checkpoint at ``path`` if it exists (None otherwise), checked against the lot's ``inputs``.

    Raises :class:`CheckpointMismatch` naming the inputs that differ, or saying why the file is not
    a checkpoint of this lot."""
    path = Path(path)
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CheckpointMismatch(f"--resume: {str(path)!r} is not a lot checkpoint ({exc}); remove it or choose another --out") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise CheckpointMismatch(f"--resume: {str(path)!r} is not a lot checkpoint of format {FORMAT!r}; remove it or choose another --out")
    if data.get("version") != VERSION:
        raise CheckpointMismatch(f"--resume: {str(path)!r} was written by cmpsim {data.get('version')!r}, this is {VERSION!r}: a resumed lot "
                                 "must run the same code; remove the checkpoint to start the lot again")
    saved = data.get("inputs", {})
    differ = sorted(k for k in set(saved) | set(inputs) if saved.get(k) != inputs.get(k))
    if differ:
        detail = "; ".join(f"{k}: checkpoint {saved.get(k)!r}, now {inputs.get(k)!r}" for k in differ)
        raise CheckpointMismatch(f"--resume: the checkpoint {str(path)!r} belongs to a lot with other inputs ({detail}); "
                                 "run with the checkpoint's inputs, or remove it (or choose another --out) to start a new lot")
    return LotCheckpoint(saved, int(data["next_wafer"]), data["setup"], data["pad_state"], data["estimator"], data["zones"],
                         list(data["records"]), int(data["solves"]), data.get("model_life"), data.get("refit"))
