"""The tables and keys a scene file may hold (docs/scenes.md), and the keys each
registered shading model, shadow method and ordering reads."""

from __future__ import annotations

import dataclasses
from typing import Any

from .._geometry._ordering import ordering_class, ordering_names
from .._geometry._shadows import shadow_method_class, shadow_method_names
from .._shading import shading_model_class, shading_model_names
from ._hair_table import HAIR_KEYS
from ._reference import REFERENCE_KEYS

__all__ = ["scene_tables", "choice_keys", "field_names", "TOP_LEVEL_KEYS", "PATCH_KEYS", "CHOICES"]

_FIXED_TABLES: dict[str, tuple[str, ...]] = {
    "hair": HAIR_KEYS,
    "camera": (
        "frame",
        "eye",
        "target",
        "up",
        "fov",
        "width",
        "height",
        "near",
        "azimuth",
        "elevation",
        "zoom",
    ),
    "light": ("kind", "direction", "position", "color"),
    "occluder": ("kind", "center", "radius", "color", "path"),
    "background": ("color",),
    "streaks": ("texels", "width", "contrast", "seed"),
    # Read by `hairjax animate` only (hairjax/_animate.py); a still render shows the rest pose.
    "animation": ("amplitude", "frequency", "phase", "inertia", "frames"),
    # Read by `hairjax reference` only (hairjax/_reference/): the fibres' BSDF and the path tracer.
    "reference": REFERENCE_KEYS,
}
TOP_LEVEL_KEYS = ("name",)
# [hair]'s keys that `read_patches` reads into `Scene.patches`.
PATCH_KEYS = (
    "geometry",
    "patch_width",
    "opaque_core",
    "patch_strands",
    "patch_strand_alpha",
    "patch_strand_tips",
)


def _union(groups) -> tuple[str, ...]:
    return tuple(dict.fromkeys(k for keys in groups for k in keys))


def scene_tables() -> dict[str, tuple[str, ...]]:
    """Every table of a scene file and the keys it may hold. [shading], [shadows] and
    [ordering] take the keys of every registered model, method and ordering."""
    tables = dict(_FIXED_TABLES)
    tables["shading"] = ("model",) + _union(shading_model_class(n).table_keys for n in shading_model_names())
    tables["shadows"] = ("method",) + _union(
        tuple(f.name for f in dataclasses.fields(shadow_method_class(n))) for n in shadow_method_names()
    )
    tables["ordering"] = ("method",) + _union(
        tuple(f.name for f in dataclasses.fields(ordering_class(n))) for n in ordering_names()
    )
    order = (
        "hair",
        "camera",
        "light",
        "shading",
        "shadows",
        "ordering",
        "occluder",
        "background",
        "streaks",
        "animation",
        "reference",
    )
    return {name: tables[name] for name in order}


def field_names(cls) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(cls))


def choice_keys(table: str, choice: Any) -> tuple[str, ...] | None:
    """The keys (besides the choice's own) that `table`'s `choice` reads, or None for a
    name that is not registered (refused later, with the allowed names)."""
    if table == "shading":
        cls = shading_model_class(choice) if choice in shading_model_names() else None
        return None if cls is None else cls.table_keys
    names, lookup = (
        (shadow_method_names(), shadow_method_class)
        if table == "shadows"
        else (ordering_names(), ordering_class)
    )
    return field_names(lookup(choice)) if choice in names else None


# The tables whose one key chooses a registered class, that key and the default choice.
CHOICES = (
    ("shading", "model", "kajiya-kay"),
    ("shadows", "method", "opacity-maps"),
    ("ordering", "method", "bins"),
)
