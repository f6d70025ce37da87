"""The scene: what to render, as plain immutable values.

A `Scene` is configuration, not a pytree: the geometry stage reads it with NumPy, and the
shading stage takes its differentiable parameters from its shading model
(`Scene.shading.params`, also `Scene.params`). Construction validates every value, so a
`Scene` that exists can be rendered.
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np

from ._constants import NEAR_FRACTION
from ._errors import SceneError
from ._light import Light, rgb, vec3
from ._ordering import AbstractOrdering, DepthBins
from ._shading import AbstractShadingModel, KajiyaKay, Streaks
from ._shadows import AbstractShadowMethod, OpacityMaps
from ._strands import Strands

__all__ = ["Camera", "Light", "Occluder", "PatchGeometry", "Scene", "OCCLUDER_KINDS"]


@dataclasses.dataclass(frozen=True)
class Camera:
    """Pinhole look-at camera. `fov` is the vertical field of view in degrees.

    Images are `[height, width, 4]`, row 0 at the top; pixel (i, j) has its centre at
    (i + 0.5, j + 0.5); `target` projects to (width/2, height/2); world `up` is up.
    `near` (world units) defaults to NEAR_FRACTION (1e-3) × |target − eye|; segments with an endpoint
    nearer than it are not drawn. `offset` (pixels, each in [-0.5, 0.5]) shifts the image:
    `target` projects to (width/2 + offset[0], height/2 + offset[1]); supersampling averages
    images rendered with a grid of such offsets (`hairjax.supersample`).
    """

    eye: tuple[float, float, float] = (0.0, 0.0, 4.0)
    target: tuple[float, float, float] = (0.0, 0.0, 0.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fov: float = 40.0
    width: int = 512
    height: int = 512
    near: float | None = None
    offset: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self):
        eye = vec3("camera.eye", self.eye)
        target = vec3("camera.target", self.target)
        up = vec3("camera.up", self.up, nonzero=True)
        d = np.subtract(target, eye)
        if not np.linalg.norm(d) > 0:
            raise SceneError("camera.eye and camera.target must differ")
        if not np.linalg.norm(np.cross(d, up)) > 1e-12 * np.linalg.norm(d) * np.linalg.norm(up):
            raise SceneError("camera.up must not be parallel to the view direction")
        if not (0 < float(self.fov) < 180):
            raise SceneError(f"camera.fov must be in (0, 180) degrees, got {self.fov!r}")
        for key in ("width", "height"):
            v = getattr(self, key)
            if isinstance(v, bool) or int(v) != v or not (1 <= int(v) <= 16384):
                raise SceneError(f"camera.{key} must be an integer in [1, 16384], got {v!r}")
        near = self.near
        if near is None:
            near = NEAR_FRACTION * float(np.linalg.norm(d))
        if not (np.isfinite(near) and near > 0):
            raise SceneError(f"camera.near must be positive, got {self.near!r}")
        try:
            offset = np.asarray(self.offset, dtype=np.float64)
        except (TypeError, ValueError):
            offset = np.full(1, np.nan)  # not numbers: refused below
        if offset.shape != (2,) or not np.all(np.abs(offset) <= 0.5):
            raise SceneError(f"camera.offset must be two numbers in [-0.5, 0.5], got {self.offset!r}")
        for key, v in (("eye", eye), ("target", target), ("up", up), ("fov", float(self.fov)),
                       ("width", int(self.width)), ("height", int(self.height)),
                       ("near", float(near)), ("offset", (float(offset[0]), float(offset[1])))):
            object.__setattr__(self, key, v)


OCCLUDER_KINDS = ("sphere", "mesh")


@dataclasses.dataclass(frozen=True)
class Occluder:
    """An opaque Lambertian occluder drawn before the hair; hair behind it is hidden, it
    receives the hair's shadow and casts its own (docs/model.md §9, §13).

    `kind="sphere"`: `center`, `radius`. `kind="mesh"`: a triangle mesh, from an OBJ file
    at `path` (read at construction) or given as `vertices` (`[V, 3]`) and `triangles`
    (`[F, 3]`, 0-based). Both are in the hair's world coordinates.
    """

    kind: Literal["sphere", "mesh"] = "sphere"
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    radius: float = 1.0
    color: tuple[float, float, float] = (0.5, 0.5, 0.5)
    path: str | None = None
    vertices: np.ndarray | None = dataclasses.field(default=None, compare=False, repr=False)
    triangles: np.ndarray | None = dataclasses.field(default=None, compare=False, repr=False)

    def __post_init__(self):
        if self.kind not in OCCLUDER_KINDS:
            raise SceneError(f"occluder.kind must be one of {OCCLUDER_KINDS}, got {self.kind!r}")
        object.__setattr__(self, "center", vec3("occluder.center", self.center))
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise SceneError(f"occluder.radius must be positive, got {self.radius!r}")
        object.__setattr__(self, "radius", float(self.radius))
        object.__setattr__(self, "color", rgb("occluder.color", self.color))
        if self.kind == "sphere":
            if self.path is not None or self.vertices is not None or self.triangles is not None:
                raise SceneError("occluder.path, vertices and triangles are for kind 'mesh' only")
            return
        vertices, triangles = self.vertices, self.triangles
        if self.path is not None:
            if vertices is not None or triangles is not None:
                raise SceneError("occluder: give either path or vertices and triangles, not both")
            from ._io._obj import load_obj  # Lazy: only mesh occluders need the reader.

            try:
                vertices, triangles = load_obj(self.path)
            except ValueError as e:  # MeshFormatError names the file and line
                raise SceneError(f"occluder.path could not be loaded: {e}") from e
        elif vertices is None or triangles is None:
            raise SceneError("occluder kind 'mesh' needs path, or vertices and triangles")
        vertices = np.array(vertices, dtype=np.float64)
        triangles = np.array(triangles)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or not np.all(np.isfinite(vertices)):
            raise SceneError(f"occluder.vertices must be finite [V, 3], got shape {vertices.shape}")
        if (triangles.ndim != 2 or triangles.shape[1] != 3 or len(triangles) == 0
                or not np.issubdtype(triangles.dtype, np.integer)):
            raise SceneError(f"occluder.triangles must be integer [F, 3] with F ≥ 1, got "
                             f"shape {triangles.shape} and dtype {triangles.dtype}")
        if triangles.min() < 0 or triangles.max() >= len(vertices):
            raise SceneError(f"occluder.triangles index outside [0, {len(vertices)})")
        vertices.setflags(write=False)
        triangles = triangles.astype(np.int32)
        triangles.setflags(write=False)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "triangles", triangles)

    def __eq__(self, other):
        if not isinstance(other, Occluder):
            return NotImplemented
        same = (self.kind, self.center, self.radius, self.color, self.path) == (
            other.kind, other.center, other.radius, other.color, other.path)
        if not same or self.kind == "sphere":
            return same
        return (np.array_equal(self.vertices, other.vertices)
                and np.array_equal(self.triangles, other.triangles))


@dataclasses.dataclass(frozen=True)
class PatchGeometry:
    """Draw the strands as polygonal hair patches (docs/model.md §18, scheuermann-2004
    slides 4–6, 14–17): ribbons `width` world units wide, alpha texture with an opaque
    core of fraction `opaque_core`, drawn with slide 17's four passes."""

    width: float
    opaque_core: float = 0.5

    def __post_init__(self):
        w = self.width
        if isinstance(w, bool) or not isinstance(w, (int, float)) or not (np.isfinite(w) and w > 0):
            raise SceneError(f"hair.patch_width must be a positive finite number, got {w!r}")
        c = self.opaque_core
        if isinstance(c, bool) or not isinstance(c, (int, float)) or not 0 <= c <= 1:
            raise SceneError(f"hair.opaque_core must be a number in [0, 1], got {c!r}")
        object.__setattr__(self, "width", float(w))
        object.__setattr__(self, "opaque_core", float(c))


