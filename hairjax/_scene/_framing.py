"""Automatic framing: a camera, a key light and a whole scene that show any hair.

Real assets come in their own units and places (centimetres, a head's height above the
origin), which the default camera (eye (0, 0, 4) looking at the origin) misses. Here the
camera is placed from the strands' bounding sphere, so any asset fills the view; the
scene file's `[camera] frame = "auto"` and `_file.scene_for_hair` use it (docs/scenes.md).
"""

from __future__ import annotations

import math

import numpy as np

from .._errors import SceneError
from .._geometry._projection import camera_view
from .._values._camera import Camera
from .._values._light import Light
from .._values._strands import Strands

__all__ = [
    "frame_camera",
    "key_light",
    "bounding_sphere",
    "FRAME_AZIMUTH",
    "FRAME_ELEVATION",
    "FRAME_MARGIN",
    "WIDTH_FRACTION",
]

# The three-quarter view: the eye 35° round from the front (+z) towards +x, 20° above
# the horizontal plane through the sphere's centre.
FRAME_AZIMUTH = 35.0
FRAME_ELEVATION = 20.0
# The bounding sphere's silhouette fills 1/1.1 of the narrower field of view's half-angle
# (as sines), leaving a rim of empty pixels for the ribbons' width and antialiasing.
FRAME_MARGIN = 1.1
# Ribbon width for `scene_for_hair`, world units, as a fraction of the bounding radius.
# The example scenes draw real hair 1 pixel wide: tressfx_ponytail.toml (320², eye 4.27
# from the centre, radius 1.50 after its scale) is 0.0065 radii, sintel.toml (256², eye
# 60.8 away, radius 20.9) 0.0083 radii; 1/128 lies between, so a 256–320² render of a
# framed asset looks like theirs and the look does not depend on the file's units.
WIDTH_FRACTION = 1.0 / 128.0


def bounding_sphere(points) -> tuple[np.ndarray, float]:
    """(centre, radius) of a sphere holding every point: the bounding box's centre and the
    largest distance of a point from it. SceneError for no points."""
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) == 0:
        raise SceneError(f"cannot frame hair without points (got points of shape {points.shape})")
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    radius = float(np.linalg.norm(points - centre, axis=1).max())
    return centre, radius


def frame_camera(
    strands: Strands,
    *,
    width: int = 512,
    height: int = 512,
    fov: float = 40.0,
    azimuth: float = FRAME_AZIMUTH,
    elevation: float = FRAME_ELEVATION,
    zoom: float = 1.0,
) -> Camera:
    """A camera that shows all of `strands`, by default from a three-quarter view.

    The eye looks at the centre of the strands' bounding sphere (`bounding_sphere`) from
    `azimuth` degrees (default `FRAME_AZIMUTH`, 35°; 0 is the front, +z, and positive
    angles turn towards +x) and `elevation` degrees (default `FRAME_ELEVATION`, 20°,
    towards +y, which stays up in the image; in (−90, 90)), at the distance
    r / sin(φ/2) × `FRAME_MARGIN` (1.1) / `zoom`, with φ the smaller of the vertical `fov`
    and the horizontal field of view of a `width` × `height` image: at `zoom` 1 the
    sphere's silhouette lies inside the image, in wide and tall images alike; `zoom` 2
    comes twice as close. `near` is Camera's default (1e-3 × that distance). SceneError
    for a bad `fov`, `width` or `height` (Camera's checks), an elevation of ±90° or more,
    a zoom ≤ 0, or strands without points.
    """
    if not -90 < elevation < 90:  # at ±90° the view is parallel to up (+y)
        raise SceneError(f"camera.elevation must be in (-90, 90) degrees, got {elevation!r}")
    if not (math.isfinite(zoom) and zoom > 0) or not math.isfinite(azimuth):
        raise SceneError(f"camera.zoom must be > 0 and camera.azimuth finite, got {zoom!r}, {azimuth!r}")
    checked = Camera(fov=fov, width=width, height=height)  # SceneError for a bad fov or size
    fov, width, height = checked.fov, checked.width, checked.height
    centre, radius = bounding_sphere(strands.points)
    if not radius > 0:
        # Fires when every point coincides (one point, or strands of repeated points):
        # any distance frames a point, so take one world unit.
        radius = 1.0
    half_v = math.radians(fov) / 2
    half_h = math.atan(math.tan(half_v) * width / height)
    distance = radius / math.sin(min(half_v, half_h)) * FRAME_MARGIN / zoom
    az, el = math.radians(azimuth), math.radians(elevation)
    direction = np.array([math.cos(el) * math.sin(az), math.sin(el), math.cos(el) * math.cos(az)])
    eye = centre + distance * direction
    return Camera(
        eye=tuple(eye), target=tuple(centre), up=(0.0, 1.0, 0.0), fov=fov, width=width, height=height
    )


def key_light(camera: Camera) -> Light:
    """A white directional key light from the upper left, in front of the hair, as seen
    by `camera`: it comes from the direction left + up + towards the eye (equal parts of
    the view's right, up and backward axes, 45° off each), so `direction` (the way the
    light travels, docs/model.md §3) is right − up + forward."""
    view = camera_view(camera)
    return Light(kind="directional", direction=tuple(view.right - view.up + view.forward))
