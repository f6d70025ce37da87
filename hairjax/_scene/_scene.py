"""The scene: what to render, as plain immutable values.

A `Scene` is configuration, not a pytree: the geometry stage reads it with NumPy, and the
shading stage takes its differentiable parameters from its shading model
(`Scene.shading.params`, also `Scene.params`). Construction validates every value, so a
`Scene` that exists can be rendered.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np

from .._errors import SceneError
from .._geometry._ordering import AbstractOrdering, DepthBins
from .._geometry._shadows import AbstractShadowMethod, OpacityMaps
from .._shading import AbstractShadingModel, KajiyaKay, Streaks
from .._values._camera import Camera
from .._values._light import Light, rgb
from .._values._strands import Strands
from ._occluder import Occluder
from ._reference import ReferenceSettings

__all__ = ["PatchGeometry", "Scene"]


@dataclasses.dataclass(frozen=True)
class PatchGeometry:
    """Draw the strands as polygonal hair patches (docs/model.md §18, scheuermann-2004
    slides 4–6, 14–17): ribbons `width` world units wide, drawn with slide 17's four
    passes, with an alpha texture of `strands` strands side by side across each patch,
    each with an opaque core of fraction `opaque_core`; the semi-transparent strands peak
    at `strand_alpha` or more, and the strands end up to `tips` of the patch's length
    before its tip."""

    width: float
    opaque_core: float = 0.5
    strands: int = 1
    strand_alpha: float = 1.0
    tips: float = 0.0

    def __post_init__(self):
        w = self.width
        if isinstance(w, bool) or not isinstance(w, (int, float)) or not (np.isfinite(w) and w > 0):
            raise SceneError(f"hair.patch_width must be a positive finite number, got {w!r}")
        for key, name in (
            ("opaque_core", "opaque_core"),
            ("strand_alpha", "patch_strand_alpha"),
            ("tips", "patch_strand_tips"),
        ):
            c = getattr(self, key)
            if isinstance(c, bool) or not isinstance(c, (int, float)) or not 0 <= c <= 1:
                raise SceneError(f"hair.{name} must be a number in [0, 1], got {c!r}")
            object.__setattr__(self, key, float(c))
        n = self.strands
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise SceneError(f"hair.patch_strands must be an integer ≥ 1, got {n!r}")
        object.__setattr__(self, "width", float(w))
        object.__setattr__(self, "strands", int(n))


@dataclasses.dataclass(frozen=True, eq=False)
class Scene:
    """Everything needed to render one image.

    `shading`: the shading model with its differentiable parameters (`KajiyaKay`,
    `KajiyaKayMirror`, `KajiyaKayLookup`, `Scheuermann`, or any registered model,
    docs/architecture.md); `scene.params` is `scene.shading.params`. `shadows`: the
    self-shadowing method (`Shadows(...)`, docs/model.md §7); `ordering`: the visibility
    order (`Ordering(...)`, §4). `streaks`: wenzel-2002's streak texture along the hairs
    (§16), or None. `patches`: draw the strands as hair patches (§18) instead of ribbons,
    or None; the strands' opacity maps still give the self-shadows; an occluder is the
    head, drawn first.
    `reference`: the fibres and path tracer of the physically based reference
    (`hairjax.reference_image`, docs/reference.md), or None for `ReferenceSettings()`;
    the JAX and GL renderers do not read it.
    `file_tables`: the scene file's tables a Scene holds no values for, as `load_scene`
    read them: `[hair]` (the generator's or the file's keys, a file path resolved), from
    which `strands` came, and `[animation]`; `save_scene` writes them back. None for a
    scene built in Python; `replace(strands=…)` drops `[hair]`.
    """

    strands: Strands
    camera: Camera = Camera()
    light: Light = Light()
    shading: AbstractShadingModel = dataclasses.field(default_factory=KajiyaKay)
    shadows: AbstractShadowMethod = OpacityMaps()
    ordering: AbstractOrdering = DepthBins()
    occluder: Occluder | None = None
    background: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str = "scene"
    streaks: Streaks | None = None
    patches: PatchGeometry | None = None
    reference: ReferenceSettings | None = None
    file_tables: Mapping[str, Mapping[str, Any]] | None = None

    def __post_init__(self):
        for key, kind in (
            ("strands", Strands),
            ("camera", Camera),
            ("light", Light),
            ("shading", AbstractShadingModel),
            ("shadows", AbstractShadowMethod),
            ("ordering", AbstractOrdering),
        ):
            if not isinstance(getattr(self, key), kind):
                raise SceneError(
                    f"scene.{key} must be a {kind.__name__}, got {type(getattr(self, key)).__name__}"
                )
        if self.streaks is not None and not isinstance(self.streaks, Streaks):
            raise SceneError("scene.streaks must be a Streaks or None")
        object.__setattr__(self, "background", rgb("background.color", self.background))
        if self.reference is not None and not isinstance(self.reference, ReferenceSettings):
            raise SceneError("scene.reference must be a ReferenceSettings or None")
        if self.patches is not None:
            if not isinstance(self.patches, PatchGeometry):
                raise SceneError("scene.patches must be a PatchGeometry or None")

    @property
    def params(self):
        """The shading model's parameters (`scene.shading.params`)."""
        return self.shading.params

    def replace(self, **changes) -> Scene:
        """A copy with some fields changed; `params=` replaces the shading model's
        parameters (`scene.shading.replace_params`)."""
        if "params" in changes:
            shading = changes.pop("shading", self.shading)
            changes["shading"] = shading.replace_params(changes.pop("params"))
        if "strands" in changes and "file_tables" not in changes and self.file_tables is not None:
            # The [hair] table no longer describes the strands.
            changes["file_tables"] = {k: v for k, v in self.file_tables.items() if k != "hair"}
        return dataclasses.replace(self, **changes)