@dataclasses.dataclass(frozen=True, eq=False)
class Scene:
    """Everything needed to render one image.

    `shading`: the shading model with its differentiable parameters (`KajiyaKay`,
    `KajiyaKayMirror`, `KajiyaKayLookup`, `Scheuermann`, or any registered model,
    docs/architecture.md); `scene.params` is `scene.shading.params`. `shadows`: the
    self-shadowing method (`Shadows(...)`, docs/model.md §7); `ordering`: the visibility
    order (`Ordering(...)`, §4). `streaks`: wenzel-2002's streak texture along the hairs
    (§16), or None. `patches`: draw the strands as hair patches (§18) instead of ribbons,
    or None; the strands' opacity maps still give the self-shadows; no occluder.
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

    def __post_init__(self):
        for key, kind in (("strands", Strands), ("camera", Camera), ("light", Light),
                          ("shading", AbstractShadingModel), ("shadows", AbstractShadowMethod),
                          ("ordering", AbstractOrdering)):
            if not isinstance(getattr(self, key), kind):
                raise SceneError(f"scene.{key} must be a {kind.__name__}, "
                                 f"got {type(getattr(self, key)).__name__}")
        if self.streaks is not None and not isinstance(self.streaks, Streaks):
            raise SceneError("scene.streaks must be a Streaks or None")
        object.__setattr__(self, "background", rgb("background.color", self.background))
        if self.patches is not None:
            if not isinstance(self.patches, PatchGeometry):
                raise SceneError("scene.patches must be a PatchGeometry or None")
            if self.occluder is not None:
                raise SceneError("hair.geometry = 'patches' does not draw an occluder: "
                                 "remove [occluder] or use geometry = 'strands'")

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
        return dataclasses.replace(self, **changes)
