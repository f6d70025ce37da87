"""The scene: what to render, as plain immutable values.

A `Scene` is configuration, not a pytree: the geometry stage reads it with NumPy, and the
shading stage takes its differentiable parameters from `Scene.params` (a `ShadingParams`).
Construction validates every value, so a `Scene` that exists can be rendered.
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np

from ._errors import SceneError
from ._lookup import LOOKUP_MODELS
from ._scheuermann import ScheuermannMaps, ScheuermannParams, check_scheuermann_params
from ._shading import SHADING_MODELS, ShadingParams
from ._strands import Strands
from ._streaks import Streaks

__all__ = ["Camera", "Light", "Shadows", "Ordering", "Occluder", "PatchGeometry", "Scene"]

# Every shading model a scene may name: the analytic ones and their lookup-table variants (§14).
MODELS = (*SHADING_MODELS, *LOOKUP_MODELS)
LOOKUP_SIZE_RANGE = (2, 4096)


def _vec3(name: str, value, *, nonzero: bool = False) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise SceneError(f"{name} must be 3 finite numbers, got {value!r}")
    if nonzero and not np.linalg.norm(arr) > 0:
        raise SceneError(f"{name} must not have length 0")
    return tuple(float(x) for x in arr)


def _rgb(name: str, value) -> tuple[float, float, float]:
    arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (3,))
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise SceneError(f"{name} must be a non-negative number or 3 of them, got {value!r}")
    return tuple(float(x) for x in arr)


@dataclasses.dataclass(frozen=True)
class Camera:
    """Pinhole look-at camera. `fov` is the vertical field of view in degrees.

    Images are `[height, width, 4]`, row 0 at the top; pixel (i, j) has its centre at
    (i + 0.5, j + 0.5); `target` projects to (width/2, height/2); world `up` is up.
    `near` (world units) defaults to 1e-3 × |target − eye|; segments with an endpoint
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
        eye = _vec3("camera.eye", self.eye)
        target = _vec3("camera.target", self.target)
        up = _vec3("camera.up", self.up, nonzero=True)
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
            near = 1e-3 * float(np.linalg.norm(d))
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


@dataclasses.dataclass(frozen=True)
class Light:
    """A directional light (`direction`: the way light travels) or a point light (`position`)."""

    kind: Literal["directional", "point"] = "directional"
    direction: tuple[float, float, float] | None = (-1.0, -1.0, -1.0)
    position: tuple[float, float, float] | None = None
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)

    def __post_init__(self):
        if self.kind == "directional":
            if self.direction is None:
                raise SceneError("light.direction is required for a directional light")
            object.__setattr__(self, "direction",
                               _vec3("light.direction", self.direction, nonzero=True))
            object.__setattr__(self, "position", None)
        elif self.kind == "point":
            if self.position is None:
                raise SceneError("light.position is required for a point light")
            object.__setattr__(self, "position", _vec3("light.position", self.position))
            object.__setattr__(self, "direction", None)
        else:
            raise SceneError(f"light.kind must be 'directional' or 'point', got {self.kind!r}")
        object.__setattr__(self, "color", _rgb("light.color", self.color))


SHADOW_METHODS = ("none", "opacity-maps", "exact")
ORDERING_METHODS = ("bins", "exact", "none", "static")


@dataclasses.dataclass(frozen=True)
class Shadows:
    """Self-shadowing: `none`, `opacity-maps` (N maps of R × R), or `exact` (N → ∞)."""

    method: Literal["none", "opacity-maps", "exact"] = "opacity-maps"
    maps: int = 64
    resolution: int = 256

    def __post_init__(self):
        if self.method not in SHADOW_METHODS:
            raise SceneError(f"shadows.method must be one of {SHADOW_METHODS}, got {self.method!r}")
        if isinstance(self.maps, bool) or int(self.maps) != self.maps or not 1 <= self.maps <= 65536:
            raise SceneError(f"shadows.maps must be an integer in [1, 65536], got {self.maps!r}")
        r = self.resolution
        if isinstance(r, bool) or int(r) != r or not 4 <= r <= 16384:
            raise SceneError(f"shadows.resolution must be an integer in [4, 16384], got {r!r}")
        object.__setattr__(self, "maps", int(self.maps))
        object.__setattr__(self, "resolution", int(r))


