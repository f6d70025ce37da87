"""The render's capacity estimate (docs/model.md §5, "Capacity"): the memory a render of a
scene will hold, item by item, from the scene's own numbers, taken before any large array
exists, and the refusal (`SceneTooLarge`) of a scene that needs more than is available.

Two steps, both before the arrays they bound exist (`_setup` calls them):

- `fixed_needs`, in closed form before anything is projected: the image's per-pixel
  arrays (camera size), the per-point and per-segment arrays (strands and points, and
  the 3 × 3 plans of the shadow methods that keep one), the opacity maps or deep layers
  (maps or layers × the light's resolution²);
- `fragment_needs`, once the camera's projection and draw order exist, before the image
  and the fragments are allocated: the camera's and the light's fragments, bounded per
  segment by the lattice points of its ribbon clipped to the raster
  (`ribbon_pixel_bound`), and on an accelerator the raster's candidates (every one is
  allocated there, `_device_raster`).

Where those bounds exceed the memory but the exact count may not, the raster loop counts
the fragments without writing them (`count_fragments`), unless that pass would visit
more candidates than four times the fragments memory could hold (a ribbon far wider than
its segment is long: then the bound is close to the count, area against area).
On the CPU the host and JAX share one memory; on an accelerator JAX's arrays are counted
against the device's free memory and NumPy's against the host's.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import no_type_check

import jax
import jax.numpy as jnp
import numpy as np

from .._errors import SceneTooLarge
from .._geometry import _capacity, _device_raster
from .._geometry._capacity import fragment_bytes, memory_size
from .._geometry._device_raster import candidate_bytes
from .._geometry._host import compile_loop
from .._geometry._placement import Placement
from .._geometry._raster import count_fragments
from .._geometry._raster_plan import RibbonRaster, raster_plan
from .._geometry._shadows import MAX_MAP_CELLS, light_raster
from .._scene._scene import Scene

__all__ = [
    "Need",
    "fixed_needs",
    "fragment_needs",
    "check_capacity",
    "ribbon_pixel_bound",
    "scene_light_raster",
]

# Bytes held at the render's peak, read off the code that allocates them (the JAX arrays
# as floats of the working precision); against measured peaks: docs/model.md §5.
PIXEL_HOST = 48  # backdrop (float64 RGB), opaque, the image read back and written (RGBA)
PIXEL_FLOATS = 12  # transmittance, alpha, backdrop (3), opaque, the image (4), the composite's temporaries
OCCLUDER_PIXEL = 128  # the occluder's ray hits: depth, normal and point (float64), and their temporaries
POINT_HOST = 240  # projection, tangent, to-light, to-eye, colour (float64 and float copies), temporaries
SEGMENT_HOST = 200  # segments, strand, order, both ends' positions and widths, the raster plan
POINT_FLOATS = 16  # the Geometry's four 3-vectors, Ω, the shading's colours and temporaries
LOOKUP_HOST = 40  # per point and texel of a 3 × 3 plan: texel, bounds (int64), weight, masks
FRAGMENT_SORT = 8  # the grouping's permutation, beyond `fragment_bytes`
FRAGMENT_FLOATS = 4  # the weights (on the CPU the rest share the set-up's arrays)
LIGHT_FRAGMENT_HOST = 40  # the light raster's fields, strand, cell, sort key and order
LIGHT_FRAGMENT_FLOATS = 4  # its alpha
MAP_FLOATS = 8  # per map cell: the sums, their cumulative sum, the box filter's passes
COUNT_VISITS = 4  # the counting pass visits at most this many candidates per fragment that fits


@dataclasses.dataclass(frozen=True)
class Need:
    """One item of the estimate: `what` it is, the scene `keys` that set its size (with
    their values), and its bytes on the host (NumPy) and in JAX's arrays."""

    what: str
    keys: str
    host: int
    jax: int


def fixed_needs(scene: Scene) -> list[Need]:
    """The items known in closed form from the scene's numbers (no projection): image,
    points and segments, maps (module docstring)."""
    cam, strands, shadows = scene.camera, scene.strands, scene.shadows
    f = jnp.dtype(jnp.result_type(float)).itemsize
    hw = cam.width * cam.height
    pixel_host = PIXEL_HOST + (OCCLUDER_PIXEL if scene.occluder is not None else 0)
    size_keys = f"camera.width x camera.height = {cam.width}x{cam.height} (--size)"
    p, s = strands.num_points, strands.num_strands
    lookups = shadows.point_lookups() if shadows.casts else 0
    needs = [
        Need("the image's per-pixel arrays", size_keys, hw * pixel_host, hw * PIXEL_FLOATS * f),
        Need(
            "the per-point and per-segment arrays",
            f"hair.strands = {s:,} strands of {p:,} points in all (hair.points)",
            p * (POINT_HOST + (LOOKUP_HOST * lookups if lookups > 1 else 0)) + (p - s) * SEGMENT_HOST,
            p * POINT_FLOATS * f,
        ),
    ]
    cells, keys = shadows.planned_maps() if shadows.casts else (0, "")
    if cells:
        needs.append(Need("the shadow maps", keys, 0, cells * MAP_FLOATS * f))
    return needs


