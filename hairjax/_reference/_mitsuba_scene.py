"""A hairjax scene as a Mitsuba 3 scene description (`mitsuba.load_dict`'s dictionary).

Each part maps to its Mitsuba counterpart (docs/reference.md, "The mapping"):

- camera (docs/model.md §2): `perspective` with `look_at(eye, target, up)`, `fov` on the
  vertical axis (`fov_axis = "y"`; Mitsuba's default is x), `near_clip` = camera.near; an
  `hdrfilm` of W × H pixels, pixel (i, j) covering [i, i + 1) × [j, j + 1), row 0 at the top,
  with a box filter (the pixel box of §5's coverage), RGBA so that alpha is coverage, and
  stratified samples (`multijitter`);
- light (§3): hairjax's light colour is the radiance a white Lambertian surface facing the
  light reflects (§9: an occluder of colour k shows k·light·max(N·L, 0)), and a Lambertian
  BRDF is k/π, so the directional emitter's irradiance is π·colour; `direction` is the way
  the light travels in both. A hairjax point light does not fall off with distance; Mitsuba's
  does (intensity/d²), so its intensity is π·colour·d₀², d₀ the light's distance to the
  centre of the hair's bounding sphere: the two agree there;
- occluder (§9, §13): a `sphere` or an `obj` mesh (the occluder's own triangles) with a
  `diffuse` BSDF of reflectance k;
- strands: a `bsplinecurve` (`_fibres.py`: the polylines themselves, with the frame the
  `hair` BSDF reads) with the `hair` BSDF of `ReferenceSettings`;
- the integrator: `path` with `max_depth`.
"""

from __future__ import annotations

import math
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from .._scene._framing import bounding_sphere
from .._scene._reference import ReferenceSettings
from .._scene._scene import Scene

__all__ = ["mitsuba_scene", "light_emitter", "hair_bsdf", "obj_text", "sample_count", "FAR_FACTOR"]

# The far clipping plane sits this many times beyond the farthest point of the scene
# (strands, occluder), so that nothing the camera sees is clipped, whatever the units.
FAR_FACTOR = 10.0


def sample_count(spp: int) -> int:
    """The samples per pixel Mitsuba's `multijitter` sampler takes for `spp`: a grid of
    ⌊√spp⌋ rows and as many columns as cover spp (16, 48, 64, 256 stay; 32 becomes 35). The
    grid stratifies the samples over the pixel, so a fibre's coverage is far less noisy than
    with independent samples (measured: a 1-pixel fibre's IoU with its ribbon 0.89–0.90 at
    16 spp, against 0.81–0.86)."""
    rows = math.isqrt(spp)
    return rows * -(-spp // rows)


def _floats(value) -> list[float]:
    return [float(v) for v in np.asarray(value, dtype=np.float64)]


def _rgb(value) -> dict[str, Any]:
    return {"type": "rgb", "value": _floats(value)}


def _near(scene: Scene) -> float:
    # Camera replaces a near of None by its default at construction.
    return float(np.asarray(scene.camera.near, dtype=np.float64))


def light_emitter(scene: Scene) -> dict[str, Any]:
    """The scene's light as a Mitsuba emitter (module docstring)."""
    light = scene.light
    colour = math.pi * np.asarray(light.color)
    if light.kind == "directional":
        return {"type": "directional", "direction": _floats(light.direction), "irradiance": _rgb(colour)}
    centre, _ = bounding_sphere(scene.strands.points)
    d0 = float(np.linalg.norm(np.asarray(light.position) - centre))
    # Fires for a point light at the hair's centre: no distance to match at, so d₀ = 1.
    d0 = d0 if d0 > 0 else 1.0
    return {"type": "point", "position": _floats(light.position), "intensity": _rgb(colour * d0**2)}


def hair_bsdf(settings: ReferenceSettings) -> dict[str, Any]:
    """Mitsuba's `hair` BSDF (Chiang et al. 2016) with `settings`' parameters."""
    bsdf: dict[str, Any] = {
        "type": "hair",
        "longitudinal_roughness": settings.longitudinal_roughness,
        "azimuthal_roughness": settings.azimuthal_roughness,
        "scale_tilt": settings.scale_tilt,
        # The plugin's η is int_ior/ext_ior, and ext_ior defaults to air's 1.000277.
        "int_ior": settings.eta,
        "ext_ior": 1.0,
    }
    if settings.sigma_a is not None:
        bsdf["sigma_a"] = _rgb(settings.sigma_a)
    else:
        bsdf["eumelanin"] = settings.eumelanin
        bsdf["pheomelanin"] = settings.pheomelanin
    return bsdf


def _far_clip(scene: Scene) -> float:
    eye = np.asarray(scene.camera.eye)
    extent = [np.linalg.norm(scene.strands.points - eye, axis=1).max(initial=0.0)]
    occluder = scene.occluder
    if occluder is not None and occluder.kind == "sphere":
        extent.append(np.linalg.norm(np.asarray(occluder.center) - eye) + occluder.radius)
    elif occluder is not None:
        extent.append(np.linalg.norm(np.asarray(occluder.vertices) - eye, axis=1).max())
    return FAR_FACTOR * max(float(max(extent)), _near(scene))


def mitsuba_scene(
    mi: ModuleType,
    scene: Scene,
    settings: ReferenceSettings,
    spp: int,
    curve_file: Path | None,
    mesh_file: Path | None,
) -> dict[str, Any]:
    """`scene` as a dictionary for `mi.load_dict` (module docstring). `curve_file`: the
    fibres (`_fibres.curve_file_text`), None when no fibre is drawn; `mesh_file`: the mesh
    occluder's triangles as OBJ, None without one. `mi`: the `mitsuba` module, in the
    variant to render with."""
    camera = scene.camera
    out: dict[str, Any] = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": settings.max_depth},
        "sensor": {
            "type": "perspective",
            "fov": camera.fov,
            "fov_axis": "y",
            "near_clip": _near(scene),
            "far_clip": _far_clip(scene),
            "to_world": mi.ScalarTransform4f().look_at(
                origin=list(camera.eye), target=list(camera.target), up=list(camera.up)
            ),
            "film": {
                "type": "hdrfilm",
                "width": camera.width,
                "height": camera.height,
                "pixel_format": "rgba",
                "rfilter": {"type": "box"},
            },
            "sampler": {"type": "multijitter", "sample_count": sample_count(spp)},
        },
        "light": light_emitter(scene),
    }
    if curve_file is not None:
        out["hair"] = {"type": "bsplinecurve", "filename": str(curve_file), "bsdf": hair_bsdf(settings)}
    occluder = scene.occluder
    if occluder is not None:
        bsdf = {"type": "diffuse", "reflectance": _rgb(occluder.color)}
        if occluder.kind == "sphere":
            out["occluder"] = {
                "type": "sphere",
                "center": list(occluder.center),
                "radius": occluder.radius,
                "bsdf": bsdf,
            }
        else:
            out["occluder"] = {"type": "obj", "filename": str(mesh_file), "bsdf": bsdf}
    return out


def obj_text(vertices: np.ndarray, triangles: np.ndarray) -> str:
    """A triangle mesh as OBJ text (`v` lines, then 1-based `f` lines), for Mitsuba's reader."""
    lines = [f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles]
    return "\n".join(lines) + "\n"
