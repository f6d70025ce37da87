"""Live exploration of a scene's shading parameters and light in a notebook
(`explore(scene)`): sliders beside the rendered image (ipywidgets).

The staged renderer makes the shading sliders cheap: the geometry stage (projection,
draw order, fragments, opacity, Ω) runs once, and each move of a shading slider runs only
the shading stage, compiled once per panel. The light is different: its direction is an
input of the geometry stage (the opacity shadow maps are built from the light's view,
and L at every point with them), so a light slider re-runs the whole geometry stage —
seconds, not a fraction of one (BENCHMARKS.md, "Live exploration"). Its sliders update
on release only.
"""

from __future__ import annotations

import base64
import dataclasses
import math
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import equinox as eqx
import jax
import numpy as np

from ._errors import SceneError
from ._geometry_stage._stage import Geometry, geometry_stage
from ._io._image import write_image
from ._scene._scene import Scene
from ._shading import shading_stage
from ._shading._transforms import LOG
from ._values._light import Light

if TYPE_CHECKING:
    import ipywidgets as widgets  # type: ignore[import-untyped]

__all__ = ["Explorer", "explore", "slider_range", "light_angles", "light_from_angles"]


def slider_range(params: eqx.Module, name: str, model=None) -> tuple[str, float, float]:
    """The kind and range of the slider for parameter `name` of `params`.

    Where the shading `model` (a class or an instance) declares a range for `name`
    (`AbstractShadingModel.ranges`), the slider spans it, widened to hold the current
    value: logarithmic where the model searches `name` through `hj.extend.LOG` (and the range is
    positive), linear otherwise.
    Elsewhere the range comes from the parameter class's own validity check
    (`check_params`), probed with 0 and −1:

    - 0 refused (an exponent, p > 0): `"log"`, a logarithmic slider over the decades
      around the value, from one decade below to one above;
    - 0 allowed, −1 refused (a gain or κ ≥ 0): `"linear"` over [0, max(1, 2·value)];
    - −1 allowed (a tangent shift): `"linear"` over ±max(1, 2·|value|).

    `value` is the largest channel of an RGB parameter. Returns `(kind, low, high)`; for
    `"log"`, `low` and `high` are the powers of ten (the exponents, as `FloatLogSlider`
    takes them)."""
    value = float(np.max(np.asarray(getattr(params, name))))
    declared = None if model is None else model.ranges.get(name)
    if declared is not None:
        low, high = min(declared[0], value), max(declared[1], value)
        if model.searched.get(name) is LOG and declared[0] > 0:
            # A value of 0 (a LOG parameter whose check allows it) has no place on a log
            # slider: it keeps the declared low end, where the slider shows it.
            low = declared[0] if value <= 0 else low
            return "log", math.log10(low), math.log10(high)
        return "linear", low, high

    def accepts(x: float) -> bool:
        fields = {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}
        try:
            type(params)(**{**fields, name: x})
        except SceneError:
            return False
        return True

    if not accepts(0.0):
        # `value` > 0 here: the scene's own parameters passed the same check.
        centre = math.log10(value)
        return "log", float(math.floor(centre) - 1), float(math.ceil(centre) + 1)
    if not accepts(-1.0):
        return "linear", 0.0, max(1.0, 2 * value)
    bound = max(1.0, 2 * abs(value))
    return "linear", -bound, bound


def light_angles(scene: Scene) -> tuple[float, float]:
    """(azimuth, elevation) in degrees of the direction the light comes from, u: toward a
    directional light (−`direction`) or toward a point light from the camera's target.
    Elevation is u's angle above the world's x–z plane (+y up); azimuth is measured in
    that plane from +z toward +x (0: from +z, 90: from +x)."""
    light = scene.light
    if light.kind == "directional":
        u = -np.asarray(light.direction, dtype=np.float64)
    else:
        u = np.asarray(light.position, dtype=np.float64) - np.asarray(scene.camera.target, dtype=np.float64)
    norm = float(np.linalg.norm(u))
    if norm == 0:  # Fires for a point light at the camera's target: no direction, say (0, 0)
        return 0.0, 0.0
    u = u / norm
    elevation = math.degrees(math.asin(float(np.clip(u[1], -1.0, 1.0))))
    return math.degrees(math.atan2(float(u[0]), float(u[2]))), elevation


