"""experiments/13_device_floor.py runs end to end (BENCHMARKS.md "The device-resident
set-up on this CPU")."""

from __future__ import annotations

import re

import pytest
from helpers import load_experiment


@pytest.mark.slow
def test_device_floor_runs(capsys):
    argv = ["--strands", "200", "--size", "32", "--repeats", "1"]
    assert load_experiment("13_device_floor").main(argv) == 0
    out = capsys.readouterr().out
    assert "200 strands at 32²" in out
    times = dict(re.findall(r"^ +(\S.*?) +([0-9.]+) ms$", out, flags=re.M))
    parts = ("sort F keys: XLA, packed uint64 keys only", "compaction to F: XLA nonzero")
    assert {"GL render", *parts} <= set(times)
    # The floor is the sum of its parts as printed (each rounded to 1 ms).
    floor = next(float(v) for k, v in times.items() if k.startswith("floor"))
    summed = sum(float(times[k]) for k in parts) + float(times["geometry opacity + shading (JAX)"])
    assert abs(floor - summed) <= 2.0
    assert re.search(r"floor / GL render: [0-9.]+$", out, flags=re.M)
