"""The settings search's folder (docs/results.md §1 and §7): its settings in a JSON file,
checked when it is resumed, and its finished points, one JSON line each, appended as they
finish; each path's reference as reference_PATH.npz beside them (`_measure.py`).

One store with two layouts, so that the files each command has always written keep their
names and lines: the one-knob sweep keeps sweep.json and points.jsonl, a point's setting
written as its `knob` and `value`; the joint search keeps joint.json and joint.jsonl, a
point's setting as `settings`. In memory every point holds `settings` (a one-knob point
`{knob: value}` as well as its knob and value). A folder holds one layout: each refuses
the other's.
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

from .._io._files import write_json, write_text
from ._knob_space import KnobSpace, OneKnobSpace
from ._knobs import SweepError
from ._measure import PATHS

__all__ = ["Store", "SWEEP_STORE", "JOINT_STORE", "store_of", "load_points", "load_joint"]

# What a config must agree on for its folder's points to be kept, and the value a key has
# in a config that does not hold it (a sweep's config before it recorded its timing).
_SAME = {"scene_digest": None, "repeats": None, "reference": None, "timing": "measured"}


@dataclasses.dataclass(frozen=True)
class Store:
    """A layout of the folder: `config` and `points`, its files; `one_knob`: its points
    are one-knob settings, written as `knob` and `value` (else as `settings`); `space`:
    the config's key holding the space; `title`: the search's name in progress lines and
    the report; `other`: the other layout's settings file, refused."""

    config: str
    points: str
    one_knob: bool
    space: str
    title: str
    other: str

    @property
    def required(self) -> tuple[str, ...]:
        """The keys every stored point holds: what a resumed run reads of it."""
        return ("path", "knob", "value") if self.one_knob else ("path", "settings")

    def space_of(self, config: dict) -> KnobSpace | OneKnobSpace:
        data = config[self.space]
        return OneKnobSpace.from_json(data) if self.one_knob else KnobSpace.from_json(data)

    def record(self, point: dict) -> dict:
        """A point as its line holds it."""
        if not self.one_knob:
            return point
        ((knob, value),) = point["settings"].items()
        rest = {k: v for k, v in point.items() if k not in ("path", "settings", "knob", "value")}
        return {"path": point["path"], "knob": knob, "value": value, **rest}

    def point(self, record: dict) -> dict:
        """A stored line as a point (`record`'s inverse)."""
        return {**record, "settings": {record["knob"]: record["value"]}} if self.one_knob else record

    def load(self, out) -> list[dict]:
        """The finished points in `out`. A last line cut short by an interruption is
        ignored: it is redone on resume.

        **Raises:** `SweepError` naming the file and the line for any other line that is
        not a JSON object holding `required`'s keys (a damaged or foreign file), rather
        than failing later on its content."""
        path = Path(out) / self.points
        if not path.exists():
            return []
        try:
            lines = path.read_text().splitlines()
        except (OSError, UnicodeDecodeError) as err:
            raise SweepError(f"{path}: cannot read the finished points: {err}") from None
        points = []
        for number, line in enumerate(lines, start=1):
            try:
                record = json.loads(line)
            except json.JSONDecodeError:
                if number == len(lines):
                    continue  # fires only for a last line cut short by a kill
                raise SweepError(
                    f"{path}:{number}: not a JSON line; remove the line or pass --restart"
                ) from None
            missing = [k for k in self.required if k not in record] if isinstance(record, dict) else None
            if missing is None or missing:
                what = f"a point without {', '.join(missing)}" if missing else "not a JSON object"
                raise SweepError(f"{path}:{number}: {what}; remove the line or pass --restart")
            points.append(self.point(record))
        return points

    def append(self, out, point: dict) -> dict:
        """Append one point, flushed to disk before the next render starts; return it as
        `load` will read it back."""
        record = self.record(point)
        with open(Path(out) / self.points, "a") as f:
            f.write(json.dumps(record) + "\n")
            f.flush()
            os.fsync(f.fileno())
        return self.point(record)

    def rewrite(self, out, points: list[dict]) -> None:
        """Rewrite the points file with `points`: drops a line cut short, so the next
        append starts a fresh line."""
        write_text(Path(out) / self.points, "".join(json.dumps(self.record(p)) + "\n" for p in points))

    def check_config(self, out: Path, config: dict, restart: bool) -> None:
        """Write `config` to the folder, after checking that its finished points were
        measured with the same scene, repeats, reference and timing (a SweepError if not,
        unless `restart`, which removes them and the references). A folder holding the
        other layout's settings file is refused."""
        if (out / self.other).exists():
            raise SweepError(f"{out} holds another kind of sweep ({self.other}); choose another --out")
        path = out / self.config
        if path.exists() and not restart:
            old = _read_config(path)
            if any(old.get(k, default) != config[k] for k, default in _SAME.items()):
                raise SweepError(
                    f"{out} holds a sweep of other settings ({old.get('scene')}, "
                    f"repeats {old.get('repeats')}); choose another --out or pass --restart"
                )
        if restart:
            for file in (self.points, *[f"reference_{p}.npz" for p in PATHS]):
                (out / file).unlink(missing_ok=True)
        write_json(path, config)


# The files each command has always written.
SWEEP_STORE = Store(
    config="sweep.json",
    points="points.jsonl",
    one_knob=True,
    space="knobs",
    title="sweep",
    other="joint.json",
)
JOINT_STORE = Store(
    config="joint.json",
    points="joint.jsonl",
    one_knob=False,
    space="space",
    title="joint search",
    other="sweep.json",
)


def store_of(config: dict) -> Store:
    """The layout whose settings file `config` is: a joint search's holds its `space`."""
    return JOINT_STORE if JOINT_STORE.space in config else SWEEP_STORE


def load_points(out) -> list[dict]:
    """The one-knob sweep's finished points in `out` (`Store.load`)."""
    return SWEEP_STORE.load(out)


def load_joint(out) -> list[dict]:
    """The joint search's finished points in `out`, every path's (`Store.load`)."""
    return JOINT_STORE.load(out)


def _read_config(path: Path) -> dict:
    """A search's settings file as a JSON object; SweepError naming it otherwise."""
    try:
        old = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise SweepError(f"{path}: damaged settings file ({err}); pass --restart to start afresh") from None
    if not isinstance(old, dict):
        raise SweepError(f"{path}: damaged settings file (not a JSON object); pass --restart to start afresh")
    return old
