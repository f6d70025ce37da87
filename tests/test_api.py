"""The public names are listed in one place, docs/api.md: this fails when the page and the
code disagree, name by name, for each of the four namespaces."""

from __future__ import annotations

import importlib
import re
import types
from pathlib import Path

import pytest

API = Path(__file__).resolve().parents[1] / "docs" / "api.md"
NAMESPACES = ("hairjax", "hairjax.extend", "hairjax.experimental", "hairjax.tools")
SUBMODULES = {"experimental", "extend"}  # hairjax's namespaces, listed as such


def documented(text: str) -> dict[str, set[str]]:
    """Each `## \\`namespace\\`` section's backquoted names (those that are identifiers)."""
    sections = re.split(r"^## `([\w.]+)`$", text, flags=re.M)
    names: dict[str, set[str]] = {}
    for title, body in zip(sections[1::2], sections[2::2], strict=True):
        # A name is a backquoted identifier in the first column of a table or in a bold
        # paragraph's list; §-references and file names are not identifiers.
        cells = [line.split("|")[1] for line in body.splitlines() if line.startswith("| `")]
        listed = re.findall(r"`([A-Za-z_]\w*)`", " ".join(cells))
        listed += re.findall(r"`([A-Za-z_]\w*)` \(", body)  # "`SceneError` (…)" paragraphs
        for line in re.findall(r"^\*\*Namespaces:\*\* (.*)$", body, flags=re.M):
            listed += re.findall(r"`(\w+)`", line)
        names[title] = set(listed)
    return names


@pytest.mark.parametrize("namespace", NAMESPACES)
def test_api_page_lists_every_public_name(namespace):
    module = importlib.import_module(namespace)
    # hairjax and its namespaces declare __all__; hairjax.tools re-exports with `as`.
    public = getattr(module, "__all__", None) or [
        n for n, v in vars(module).items() if not n.startswith("_") and not isinstance(v, types.ModuleType)
    ]
    exported = {n for n in public if not n.startswith("__")}
    listed = documented(API.read_text(encoding="utf-8"))[namespace]
    assert exported - listed == set(), f"{namespace}: public but not in docs/api.md"
    assert listed - exported == set(), f"{namespace}: in docs/api.md but not public"


def test_the_page_parser_finds_names_and_only_names():
    text = (
        "## `a`\n\n| name | what |\n|---|---|\n| `x`, `Y` | see `z` and §3 |\n\n"
        "**Errors:** `E` (bad).\n\n**Namespaces:** `sub`\n\n## `b`\n\n| `w` | `docs/x.md` |\n"
    )
    assert documented(text) == {"a": {"x", "Y", "E", "sub"}, "b": {"w"}}


def test_hairjax_stays_small():
    """About fifty names a user needs (docs/api.md: 63 today, with the two namespaces); the
    rest is in the namespaces. The bound stops the face from growing back unnoticed: a name
    past it belongs in `extend` or `experimental`, or the page says why it does not."""
    import hairjax

    assert len(hairjax.__all__) <= 64, len(hairjax.__all__)
