"""experiments/12_views_batch.py runs end to end (BENCHMARKS.md "Batched views")."""

from __future__ import annotations

import re

import pytest
from helpers import load_experiment


@pytest.mark.slow
def test_views_batch_runs(capsys):
    # A 500-strand ball: the same code path as the default 20,000 (which only take longer).
    argv = ["--size", "24", "--views", "2", "--repeats", "1", "--strands", "500"]
    assert load_experiment("12_views_batch").main(argv) == 0
    out = capsys.readouterr().out
    assert "2 views of 24², 500 strands" in out
    times = [float(t) for t in re.findall(r"shading, [^:]+: +([0-9.]+) ms", out)]
    assert len(times) == 2 and all(t > 0 for t in times)
    firsts = re.search(r"first render of each view +: (.*)", out).group(1).split(", ")
    assert len(firsts) == 2 and all(float(t.removesuffix(" ms")) > 0 for t in firsts)
    assert re.search(r"its fragments \(bucket\) +: [0-9,]+ \([0-9,]+\), [0-9,]+ \([0-9,]+\)", out)
