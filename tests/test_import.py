"""`import hairjax` loads nothing heavy: not JAX (the package is lazy, `__init__.pyi`), not
the tools (hairjax.tools: the benchmark, the sweep, the reports) nor what only they or the
notebook panel need (matplotlib, rich, ipywidgets). The CLI imports them inside the
subcommands that use them, after the arguments parse."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
HEAVY = ("matplotlib", "rich", "ipywidgets", "hairjax.tools", "jax")


def _loaded_after(module: str) -> list[str]:
    """The modules of HEAVY that `import module` loads, in a fresh interpreter."""
    code = (
        f"import json, sys, {module}; print(json.dumps([m for m in sys.modules if m.startswith({HEAVY!r})]))"
    )
    # This checkout's hairjax, installed or not.
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join(p for p in (str(REPO), os.environ.get("PYTHONPATH")) if p)
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, cwd=REPO, check=True, capture_output=True, text=True
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


@pytest.mark.parametrize("module", ["hairjax", "hairjax.cli"])
def test_import_loads_no_tools(module):
    assert _loaded_after(module) == []


def test_the_check_sees_the_tools():
    """The check above can fail: importing the tools shows them."""
    assert "hairjax.tools" in _loaded_after("hairjax.tools")