def ribbon_pixel_bound(xy0, xy1, width, image_width: int, image_height: int) -> np.ndarray:
    """Per segment, an upper bound on the pixel centres its ribbon covers (`[E]` float64;
    `rasterize`'s arguments, `width` `[E]` or `[E, 2]`).

    A covered centre lies within the segment's [0, L) and within (w + 1)/2 of its line
    (§5's coverage is 0 beyond), w the wider end: in a rectangle of L × (w + 1), and in the
    image. The unit boxes around the lattice points of a convex set K are disjoint and lie
    in K ⊕ [−½, ½]², so there are at most area(K) + extent_x(K) + extent_y(K) + 1 of them;
    K's area is at most the rectangle's, the image's, and either side times the image's
    extent across it, and its extents at most the rectangle's bounding box clipped to the
    image. The bound of each segment is one compiled step (`_bound_loop`): NumPy's two dozen
    passes over the 2 M ribbons of 100k strands, camera and light, took 0.27 s."""
    xy0, xy1 = np.asarray(xy0, np.float64), np.asarray(xy1, np.float64)
    width = np.asarray(width, np.float64)
    # The wider end: np.maximum of the two columns, as `max(axis=1)` over 2 is 10× as slow.
    width = np.maximum(width[:, 0], width[:, 1]) if width.ndim == 2 else np.broadcast_to(width, xy0.shape[:1])
    bound = np.empty(xy0.shape[0])
    _bound_loop()(
        np.ascontiguousarray(xy0),
        np.ascontiguousarray(xy1),
        np.ascontiguousarray(width),
        image_width,
        image_height,
        bound,
    )
    return bound


@functools.cache
def _bound_loop():
    """`ribbon_pixel_bound`'s per-segment bound compiled by numba (on first use; cached on
    disk), in float64."""

    @compile_loop(error_model="numpy")
    @no_type_check
    def bound(xy0, xy1, width, image_width, image_height, out):
        for i in range(out.size):
            dx, dy = xy1[i, 0] - xy0[i, 0], xy1[i, 1] - xy0[i, 1]
            length = math.hypot(dx, dy)
            if not length > 0:
                out[i] = 0.0  # a zero-length segment covers nothing
                continue
            ux, uy = abs(dx) / length, abs(dy) / length
            # A little beyond w + 1 and L: the loop's float32 may place a centre ulps inside.
            across = width[i] + 1.0 + 1e-3 * (1.0 + width[i])
            along = length * (1.0 + 1e-6) + 1e-3
            cx, cy = 0.5 * (xy0[i, 0] + xy1[i, 0]), 0.5 * (xy0[i, 1] + xy1[i, 1])
            half_x, half_y = 0.5 * (along * ux + across * uy), 0.5 * (along * uy + across * ux)
            span_x = min(cx + half_x, image_width) - max(cx - half_x, 0.0)
            span_y = min(cy + half_y, image_height) - max(cy - half_y, 0.0)
            if not (span_x >= 0 and span_y >= 0):
                out[i] = 0.0  # the ribbon misses the image
                continue
            area = min(
                along * across,
                along * (image_width * uy + image_height * ux),
                across * (image_width * ux + image_height * uy),
                max(span_x, 0.0) * max(span_y, 0.0),
            )
            out[i] = math.ceil(area + max(span_x, 0.0) + max(span_y, 0.0) + 1.0)

    return bound


def _fragments(raster, limit: int | None) -> tuple[int, bool]:
    """(fragments, counted): the raster's bound, or its count where `limit` allows."""
    if limit is not None:
        count = count_fragments(*raster, limit=limit)
        if count is not None:
            return count, True
    bound = ribbon_pixel_bound(raster.xy0, raster.xy1, raster.width, raster.image_width, raster.image_height)
    return int(bound.sum()), False


def _plan(raster: RibbonRaster):
    """The raster's layout (`raster_plan`) from its input."""
    r = raster
    return raster_plan(r.xy0, r.xy1, r.z0, r.z1, r.width, r.image_width, r.image_height)


def _width_keys(scene: Scene) -> str:
    strands = scene.strands
    widest = float(np.max(strands.width, initial=0.0))
    return f"hair.width = {widest:g} ({strands.width_units}), {strands.num_strands:,} strands"


