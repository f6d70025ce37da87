"""The Makefile's JAX_EXTRA: `make run JAX_EXTRA=cuda` installs the `cuda` extra (JAX's
CUDA build), into a stamp of its own so that a CPU install gains it; a value it does not
know stops make with one line. Read with `make -n` (nothing is run), against an empty
virtual environment's folder so that every install step is listed."""

from __future__ import annotations

import shutil
import subprocess
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.skipif(shutil.which("make") is None, reason="needs make")


def _dry_run(tmp_path, *variables) -> subprocess.CompletedProcess:
    return subprocess.run(
        ["make", "-n", "-C", str(REPO), "run", f"VENV={tmp_path / 'venv'}", *variables],
        capture_output=True,
        text=True,
    )


def test_jax_extra_cuda_installs_the_cuda_extra(tmp_path):
    run = _dry_run(tmp_path, "JAX_EXTRA=cuda")
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert f"{tmp_path / 'venv'}/bin/python -m pip install --quiet -e '.[cuda]'" in lines
    assert f"touch {tmp_path / 'venv'}/.installed-cuda" in lines
    # The CUDA build goes on after the base install, and before the render.
    install = next(i for i, line in enumerate(lines) if "'.[cuda]'" in line)
    render = next(i for i, line in enumerate(lines) if "hairjax render" in line)
    assert any("pip install" in line for line in lines[:install]) and install < render


def test_without_jax_extra_nothing_cuda(tmp_path):
    run = _dry_run(tmp_path)
    assert run.returncode == 0, run.stderr
    assert "cuda" not in run.stdout
    assert f"touch {tmp_path / 'venv'}/.installed" in run.stdout.splitlines()


def test_an_unknown_jax_extra_stops_make(tmp_path):
    run = _dry_run(tmp_path, "JAX_EXTRA=gpu")
    assert run.returncode != 0
    assert "JAX_EXTRA must be cuda or empty, got 'gpu'" in run.stderr
    assert "pip install" not in run.stdout


def test_the_cuda_extra_is_jax_cuda_build():
    extras = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert any(req.startswith("jax[cuda12]") for req in extras["cuda"]), extras["cuda"]
