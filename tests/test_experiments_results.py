"""experiments/results.py --quick: every section of docs/results.md is regenerated."""

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_results_quick(tmp_path, gl):
    spec = importlib.util.spec_from_file_location("results", ROOT / "experiments" / "results.py")
    results = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(results)
    docs = tmp_path / "docs"
    assert results.main(["--quick", "--out", str(tmp_path / "out"), "--docs", str(docs)]) == 0
    text = (docs / "results.md").read_text()
    for heading in ("## 1. Error against run time", "## 2. kim-2003 Fig. 16", "## 3. kim-2003 Fig. 8",
                    "## 4. kim-2003 §3", "## 5. Stiff fits", "Cheapest settings reaching 1.0%"):
        assert heading in text, heading
    for figure in ("sweep_pareto.png", "maps_vs_time.png", "order_reuse.png"):
        assert f"figures/{figure}" in text
        assert (docs / "figures" / figure).read_bytes()[:4] == b"\x89PNG"
    assert "python experiments/results.py --quick" in text