def fragment_needs(
    scene: Scene, camera_raster, light, *, placement: Placement = "host", limit: int | None = None
) -> list[Need]:
    """The camera's and the light's fragments (module docstring): `camera_raster` and
    `light` (`light_raster`'s, or None without shadows) are `rasterize`'s arguments;
    bounded, or with a `limit` counted (`_fragments`); with the raster's candidates where
    the set-up is `placement`d on the device."""
    cam = scene.camera
    f = jnp.dtype(jnp.result_type(float)).itemsize
    depth = scene.occluder is not None
    on_device = placement == "device"
    count, counted = _fragments(camera_raster, limit)
    keys = f"{_width_keys(scene)}, camera.width x camera.height = {cam.width}x{cam.height} (--size)"
    what = f"the camera's {count:,} fragments" if counted else f"the camera's fragments (at most {count:,})"
    per = fragment_bytes(f, depth) + FRAGMENT_SORT
    needs = [Need(what, keys, 0 if on_device else count * per, count * FRAGMENT_FLOATS * f)]
    if on_device:
        plan = _plan(camera_raster)
        needs.append(Need("the camera raster's candidates", keys, 0, candidate_bytes(plan, depth)))
    if light is not None:
        count, counted = _fragments(light, limit)
        keys = f"shadows.resolution = {light.image_width}, {_width_keys(scene)}"
        what = f"the light's {count:,} fragments" if counted else f"the light's fragments (at most {count:,})"
        light_on_device = on_device and scene.shadows.rasterizes_on_device
        host = 0 if light_on_device else count * LIGHT_FRAGMENT_HOST
        needs.append(Need(what, keys, host, count * LIGHT_FRAGMENT_FLOATS * f))
        if light_on_device:
            plan = _plan(light)
            needs.append(Need("the light raster's candidates", keys, 0, candidate_bytes(plan, True)))
    return needs


def _pools(needs: list[Need]) -> list[tuple[str, int, int | None, list[int]]]:
    """(where, total bytes, bytes available, each need's bytes there) per memory."""
    if jax.default_backend() == "cpu":
        each = [n.host + n.jax for n in needs]
        return [("", sum(each), _capacity.available_memory(), each)]
    host, device = [n.host for n in needs], [n.jax for n in needs]
    return [
        (" on the host", sum(host), _capacity.available_memory(), host),
        (" on the device", sum(device), _device_raster.device_memory(), device),
    ]


def _over(needs: list[Need]) -> SceneTooLarge | None:
    """The refusal of `needs` where they exceed a memory, naming the largest item there."""
    for where, total, available, each in _pools(needs):
        if available is None or total <= available:
            continue
        need, size = max(zip(needs, each), key=lambda pair: pair[1])
        return SceneTooLarge(
            f"{need.keys}: {need.what} need {memory_size(size)} of the {memory_size(total)} this "
            f"render needs{where}; {memory_size(available)} of memory is available{where}"
        )
    return None


def scene_light_raster(scene: Scene):
    """The light's frame and raster of `scene`'s shadows (`light_raster`), None without."""
    if not scene.shadows.casts:
        return None
    strands = scene.strands
    segments = strands.segments()
    return light_raster(
        strands.points,
        segments,
        strands.strand_of_point[segments[:, 0]],
        strands.width,
        scene.light,
        scene.shadows.resolution,
        strands.width_units,
    )


def check_capacity(scene: Scene, camera_raster=None, *, light=None, placement: Placement = "host") -> None:
    """Refuse (`SceneTooLarge`) a render of `scene` whose estimate exceeds the memory
    available: the closed-form items (`fixed_needs`); with the camera's `camera_raster`
    (`rasterize`'s arguments) also the fragments, bounded, then counted where the bound
    is over (module docstring), for the set-up at `placement` (`_placement`). `light`:
    the light's frame and raster (`scene_light_raster`) where made already."""
    needs = fixed_needs(scene)
    refusal = _over(needs)
    if refusal is not None:
        raise refusal
    cells, keys = scene.shadows.planned_maps() if scene.shadows.casts else (0, "")
    if cells > MAX_MAP_CELLS:
        raise SceneTooLarge(f"{keys}: {cells:,} map cells exceed the {MAX_MAP_CELLS:,} the maps can index")
    if camera_raster is None:
        return
    if light is None:
        light = scene_light_raster(scene)
    light = None if light is None else light[1]
    bounded = needs + fragment_needs(scene, camera_raster, light, placement=placement)
    if _over(bounded) is None:
        return
    available = _capacity.available_memory() or 0
    limit = COUNT_VISITS * available // fragment_bytes(jnp.dtype(jnp.result_type(float)).itemsize, False)
    refusal = _over(needs + fragment_needs(scene, camera_raster, light, placement=placement, limit=limit))
    if refusal is not None:
        raise refusal
