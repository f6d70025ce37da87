"""`distill`: a real-time shading model's parameters for a physically based hair
(docs/physically_based.md, "Distilling a hair colour").

The physically based reference (`reference_image`: the scene's strands as fibres with
Chiang et al. 2016's hair BSDF, path traced by Mitsuba 3) is rendered under a few views of
the scene, and the real-time model is fitted to the training views (`fit`); the views held
out measure what the fitted parameters are worth where the fit did not look. The views are
values (`DistillView`): the camera turned about its up vector through its target, under
the scene's light or a light derived from it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Literal, NamedTuple

import numpy as np

from ._errors import SceneError
from ._fit import FitError, FitResult, FitStop, FitTargets, FitVariables, fit
from ._progress import Progress, counter
from ._reference._render import check_sampling, settings_of
from ._reference._support import check_supported, import_mitsuba
from ._scene._scene import Scene
from ._shading import AbstractShadingModel, shading_model_class
from ._values._camera import Camera
from ._values._light import Light

__all__ = ["DistillView", "DISTILL_VIEWS", "Distillation", "distill"]

LightName = Literal["key", "back", "side"]


class DistillView(NamedTuple):
    """One view of a distillation.

    - `name`: how the result names it (unique among the views).
    - `azimuth`: the scene's camera turned by this many degrees about its up vector,
      through its target.
    - `light`: "key", the scene's light; "back", a directional light travelling from behind
      and above the hair towards the eye; "side", the key light's direction turned 90°
      about the camera's up vector (a directional light).
    - `train`: fitted (True) or held out (False).
    """

    name: str
    azimuth: float = 0.0
    light: LightName = "key"
    train: bool = True


# The views of docs/physically_based.md §1: three train (the scene's camera and light, the
# camera turned 60°, the camera under a back light) and one is held out (the camera turned
# −50° under a side light: a view and a light the fit never saw).
DISTILL_VIEWS = (
    DistillView("front", 0.0, "key", True),
    DistillView("side", 60.0, "key", True),
    DistillView("back-lit", 0.0, "back", True),
    DistillView("held-out", -50.0, "side", False),
)
# How far above the eye the back light comes from: its direction is the unit vector of
# (towards the eye − BACK_LIGHT_DROP · up), about 31° below the line of sight.
BACK_LIGHT_DROP = 0.6


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def _turn(v, axis, degrees: float) -> np.ndarray:
    """`v` turned by `degrees` about the unit `axis` (Rodrigues' formula)."""
    a = math.radians(degrees)
    v, k = np.asarray(v, float), _unit(axis)
    return v * math.cos(a) + np.cross(k, v) * math.sin(a) + k * float(k @ v) * (1.0 - math.cos(a))


def _key_direction(light: Light, camera: Camera) -> np.ndarray:
    """The direction the scene's light travels in: a point light's towards the target."""
    if light.kind == "point":
        return _unit(np.subtract(camera.target, np.asarray(light.position, dtype=float)))
    return _unit(light.direction)


def view_scene(scene: Scene, view: DistillView) -> Scene:
    """`scene` under `view`'s camera and light (`DistillView`)."""
    cam = scene.camera
    target = np.asarray(cam.target, float)
    eye = target + _turn(np.subtract(cam.eye, target), cam.up, view.azimuth)
    camera = dataclasses.replace(cam, eye=tuple(float(x) for x in eye))
    if view.light == "key":
        light = scene.light
    elif view.light == "back":
        to_eye = _unit(np.subtract(cam.eye, cam.target))
        back = _unit(to_eye - BACK_LIGHT_DROP * _unit(cam.up))
        light = Light(direction=tuple(float(x) for x in back), color=scene.light.color)
    else:
        side = _turn(_key_direction(scene.light, cam), cam.up, 90.0)
        light = Light(direction=tuple(float(x) for x in side), color=scene.light.color)
    return scene.replace(camera=camera, light=light, name=f"{scene.name}-{view.name}")


def image_rmse(images, references) -> float:
    """√(Σ (a − b)² / 3N) over the RGB of every pixel, pooled over the pairs: the
    definition of `FitResult.rmse`."""
    pairs = list(zip(images, references, strict=True))
    total = sum(float(np.sum((np.asarray(a)[..., :3] - np.asarray(b)[..., :3]) ** 2)) for a, b in pairs)
    return math.sqrt(total / sum(3 * np.asarray(a)[..., 0].size for a, _ in pairs))


@dataclasses.dataclass(frozen=True)
class Distillation:
    """What `distill` returns.

    - `model`: the fitted shading model (the scene's model type with the fitted parameters).
    - `result`: the fit's `FitResult` (steps, standard errors, `rmse` on the training views).
    - `views`: the views, in order; `scenes`: view name → the scene under that view with
      the fitted model.
    - `references`: view name → the reference (sampler seed `seed`), `float32[H, W, 4]`.
    - `images`: view name → the fitted model's render of that view.
    - `rmse`: view name → the fitted render's RMSE against its reference.
    - `second`: view name → the reference at the next seed, where it was made
      (`distill(noise_floor=True)`, or a pair given in `references`); empty otherwise.
    - `floors`: view name → the noise floor, the RMSE between `references` and `second`.
    """

    model: AbstractShadingModel
    result: FitResult
    views: tuple[DistillView, ...]
    scenes: dict[str, Scene]
    references: dict[str, np.ndarray]
    images: dict[str, np.ndarray]
    rmse: dict[str, float]
    floors: dict[str, float]
    second: dict[str, np.ndarray]

    @property
    def params(self):
        """The fitted parameters (the model's `params_type`)."""
        return self.result.params

    @property
    def holdout_rmse(self) -> float | None:
        """The RMSE over the held-out views, pooled (None without one)."""
        return self.result.holdout_rmse

    def floor(self, train: bool) -> float | None:
        """The noise floor pooled over the training (or the held-out) views, as `rmse`
        pools them; None where a view of them has no second render."""
        names = [v.name for v in self.views if v.train == train]
        if not names or any(n not in self.second for n in names):
            return None
        return image_rmse([self.references[n] for n in names], [self.second[n] for n in names])


def _model_of(model: str | AbstractShadingModel) -> AbstractShadingModel:
    if isinstance(model, AbstractShadingModel):
        return model
    if not isinstance(model, str):
        raise TypeError(f"model must be a shading model's name or a shading model, got {model!r}")
    try:
        kind = shading_model_class(model)
    except SceneError as err:
        raise SceneError(f"distill: {err}") from None
    # The defaults, with no ambient term: the reference has no ambient light.
    default = kind()  # type: ignore[call-arg]  # every model's params has a default
    return default.replace_params(dataclasses.replace(default.params, ambient=0.0))


def _reference_settings(scene: Scene, eumelanin, pheomelanin, roughness, azimuthal_roughness, spp):
    given = {
        "eumelanin": eumelanin,
        "pheomelanin": pheomelanin,
        "longitudinal_roughness": roughness,
        "azimuthal_roughness": azimuthal_roughness,
        "spp": spp,
    }
    given = {k: v for k, v in given.items() if v is not None}
    settings = settings_of(scene)
    if ("eumelanin" in given or "pheomelanin" in given) and settings.sigma_a is not None:
        # The pigments replace a σ_a the scene's [reference] table gave (one way at a time).
        settings = dataclasses.replace(settings, sigma_a=None, eumelanin=0.0, pheomelanin=0.0)
    try:
        return dataclasses.replace(settings, **given)
    except SceneError as err:
        raise SceneError(f"distill: {err}") from None


def _check_views(views: Sequence[DistillView]) -> tuple[DistillView, ...]:
    views = tuple(views)
    names = [v.name for v in views]
    if len(set(names)) != len(names):
        raise ValueError(f"distill: the views' names must be unique, got {names}")
    for v in views:
        if v.light not in ("key", "back", "side"):
            raise ValueError(f"distill: view {v.name!r}: light must be key, back or side, got {v.light!r}")
        if not math.isfinite(v.azimuth):
            raise ValueError(f"distill: view {v.name!r}: azimuth must be finite, got {v.azimuth!r}")
    if not any(v.train for v in views):
        raise ValueError("distill: no training view (every view has train=False)")
    return views


def _given_references(references: Mapping, views) -> tuple[dict, dict]:
    """(view → reference, view → the same at another seed where a pair was given)."""
    first, second = {}, {}
    for v in views:
        if v.name not in references:
            raise ValueError(f"distill: references has no view {v.name!r} (it has {', '.join(references)})")
        given = references[v.name]
        if isinstance(given, tuple):
            first[v.name], second[v.name] = (np.asarray(x, np.float32) for x in given)
        else:
            first[v.name] = np.asarray(given, np.float32)
    return first, second


def distill(
    scene: Scene,
    model: str | AbstractShadingModel = "marschner",
    *,
    eumelanin: float | None = None,
    pheomelanin: float | None = None,
    roughness: float | None = None,
    azimuthal_roughness: float | None = None,
    spp: int | None = None,
    seed: int = 0,
    views: Sequence[DistillView] = DISTILL_VIEWS,
    fit_names: Sequence[str] | None = None,
    max_steps: int = 100,
    noise_floor: bool = False,
    references: Mapping | None = None,
    progress: Progress | None = None,
) -> Distillation:
    """Fit a real-time shading model to physically based hair: render the reference of
    `scene` under `views`, fit `model` to the training views, and measure it on the views
    held out (docs/physically_based.md, "Distilling a hair colour").

    **Arguments:**

    - `scene`: the hair, camera and light (any scene `reference_image` takes). Its strands
      are drawn as they are: the reference's fibres are opaque, so strands of alpha 1 as
      wide as the fibres (1 px) are what the reference sees (experiment 14 uses those).
    - `model`: a registered shading model's name ("marschner", "kajiya-kay-mirror",
      "scheuermann", …: its default parameters are the start) or a shading model, whose
      parameters are the start (`hj.Marschner(multiple_scattering="dual")` for Marschner
      with dual scattering).
    - `eumelanin`, `pheomelanin`, `roughness` (the longitudinal β_m),
      `azimuthal_roughness`, `spp`: the reference's hair and samples; None takes the
      scene's `[reference]` table's (`ReferenceSettings`'s defaults when it has none).
    - `seed`: the reference's sampler seed.
    - `views`: the `DistillView`s (default `DISTILL_VIEWS`: three training views, one
      held out).
    - `fit_names`: the names to fit (`fit`'s `fit`; default the model's `fittable`).
    - `max_steps`: the fit's step limit.
    - `noise_floor`: render each reference again at `seed + 1`, for `Distillation.floors`
      (twice the reference's time).
    - `references`: view name → reference image, or a pair of images at two seeds, made
      before (`Distillation.references`, to fit another model to the same references):
      nothing is rendered then, and the reference arguments are not read.
    - `progress`: called as `progress(done, total, message)` after each reference, the fit
      and the renders of the fitted model.

    **Returns:** a `Distillation`: the fitted model, the `FitResult` (its `holdout_rmse` is
    the held-out error), and every view's reference, fitted image and RMSE.

    **Raises:** `MissingDependency` without Mitsuba (`pip install 'hairjax[reference]'`)
    and `SceneError` for a scene the reference cannot show, both before any work, unless
    `references` are given; `ValueError` for bad views or references; `FitError` for a bad
    fit input.
    """
    views = _check_views(views)
    start_model = _model_of(model)
    names = tuple(start_model.fittable) if fit_names is None else tuple(fit_names)
    if references is None:
        settings = _reference_settings(scene, eumelanin, pheomelanin, roughness, azimuthal_roughness, spp)
        check_sampling(settings.spp, seed + 1 if noise_floor else seed)
        check_supported(scene)
        import_mitsuba()  # one line without Mitsuba, before any work
        scene = scene.replace(reference=settings)
    scenes = {v.name: view_scene(scene.replace(shading=start_model), v) for v in views}
    renders = len(views) * (2 if noise_floor else 1) if references is None else 0
    step = counter(renders + 2, progress)
    if references is None:
        first, second = _rendered_references(scenes, views, seed, noise_floor, step)
    else:
        first, second = _given_references(references, views)
    result = _fit_views(scenes, first, views, names, max_steps)
    step(f"fit {start_model.name}: {result.steps} steps, {result.termination}")
    distillation = _distillation(start_model, result, views, scenes, first, second)
    step("fitted renders")
    return distillation


def _distillation(start_model, result: FitResult, views, scenes: dict, first: dict, second: dict):
    """The `Distillation`: the fitted model, each view rendered with it and measured
    against its reference, and the noise floors where a second reference was made."""
    from ._render import render

    fitted = start_model.replace_params(result.params)
    scenes = {n: s.replace(shading=fitted) for n, s in scenes.items()}
    images = {n: np.asarray(render(s)) for n, s in scenes.items()}
    return Distillation(
        model=fitted,
        result=result,
        views=views,
        scenes=scenes,
        references=first,
        images=images,
        rmse={n: image_rmse([images[n]], [first[n]]) for n in scenes},
        floors={n: image_rmse([first[n]], [second[n]]) for n in second},
        second=second,
    )


def _rendered_references(scenes: dict, views, seed: int, noise_floor: bool, step) -> tuple[dict, dict]:
    """(view → reference at `seed`, view → reference at `seed + 1` where `noise_floor`),
    each render counted by `step`."""
    from ._reference import reference_image

    first: dict[str, np.ndarray] = {}
    second: dict[str, np.ndarray] = {}
    for v in views:
        for s, out in ((seed, first), (seed + 1, second))[: 2 if noise_floor else 1]:
            out[v.name] = reference_image(scenes[v.name], seed=s)
            step(f"reference {v.name} (seed {s})")
    return first, second


def _fit_views(scenes: dict, references: dict, views, names, max_steps: int) -> FitResult:
    """The fit to the training views' references, the views held out as its holdout;
    FitError naming `distill`."""
    train = [v.name for v in views if v.train]
    held = [v.name for v in views if not v.train]
    holdout = ([scenes[n] for n in held], [references[n] for n in held]) if held else None
    try:
        return fit(
            [scenes[n] for n in train],
            FitTargets([references[n] for n in train], holdout=holdout),
            variables=FitVariables(names),
            stop=FitStop(max_steps=max_steps),
        )
    except FitError as err:
        raise FitError(f"distill: {err}") from None
