"""The JSON records `hairjax render` and `hairjax reference` write beside an image: what made it.

The scene as resolved (every dataclass field, defaults included, after --set), the
command line, the versions of hairjax and its numerical dependencies, and the time of
each stage. `render`'s adds the shading model's parameters and the device it ran on (JAX's
platform and device kind, where the set-up ran, and for `--backend gl` the GL renderer
string); `reference`'s adds the fibres' pigments and the path tracer's samples, seed and
depth, and Mitsuba's version. Arrays of more than a few numbers (the strands' points) are
summarised by shape and range, so the record stays small and readable.
"""

from __future__ import annotations

import dataclasses
import datetime
import platform
import sys
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

__all__ = ["render_record", "reference_record", "jsonable", "versions", "write_image_and_record"]

_SMALL = 16  # arrays up to this many numbers are written out in full
_VERSIONED = ("hairjax", "jax", "jaxlib", "numpy", "equinox", "optimistix", "moderngl", "OpenImageIO")
_REFERENCE_VERSIONED = ("mitsuba", "drjit")  # the [reference] extra


def jsonable(value: Any) -> Any:
    """`value` as JSON data: dataclasses (equinox modules too) as tables of their fields,
    small arrays as lists, large ones as {shape, dtype, min, max}."""
    import numpy as np

    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        table: dict[str, Any] = {"type": type(value).__name__}
        for field in dataclasses.fields(value):
            table[field.name] = jsonable(getattr(value, field.name))
        return table
    if isinstance(value, (str, bool, int, type(None))):
        return value
    if isinstance(value, float):
        return value if np.isfinite(value) else str(value)  # JSON has no inf or nan
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    try:
        array = np.asarray(value)
    except Exception:  # not array-like (a callable, a texture object): its name only
        return type(value).__name__
    if array.dtype == object:
        return type(value).__name__
    if array.size <= _SMALL:
        return jsonable(array.tolist())
    summary: dict[str, Any] = {"shape": list(array.shape), "dtype": str(array.dtype)}
    if array.dtype.kind in "fiub":
        summary["min"], summary["max"] = float(array.min()), float(array.max())
    return summary


def versions(names: tuple[str, ...] = _VERSIONED) -> dict[str, str]:
    """Python's version and each distribution's in `names`."""
    out = {"python": platform.python_version()}
    for name in names:
        try:
            out[name] = version(name)
        except PackageNotFoundError:  # an optional dependency that is not installed
            out[name] = "not installed"
    return out


def _made(scene, scene_file: Path, overrides: dict[str, Any], images: list[Path]) -> dict:
    """What every record holds: the command, the time, the scene file with its overrides,
    the images and the scene as resolved."""
    return {
        "command": ["hairjax", *sys.argv[1:]],
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "scene_file": str(scene_file),
        "overrides": jsonable(overrides),
        "image": {
            "files": [p.name for p in images],
            "width": scene.camera.width,
            "height": scene.camera.height,
        },
        "scene": jsonable(scene),
    }


def _device(backend: str) -> dict[str, str]:
    """Where the render ran: JAX's devices (`_device.device_record`), and for GL the
    renderer string of the context `render_gl` used."""
    from .._device import device_record

    device = device_record()
    if backend == "gl":
        from ..gl import renderer_info

        device |= renderer_info()
    return device


def render_record(
    scene, scene_file: Path, overrides: dict[str, Any], backend: str, timings: dict, images: list[Path]
) -> dict:
    """The sidecar's content for `scene`, read from `scene_file` with `overrides` (--set,
    --seed, --size) and rendered by `backend` in `timings` (seconds by stage)."""
    import numpy as np

    return {
        **_made(scene, scene_file, overrides, images),
        "backend": backend,
        "device": _device(backend),
        "shading": {
            "model": type(scene.shading).__name__,
            "params": {
                f.name: np.asarray(getattr(scene.params, f.name)).tolist()
                for f in dataclasses.fields(scene.params)
            },
        },
        "timings_s": {k: round(float(v), 6) for k, v in timings.items()},
        "versions": versions(),
    }


def reference_record(
    scene, scene_file: Path, overrides: dict[str, Any], sampling: dict[str, int], seconds: float, images
) -> dict:
    """The sidecar of `hairjax reference`: `scene`'s reference settings as used (the
    pigments, or `sigma_a` where the scene gives the absorption instead), `sampling` (the
    spp the sampler took, the seed) and the path tracer's time."""
    from .._reference._render import settings_of

    settings = settings_of(scene)
    return {
        **_made(scene, scene_file, overrides, images),
        "reference": {
            "eumelanin": settings.eumelanin,
            "pheomelanin": settings.pheomelanin,
            "sigma_a": jsonable(settings.sigma_a),
            "longitudinal_roughness": settings.longitudinal_roughness,
            "azimuthal_roughness": settings.azimuthal_roughness,
            "scale_tilt": settings.scale_tilt,
            "eta": settings.eta,
            "max_depth": settings.max_depth,
            **sampling,
        },
        "timings_s": {"reference": round(float(seconds), 6)},
        "versions": versions(_VERSIONED + _REFERENCE_VERSIONED),
    }


def write_image_and_record(image, images: list[Path], sidecar: Path | None, record) -> list[Path]:
    """Write `image` to every path of `images` and, unless `sidecar` is None, the JSON of
    `record()` beside them, all together (`written_together`: the image renamed last).
    `record` is called only once the image is written. Returns the paths written."""
    from .._io._files import write_json
    from .._io._image import write_image
    from ._outputs import written_together

    paths = images + ([sidecar] if sidecar is not None else [])
    with written_together(paths) as temps:
        for tmp in temps[: len(images)]:
            write_image(tmp, image)
        if sidecar is not None:
            write_json(temps[-1], record())
    return paths
