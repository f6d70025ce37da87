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


def load_points(out, name: str = "points.jsonl") -> list[dict]:
    """The finished points in `out`/`name` (a line cut short by an interruption is
    ignored: it is redone on resume)."""
    path = Path(out) / name
    if not path.exists():
        return []
    points = []
    for line in path.read_text().splitlines():
        try:
            points.append(json.loads(line))
        except json.JSONDecodeError:
            continue  # fires only for a last line cut short by a kill
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
        old = json.loads(path.read_text())
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
