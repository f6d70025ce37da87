"""The camera (docs/model.md §2): a pinhole look-at camera and its pixel grid."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from .._constants import NEAR_FRACTION
from .._errors import SceneError
from ._light import Vec3Like, vec3

__all__ = ["Camera"]


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

    # Stored as tuples of floats, a float and ints; taken as any sequences or arrays of
    # ints or floats (`Vec3Like`), checked here (SceneError).
    eye: Vec3Like = (0.0, 0.0, 4.0)
    target: Vec3Like = (0.0, 0.0, 0.0)
    up: Vec3Like = (0.0, 1.0, 0.0)
    fov: float | int = 40.0
    width: int = 512
    height: int = 512
    near: float | int | None = None
    offset: Sequence[float | int] | np.ndarray = (0.0, 0.0)

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
        for key, v in (
            ("eye", eye),
            ("target", target),
            ("up", up),
            ("fov", float(self.fov)),
            ("width", int(self.width)),
            ("height", int(self.height)),
            ("near", float(near)),
            ("offset", (float(offset[0]), float(offset[1]))),
        ):
            object.__setattr__(self, key, v)