def light_from_angles(scene: Scene, azimuth: float, elevation: float) -> Light:
    """The scene's light moved to come from (`azimuth`, `elevation`) (`light_angles`): a
    directional light gets that direction, a point light that direction from the camera's
    target at its present distance. Colour and kind are kept."""
    a, e = math.radians(azimuth), math.radians(elevation)
    u = np.array([math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)])
    light = scene.light
    if light.kind == "directional":
        return dataclasses.replace(light, direction=tuple(-u))
    target = np.asarray(scene.camera.target, dtype=np.float64)
    distance = float(np.linalg.norm(np.asarray(light.position, dtype=np.float64) - target))
    return dataclasses.replace(light, position=tuple(target + distance * u))


def _rgb(geometry: Geometry, params) -> jax.Array:
    return shading_stage(geometry, params)[..., :3]


class Explorer:
    """A live panel for one scene (`explore`): the image (`image`, an `ipywidgets.Image`
    holding the PNG of the current render, 8-bit sRGB as `hairjax render --png` writes
    it) beside one slider per shading parameter and two for the light.

    **Attributes:** `widget`, the panel (`ipywidgets.HBox`, shown when the `Explorer` is
    the cell's value); `sliders`, the sliders by name: each field of the model's
    parameters (`kd`, `ks`, `shininess`, `kappa`, `ambient` for Kajiya-Kay; the
    Scheuermann fields for Scheuermann) and `light_azimuth`, `light_elevation`
    (degrees, `light_angles`); `image`; `scene`, the scene as the sliders now set it;
    `geometry_runs`, `shading_runs`, how many times each stage ran for the panel;
    `seconds`, the time of the last update (stage, PNG and all).

    An RGB parameter has one slider, its largest channel: moving it scales all three and
    keeps the scene's hue (Kd's hair colour stays brown as it brightens). Ranges come
    from the model's declared `ranges`, else from the parameter's validity check
    (`slider_range`). Setting a slider's `value`
    from Python updates the image at once, as dragging it does.
    """

    def __init__(self, scene: Scene):
        import ipywidgets as widgets  # type: ignore[import-untyped]

        if scene.patches is not None:
            raise ValueError("explore: hair-patch scenes (§18) have no geometry stage to keep")
        self.scene = scene
        self.geometry_runs = 0
        self.shading_runs = 0
        self.seconds = 0.0
        self._folder = tempfile.TemporaryDirectory(prefix="hairjax-explore-")
        # One compiled shading function per panel; the geometry enters as arguments.
        self._shade = eqx.filter_jit(_rgb)
        params = scene.params
        self._names = [f.name for f in dataclasses.fields(params)]
        # An RGB parameter's hue: its channels over the largest (grey where it is 0).
        self._hue: dict[str, np.ndarray | None] = {}
        self.sliders: dict[str, widgets.FloatSlider | widgets.FloatLogSlider] = {}
        for name in self._names:
            channels = np.asarray(getattr(params, name), dtype=np.float64)
            top = float(np.max(channels))
            # Fires for a black RGB parameter: no hue to keep, the slider sets grey.
            self._hue[name] = None if channels.ndim == 0 else (channels / top if top > 0 else np.ones(3))
            kind, low, high = slider_range(params, name, scene.shading)
            common = dict(value=top, description=name, continuous_update=True, readout_format=".3g")
            if kind == "log":
                slider = widgets.FloatLogSlider(base=10, min=low, max=high, step=0.01, **common)
            else:
                slider = widgets.FloatSlider(min=low, max=high, step=(high - low) / 200, **common)
            slider.observe(self._on_shading, names="value")
            self.sliders[name] = slider
        azimuth, elevation = light_angles(scene)
        for name, angle, bound in (("light_azimuth", azimuth, 180.0), ("light_elevation", elevation, 90.0)):
            # Each move re-runs the geometry stage (seconds): update on release only.
            slider = widgets.FloatSlider(
                value=angle, min=-bound, max=bound, step=1.0, description=name, continuous_update=False
            )
            slider.observe(self._on_light, names="value")
            self.sliders[name] = slider
        self.status = widgets.Label()
        self._geometry = self._run_geometry(scene)
        self.image = widgets.Image(format="png", width=scene.camera.width, height=scene.camera.height)
        self._show(time.perf_counter())
        self.widget = widgets.HBox([self.image, widgets.VBox([*self.sliders.values(), self.status])])

    # ------------------------------------------------------------------ state
    def params(self) -> Any:
        """The shading parameters the sliders set now (the model's `params_type`)."""
        values: dict[str, Any] = {}
        for name in self._names:
            value, hue = self.sliders[name].value, self._hue[name]
            values[name] = value if hue is None else value * hue
        return type(self.scene.params)(**values)

    @property
    def png(self) -> bytes:
        """The PNG bytes the panel shows."""
        return bytes(self.image.value)  # the widget holds a memoryview

    # ------------------------------------------------------------------ updates
    def _run_geometry(self, scene: Scene) -> Geometry:
        self.geometry_runs += 1
        return jax.block_until_ready(geometry_stage(scene))

    def _show(self, start: float) -> None:
        """Shade with the sliders' parameters, show the PNG; `start`: when the update began."""
        params = self.params()
        rgb = np.asarray(self._shade(self._geometry, params))
        self.shading_runs += 1
        # The PNG writer's own tone map (clip, sRGB, 8 bits): the picture `hairjax render
        # --png` would write for these parameters.
        path = write_image(Path(self._folder.name) / "panel.png", rgb)
        self.image.value = path.read_bytes()
        self.scene = self.scene.replace(params=params)
        self.seconds = time.perf_counter() - start
        self.status.value = (
            f"{self.seconds:.2f} s ({self.geometry_runs} geometry, {self.shading_runs} shading runs)"
        )

    def _on_shading(self, change) -> None:
        self._show(time.perf_counter())

    def _on_light(self, change) -> None:
        start = time.perf_counter()
        light = light_from_angles(
            self.scene, self.sliders["light_azimuth"].value, self.sliders["light_elevation"].value
        )
        # A new Scene: its geometry (shadow maps included) is computed afresh and cached
        # on it; the previous scene, no longer held, takes its cache with it.
        self.scene = self.scene.replace(light=light)
        self._geometry = self._run_geometry(self.scene)
        self._show(start)

    # ------------------------------------------------------------------ display
    def _repr_mimebundle_(self, **kwargs) -> dict:
        """The panel where widgets run; its current picture (`image/png`) where they do not
        (a notebook viewed on GitHub, say)."""
        bundle = dict(self.widget._repr_mimebundle_(**kwargs) or {})
        # A notebook's JSON holds PNG as base64 text, as IPython's own Image sends it.
        bundle["image/png"] = base64.b64encode(self.png).decode("ascii")
        return bundle


def explore(scene: Scene) -> Explorer:
    """A live panel of `scene` for a notebook: sliders for each shading parameter of its
    model and for the light's azimuth and elevation, beside the image (`Explorer`).

    A shading slider re-runs only the shading stage, compiled once for the panel, with the
    geometry stage kept: a fraction of a second at 256² on the default scene. A light
    slider re-runs the geometry stage too (shadow maps are built from the light) and
    updates on release. Needs ipywidgets. Show the result as a cell's value."""
    return Explorer(scene)
