"""Every ```python block of README.md runs, top to bottom, as a reader would paste it.

Each block runs in a fresh namespace, in a folder laid out like a clone (every top-level
entry of the repository linked into it, so `experiments/scenes/…` and `../shared/data/…`
resolve as they do from the repository root) whose `out/` and new files are the test's
own, so a block that writes leaves nothing in the repository. A block that reads the
shared hair assets is skipped, saying so, where `../shared/data` is not there.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
SHARED = REPO.parent / "shared"
# A fenced block opened by ```python alone on its line, up to the next ``` line.
PYTHON_BLOCK = re.compile(r"^```python[ \t]*\n(.*?)^```[ \t]*$", re.MULTILINE | re.DOTALL)


def python_blocks(text: str) -> list[str]:
    return [m.group(1) for m in PYTHON_BLOCK.finditer(text)]


BLOCKS = python_blocks(README.read_text())


@pytest.fixture
def clone(tmp_path, monkeypatch):
    """A working directory shaped like the repository's, writes going to `tmp_path`."""
    root = tmp_path / "hairjax"
    root.mkdir()
    for entry in REPO.iterdir():
        if entry.name not in ("out", ".git", ".venv"):
            (root / entry.name).symlink_to(entry)
    if SHARED.exists():
        (tmp_path / "shared").symlink_to(SHARED)
    monkeypatch.chdir(root)
    return root


def test_the_readme_has_python_blocks():
    assert BLOCKS, "README.md has no ```python block"


def test_blocks_are_found():
    text = "x\n```python\na = 1\n```\n```sh\nmake\n```\n```python\nb = 2\n\nc = 3\n```\n"
    assert python_blocks(text) == ["a = 1\n", "b = 2\n\nc = 3\n"]


@pytest.mark.parametrize("block", BLOCKS, ids=[f"block{i + 1}" for i in range(len(BLOCKS))])
def test_the_block_runs(block, clone):
    if "../shared/data" in block and not (SHARED / "data").is_dir():
        pytest.skip(f"the block reads hair assets from {SHARED / 'data'}, which is not here")
    code = compile(block, f"README.md python block:\n{block}", "exec")
    exec(code, {"__name__": "__readme__"})
