"""`reference_image`: a scene's strands rendered as fibres by Mitsuba 3 (docs/reference.md)."""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import numpy as np

from .._scene._reference import ReferenceSettings
from .._scene._scene import Scene
from ._fibres import bspline_control_points, curve_file_text, fibre_curves
from ._mitsuba_scene import mitsuba_scene, obj_text, sample_count
from ._support import MITSUBA_VARIANT, check_supported, import_mitsuba

__all__ = ["reference_image", "settings_of", "check_sampling", "MAX_SEED"]

MAX_SEED = 2**32 - 1  # Mitsuba's sampler seed is an unsigned 32-bit integer


@contextlib.contextmanager
def _variant(mi: ModuleType) -> Iterator[None]:
    """Mitsuba's `MITSUBA_VARIANT` inside the block; a variant the caller had set is set
    again after it. (`mi.variant_context` fails when no variant was set before.)"""
    before = mi.variant()
    mi.set_variant(MITSUBA_VARIANT)
    try:
        yield
    finally:
        if before is not None:
            mi.set_variant(before)


def settings_of(scene: Scene) -> ReferenceSettings:
    """The scene's reference settings: `scene.reference`, or the defaults when it has none."""
    return scene.reference if scene.reference is not None else ReferenceSettings()


def check_sampling(spp, seed) -> None:
    """`ValueError` unless `spp` is an integer ≥ 1 and `seed` one in [0, MAX_SEED]."""
    if isinstance(spp, bool) or not isinstance(spp, int | np.integer) or spp < 1:
        raise ValueError(f"spp must be an integer >= 1, got {spp!r}")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or not 0 <= seed <= MAX_SEED:
        raise ValueError(f"seed must be an integer in [0, {MAX_SEED}], got {seed!r}")


def reference_image(scene: Scene, *, spp: int | None = None, seed: int = 0) -> np.ndarray:
    """The physically based reference of `scene`: its strands as fibres with Chiang et al.
    2016's hair BSDF, path traced by Mitsuba 3 (`scalar_rgb`) under the scene's camera,
    light and occluder (docs/reference.md has the mapping of every quantity).

    **Arguments:**

    - `scene`: any scene without patches, streaks or a camera offset; the fibres and the
      path tracer are `scene.reference` (`ReferenceSettings()` when None). Strands in pixel
      widths become fibres w·D/f world units thick at depth D, as wide on screen as their
      ribbons (`_fibres.py`). The shading model, strand opacity and colour, shadow method
      and ordering are the real-time renderer's and are not read.
    - `spp`: samples per pixel (default: `scene.reference.spp`), rounded up to the
      stratified sampler's grid (`sample_count`: 16, 48, 64, 256 stay, 32 becomes 35).
    - `seed`: the sampler's seed, in [0, 2³² − 1]: the same seed and spp give the same image.

    **Returns:** `float32[H, W, 4]` linear RGBA as `hairjax.render` returns it: RGB over the
    background, alpha the fraction of the pixel's samples that hit a fibre or the occluder.

    **Raises:** `MissingDependency` without Mitsuba (`pip install 'hairjax[reference]'`);
    `SceneError` naming a feature the reference cannot show; `ValueError` for a bad spp or seed.
    """
    settings = settings_of(scene)
    spp = settings.spp if spp is None else spp
    check_sampling(spp, seed)
    check_supported(scene)
    mi = import_mitsuba()
    spp = sample_count(int(spp))
    points, offsets = fibre_curves(scene.strands, scene.camera)
    with tempfile.TemporaryDirectory(prefix="hairjax-reference-") as folder:
        curve_file = mesh_file = None
        if len(points):  # Mitsuba refuses an empty curve file; a scene with no fibre drawn has none
            curve_file = Path(folder) / "fibres.txt"
            curve_file.write_text(curve_file_text(*bspline_control_points(points, offsets)))
        occluder = scene.occluder
        if occluder is not None and occluder.kind == "mesh":
            mesh_file = Path(folder) / "occluder.obj"
            mesh_file.write_text(obj_text(np.asarray(occluder.vertices), np.asarray(occluder.triangles)))
        with _variant(mi):
            description = mitsuba_scene(mi, scene, settings, int(spp), curve_file, mesh_file)
            rendered = np.array(mi.render(mi.load_dict(description), seed=int(seed), spp=int(spp)))
    # Mitsuba's RGB is over black (a sample that hits nothing adds 0); alpha is coverage.
    image = rendered.astype(np.float32)
    image[..., :3] += (1.0 - image[..., 3:4]) * np.asarray(scene.background, dtype=np.float32)
    return image
