"""Views: how 3-D points map to a raster (the camera, or the light for opacity maps).

Geometry only, so NumPy float64. A `View` maps a point p to pixel coordinates (x, y)
(x right, y down, pixel (i, j) centred at (i + 0.5, j + 0.5)) and a depth D along the view
axis: D = (p − origin)·forward (kim-2003 §3's distance to the image plane).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._constants import NEAR_FRACTION

__all__ = ["View", "camera_view", "light_view"]


@dataclasses.dataclass(frozen=True)
class View:
    """A perspective (camera, point light) or orthographic (directional light) raster view.

    `focal` is in pixels per unit of (lateral offset / depth) for perspective views and
    pixels per world unit for orthographic ones; (cx, cy) is where the axis lands.
    """

    origin: np.ndarray
    forward: np.ndarray
    right: np.ndarray
    up: np.ndarray
    width: int
    height: int
    focal: float
    cx: float
    cy: float
    perspective: bool
    near: float

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`float64[P, 3]` → (`float64[P, 2]` pixel coordinates, `float64[P]` depth)."""
        rel = np.asarray(points, dtype=np.float64) - self.origin
        depth = rel @ self.forward
        lateral = np.stack([rel @ self.right, rel @ self.up], axis=1)
        if self.perspective:
            # Fires for points at or behind the eye: their segments are culled by `near`
            # (see visible_segments), the guard only keeps the division finite.
            lateral = lateral / np.where(depth > self.near, depth, self.near)[:, None]
        xy = np.empty_like(lateral)
        xy[:, 0] = self.cx + self.focal * lateral[:, 0]
        xy[:, 1] = self.cy - self.focal * lateral[:, 1]
        return xy, depth

    def pixel_rays(self) -> tuple[np.ndarray, np.ndarray]:
        """Per pixel centre: (ray origin `[H*W, 3]`, unit ray direction `[H*W, 3]`), row-major."""
        j, i = np.mgrid[0 : self.height, 0 : self.width]
        x = (i.ravel() + 0.5 - self.cx) / self.focal
        y = -(j.ravel() + 0.5 - self.cy) / self.focal
        if self.perspective:
            d = self.forward + x[:, None] * self.right + y[:, None] * self.up
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            o = np.broadcast_to(self.origin, d.shape)
        else:
            o = self.origin + x[:, None] * self.right + y[:, None] * self.up
            d = np.broadcast_to(self.forward, o.shape)
        return o, d


def _basis(forward: np.ndarray, up_hint: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    right = np.cross(forward, up_hint)
    # Relative to |up| as in Camera's check (an absolute 1e-9 turned up = (0, 1e-10, 0) by 90°).
    if np.linalg.norm(right) <= 1e-12 * np.linalg.norm(up_hint):
        # Fires when the up hint is parallel to forward (a light straight along y):
        # any perpendicular works for a light's map, so take another axis.
        right = np.cross(forward, np.array([1.0, 0.0, 0.0]))
        if np.linalg.norm(right) < 1e-9:
            # Unreachable: Camera rejects up ∥ forward, and a light's forward ∥ y is not ∥ x.
            right = np.cross(forward, np.array([0.0, 0.0, 1.0]))
    right /= np.linalg.norm(right)
    return right, np.cross(right, forward)


def camera_view(camera) -> View:
    """The camera's view: `target` lands at (W/2, H/2) + offset; world up is up in the image."""
    eye = np.asarray(camera.eye, dtype=np.float64)
    forward = np.asarray(camera.target, dtype=np.float64) - eye
    forward /= np.linalg.norm(forward)
    right, up = _basis(forward, np.asarray(camera.up, dtype=np.float64))
    focal = 0.5 * camera.height / np.tan(np.radians(camera.fov) / 2)
    return View(
        origin=eye,
        forward=forward,
        right=right,
        up=up,
        width=camera.width,
        height=camera.height,
        focal=float(focal),
        cx=camera.width / 2 + camera.offset[0],
        cy=camera.height / 2 + camera.offset[1],
        perspective=True,
        near=camera.near,
    )


def light_view(light, points: np.ndarray, resolution: int, margin: int) -> View:
    """The light's view of `points` for R × R opacity maps.

    Directional light: orthographic along the light's direction, framing the points'
    bounding square with `margin` texels on each side. Point light: perspective from the
    light towards the points' bounding-box centre, the field of view fitted to the points
    in front of it (at most ±80° off axis; points beyond fall outside the maps).
    """
    points = np.asarray(points, dtype=np.float64)
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = 0.5 * (lo + hi)
    usable = resolution - 2 * margin
    if light.kind == "directional":
        forward = np.asarray(light.direction, dtype=np.float64)
        forward /= np.linalg.norm(forward)
        right, up = _basis(forward, np.array([0.0, 1.0, 0.0]))
        rel = points - centre
        extent = 2 * max(float(np.abs(rel @ right).max()), float(np.abs(rel @ up).max()))
        # Fires when all points coincide seen from the light: any scale frames one point.
        focal = usable / extent if extent > 0 else 1.0
        return _square_view(centre, (forward, right, up), resolution, focal, perspective=False, near=-np.inf)
    origin = np.asarray(light.position, dtype=np.float64)
    axis = centre - origin
    scale = float(np.linalg.norm(hi - lo) + np.linalg.norm(axis))
    if np.linalg.norm(axis) <= 1e-9 * max(scale, 1e-300):
        # Fires when the light sits at the centre of the hair: look down −y by convention.
        axis = np.array([0.0, -1.0, 0.0])
    forward = axis / np.linalg.norm(axis)
    right, up = _basis(forward, np.array([0.0, 1.0, 0.0]))
    # The max fires with the light at the hair's centre (the fallback above): near ≈ 1e-303.
    near = NEAR_FRACTION * max(float(np.linalg.norm(centre - origin)), 1e-300)
    rel = points - origin
    depth = rel @ forward
    front = depth > near
    tan_max = np.tan(np.radians(80.0))
    if front.any():
        lateral = np.maximum(np.abs(rel[front] @ right), np.abs(rel[front] @ up)) / depth[front]
        # 1e-6 fires when every point in front lies on the axis; tan_max for points beyond ±80°.
        tan_half = min(max(lateral.max(), 1e-6), tan_max)
    else:
        tan_half = tan_max  # fires when no point is in front of the light
    focal = (usable / 2) / tan_half
    return _square_view(origin, (forward, right, up), resolution, focal, perspective=True, near=float(near))


def _square_view(origin, axes, resolution: int, focal, *, perspective: bool, near: float) -> View:
    """The light's `resolution`² view from `origin` along `axes` (forward, right, up),
    centred on the map."""
    forward, right, up = axes
    return View(
        origin=origin,
        forward=forward,
        right=right,
        up=up,
        width=resolution,
        height=resolution,
        focal=float(focal),
        cx=resolution / 2,
        cy=resolution / 2,
        perspective=perspective,
        near=near,
    )
