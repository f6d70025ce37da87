"""A sweep's folder (docs/results.md §1): its settings in a JSON file, checked when it is
resumed, and its finished points, one JSON line each, appended as they finish.

The one-knob sweep keeps sweep.json and points.jsonl, the joint search joint.json and
joint.jsonl; both keep each path's reference as reference_PATH.npz (`_measure.py`). A
folder holds one of them: each refuses the other's.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path

from .._io._files import write_json, write_text
from ._knobs import SweepError
from ._measure import PATHS

__all__ = ["load_points", "append_point", "rewrite_points", "check_config"]

# What a config must agree on for its folder's points to be kept.
_SAME = ("scene_digest", "repeats", "reference")
# The keys every stored point holds, by file: what a resumed run reads of it.
_REQUIRED = {"points.jsonl": ("path", "knob", "value"), "joint.jsonl": ("path", "settings")}


def load_points(out, name: str = "points.jsonl") -> list[dict]:
    """The finished points in `out`/`name`, each a JSON object holding the keys its kind
    of sweep reads (`_REQUIRED`).
    A last line cut short by an interruption is ignored: it is redone on resume.

    **Raises:** `SweepError` naming the file and the line for any other line that is not
    such an object (a damaged or foreign file), rather than failing later on its content.
    """
    path = Path(out) / name
    if not path.exists():
        return []
    try:
        lines = path.read_text().splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise SweepError(f"{path}: cannot read the finished points: {err}") from None
    points = []
    for number, line in enumerate(lines, start=1):
        try:
            point = json.loads(line)
        except json.JSONDecodeError:
            if number == len(lines):
                continue  # fires only for a last line cut short by a kill
            raise SweepError(f"{path}:{number}: not a JSON line; remove the line or pass --restart") from None
        missing = [k for k in _REQUIRED.get(name, ()) if k not in point] if isinstance(point, dict) else None
        if missing is None or missing:
            what = f"a point without {', '.join(missing)}" if missing else "not a JSON object"
            raise SweepError(f"{path}:{number}: {what}; remove the line or pass --restart")
        points.append(point)
    return points


def append_point(out, point: dict, name: str = "points.jsonl") -> None:
    """Append one point, flushed to disk before the next render starts."""
    with open(Path(out) / name, "a") as f:
        f.write(json.dumps(point) + "\n")
        f.flush()
        os.fsync(f.fileno())


def rewrite_points(out, points: list[dict], name: str = "points.jsonl") -> None:
    """Rewrite the file with `points`: drops a line cut short, so the next append starts a
    fresh line."""
    write_text(Path(out) / name, "".join(json.dumps(p) + "\n" for p in points))


def check_config(
    out: Path,
    config: dict,
    restart: bool,
    name: str,
    points: str,
    others: Sequence[str] = (),
    keys: Sequence[str] = (),
) -> None:
    """Write `config` to `out`/`name`, after checking that the folder's finished points
    (`points`) were measured with the same scene, repeats and reference, and `keys` (a
    SweepError if not, unless `restart`, which removes them and the references). A folder
    holding one of `others` (the other kind of sweep's config) is refused."""
    for other in others:
        if (out / other).exists():
            raise SweepError(f"{out} holds another kind of sweep ({other}); choose another --out")
    path = out / name
    if path.exists() and not restart:
        old = _read_config(path)
        same = {k: old.get(k) for k in (*_SAME, *keys)}
        if same != {k: config[k] for k in same}:
            raise SweepError(
                f"{out} holds a sweep of other settings ({old.get('scene')}, "
                f"repeats {old.get('repeats')}); choose another --out or pass --restart"
            )
    if restart:
        for file in (points, *[f"reference_{p}.npz" for p in PATHS]):
            (out / file).unlink(missing_ok=True)
    write_json(path, config)


def _read_config(path: Path) -> dict:
    """A sweep's settings file as a JSON object; SweepError naming it otherwise."""
    try:
        old = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise SweepError(f"{path}: damaged settings file ({err}); pass --restart to start afresh") from None
    if not isinstance(old, dict):
        raise SweepError(f"{path}: damaged settings file (not a JSON object); pass --restart to start afresh")
    return old
