"""Batched views and lights: one scene's strands seen by V cameras (or lit by V lights)
rendered as one `[V, H, W, 4]` array, with one compilation for all of them, sharded over
every available device (docs/model.md §6, docs/architecture.md "Batched views").

Each view's geometry stage is its own (`geometry_stage` of the scene with that view's
camera and light, a new scene object per call, so computed afresh each call).
Their fragment and occluder arrays differ in length, so each is padded to the longest
(to a multiple of 2^16 entries, `bucket`): a padded fragment has weight 0 and pixel H·W,
which the composite's scatter drops; a padded occluder pixel is H·W, which the backdrop's
scatter drops. The stacked `Geometry` then goes through the one shading stage under
`vmap`, and its view axis is laid out over a one-axis device mesh (`NamedSharding`), so
the output sits on every device.
"""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec
from jaxtyping import Array, Float

from ._geometry_stage._stage import Geometry, geometry_stage
from ._scene._scene import Scene
from ._shading import shading_stage
from ._values._camera import Camera
from ._values._light import Light

__all__ = [
    "render_views",
    "view_scenes",
    "stack_geometries",
    "pad_geometries",
    "shade_views",
    "view_mesh",
    "bucket",
]

# The per-fragment fields and what pads them: a padded fragment adds nothing to any pixel.
_FRAGMENT_FILL = {"frag_pixel": None, "frag_i0": 0, "frag_t": 0.0, "frag_weight": 0.0}
# The per-occluder-pixel fields (Q) and what pads them: a padded pixel is dropped.
_OCCLUDER_FILL = {
    "occluder_pixel": None,
    "occluder_direct": 0.0,
    "occluder_omega": 0.0,
    "occluder_visibility": 0.0,
}
# (None: the pixel index H·W, past every pixel, which the composite's scatters drop.)


def view_scenes(
    scene: Scene, cameras: Sequence[Camera] | None = None, lights: Sequence[Light] | None = None
) -> list[Scene]:
    """The scene once per view: camera i (default the scene's) with light i (default the
    scene's). Cameras and lights, where both are given, pair up and must be as many; every
    camera must have the scene camera's size (one image array)."""
    if cameras is None and lights is None:
        raise ValueError("render_views needs cameras, lights or both")
    n = len(cameras) if cameras is not None else len(lights)  # type: ignore[arg-type]
    if cameras is not None and lights is not None and len(lights) != n:
        raise ValueError(f"render_views pairs cameras and lights: got {n} cameras and {len(lights)} lights")
    if n == 0:
        raise ValueError("render_views needs at least one view")
    cams = list(cameras) if cameras is not None else [scene.camera] * n
    lits = list(lights) if lights is not None else [scene.light] * n
    size = (scene.camera.width, scene.camera.height)
    for i, cam in enumerate(cams):
        if (cam.width, cam.height) != size:
            raise ValueError(
                f"camera {i} is {cam.width}x{cam.height}, the scene's {size[0]}x{size[1]}: "
                "the views of one batch share the image size"
            )
    if scene.patches is not None:
        raise ValueError("render_views draws strands; a hair-patch scene renders with hairjax.render")
    return [scene.replace(camera=c, light=lt) for c, lt in zip(cams, lits)]


# Padded lengths are multiples of this many entries: batches whose longest view differs by
# less share a compilation, and at most this many empty fragments are composited.
PAD_MULTIPLE = 1 << 16


def bucket(n: int) -> int:
    """`n` rounded up to a multiple of `PAD_MULTIPLE` (at least one): the padded length
    of a batch's arrays."""
    return max(1, -(-int(n) // PAD_MULTIPLE)) * PAD_MULTIPLE


def _pad(x, n: int, value):
    if x.shape[0] == n:
        return x
    fill = jnp.full((n - x.shape[0],) + x.shape[1:], value, x.dtype)
    return jnp.concatenate([x, fill])


def _padded(g: Geometry, fill: dict, n: int) -> Geometry:
    """`g` with the fields of `fill` present in it grown to `n` entries."""
    hw = g.height * g.width
    names = [k for k in fill if getattr(g, k) is not None]
    grown = tuple(_pad(getattr(g, k), n, hw if fill[k] is None else fill[k]) for k in names)
    return eqx.tree_at(lambda g: tuple(getattr(g, k) for k in names), g, grown)


def pad_geometries(geometries: Sequence[Geometry], round_up=bucket) -> list[Geometry]:
    """The geometries with their fragment and occluder arrays padded to the longest of
    them, rounded up by `round_up` (default `bucket`), with entries that add nothing."""
    f = round_up(max(int(g.frag_pixel.shape[0]) for g in geometries))
    padded = [_padded(g, _FRAGMENT_FILL, f) for g in geometries]
    if geometries[0].occluder_pixel is not None:
        q = round_up(max(np.shape(g.occluder_pixel)[0] for g in geometries if g.occluder_pixel is not None))
        padded = [_padded(g, _OCCLUDER_FILL, q) for g in padded]
    return padded


def stack_geometries(geometries: Sequence[Geometry]) -> Geometry:
    """One `Geometry` with a leading view axis: fragment and occluder arrays padded to the
    longest of the views (rounded up by `bucket`, so that batches compile rarely)."""
    return jax.tree.map(lambda *xs: jnp.stack(xs), *pad_geometries(geometries))


def view_mesh(devices=None) -> Mesh:
    """A one-axis mesh (`"views"`) over `devices` (default every available device)."""
    return Mesh(np.asarray(jax.devices() if devices is None else list(devices)), ("views",))


@eqx.filter_jit
def shade_views(geometry: Geometry, params) -> Float[Array, "V H W 4"]:
    """The shading stage of stacked geometries (`stack_geometries`), one compilation for all."""
    return jax.vmap(lambda g: shading_stage(g, params))(geometry)


def render_views(
    scene: Scene,
    cameras: Sequence[Camera] | None = None,
    params=None,
    *,
    lights: Sequence[Light] | None = None,
    devices=None,
) -> Float[Array, "V H W 4"]:
    """Render `scene` from each of `cameras` (and/or under each of `lights`) to linear
    RGBA `[V, H, W, 4]`, view i equal to `render(scene.replace(camera=cameras[i],
    light=lights[i]))`.

    One compilation of the shading stage serves all V views; the view axis is sharded
    over `devices` (default every device, `jax.devices()`), so with D devices each holds
    V/D views (V is padded to a multiple of D). Differentiable in `params` (default the
    scene's), like `render`. Each call runs every view's geometry stage; to shade many
    parameters, keep `stack_geometries([geometry_stage(s) for s in view_scenes(...)])` and
    call `shade_views` on it.
    """
    params = scene.params if params is None else params
    scenes = view_scenes(scene, cameras, lights)
    geometry = stack_geometries([geometry_stage(s) for s in scenes])
    v = len(scenes)
    mesh = view_mesh(devices)
    d = mesh.devices.size
    padded = -(-v // d) * d
    if padded != v:  # fires when V is not a multiple of the device count: repeat the last view
        extra = padded - v
        geometry = jax.tree.map(lambda x: jnp.concatenate([x, jnp.repeat(x[-1:], extra, axis=0)]), geometry)
    sharding = NamedSharding(mesh, PartitionSpec("views"))
    geometry = jax.tree.map(lambda x: jax.device_put(x, sharding), geometry)
    image = shade_views(geometry, params)
    return image[:v] if padded != v else image