@dataclasses.dataclass(frozen=True)
class Ordering:
    """Visibility order: depth `bins` (kim-2003 §3), `exact` depth sort, `none` (index order),
    or `static`: inside to outside, from the geometry alone (scheuermann-2004 slide 14)."""

    method: Literal["bins", "exact", "none", "static"] = "bins"
    bins: int = 256

    def __post_init__(self):
        if self.method not in ORDERING_METHODS:
            raise SceneError(
                f"ordering.method must be one of {ORDERING_METHODS}, got {self.method!r}")
        if isinstance(self.bins, bool) or int(self.bins) != self.bins or not 1 <= self.bins <= 2**24:
            raise SceneError(f"ordering.bins must be an integer in [1, 2^24], got {self.bins!r}")
        object.__setattr__(self, "bins", int(self.bins))


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
        object.__setattr__(self, "center", _vec3("occluder.center", self.center))
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise SceneError(f"occluder.radius must be positive, got {self.radius!r}")
        object.__setattr__(self, "radius", float(self.radius))
        object.__setattr__(self, "color", _rgb("occluder.color", self.color))
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

    `params` holds the differentiable shading parameters; `shading_model` picks the
    Kajiya-Kay convention (`"kajiya-kay"` or `"kajiya-kay-mirror"`, see docs/model.md) or
    the seed's convention read from a `lookup_size` × `lookup_size` table
    (`"kajiya-kay-lookup"`, §14; `lookup_size` is unused by the other models), each with a
    `ShadingParams`; or `"scheuermann"` (docs/model.md §17) with a `ScheuermannParams`;
    `scheuermann_maps` (used by that model only) says how its per-point inputs are made.
    `streaks`: wenzel-2002's streak texture along the hairs (§16), or None.
    `patches`: draw the strands as hair patches (§18) instead of ribbons, or None; the
    strands' opacity maps still give the self-shadows; no occluder.
    """

    strands: Strands
    camera: Camera = Camera()
    light: Light = Light()
    params: ShadingParams = dataclasses.field(default_factory=ShadingParams)
    shading_model: str = "kajiya-kay"
    shadows: Shadows = Shadows()
    ordering: Ordering = Ordering()
    occluder: Occluder | None = None
    background: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str = "scene"
    lookup_size: int = 256
    streaks: Streaks | None = None
    scheuermann_maps: ScheuermannMaps = ScheuermannMaps()
    patches: PatchGeometry | None = None

    def __post_init__(self):
        if not isinstance(self.strands, Strands):
            raise SceneError("scene.strands must be a Strands")
        if self.shading_model not in MODELS:
            raise SceneError(
                f"shading.model must be one of {MODELS}, got {self.shading_model!r}")
        lo, hi = LOOKUP_SIZE_RANGE
        n = self.lookup_size
        if isinstance(n, bool) or int(n) != n or not lo <= n <= hi:
            raise SceneError(f"shading.lookup_size must be an integer in [{lo}, {hi}], got {n!r}")
        object.__setattr__(self, "lookup_size", int(n))
        if self.streaks is not None and not isinstance(self.streaks, Streaks):
            raise SceneError("scene.streaks must be a Streaks or None")
        wanted = ScheuermannParams if self.shading_model == "scheuermann" else ShadingParams
        if not isinstance(self.params, wanted):
            raise SceneError(f"shading model {self.shading_model!r} takes {wanted.__name__}, "
                             f"got {type(self.params).__name__}")
        if wanted is ScheuermannParams:
            check_scheuermann_params(self.params)
        object.__setattr__(self, "background", _rgb("background.color", self.background))
        if self.patches is not None:
            if not isinstance(self.patches, PatchGeometry):
                raise SceneError("scene.patches must be a PatchGeometry or None")
            if self.occluder is not None:
                raise SceneError("hair.geometry = 'patches' does not draw an occluder: "
                                 "remove [occluder] or use geometry = 'strands'")

    def replace(self, **changes) -> Scene:
        return dataclasses.replace(self, **changes)
