"""Small scenes and checks shared by the tests."""

from __future__ import annotations

import contextlib
import re
from pathlib import Path

import numpy as np
import pytest
from jaxtyping import TypeCheckError

import hairjax as hj
from hairjax._disagreement import MAX_BAND, PIXEL_TOL, TAU_TOL, camera_band, shadow_band  # noqa: F401 (tests')

# tests/helpers.py sits directly in tests/: the repository root is one folder up, whichever
# subfolder of tests/ imports this (test files use these rather than their own __file__).
REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
EXAMPLES = REPO / "experiments" / "scenes"


def first_then_slow(values) -> list:
    """Parameters of which `make test` runs the first and the slow tier (`make test-slow`,
    README) the others: the further cases of a check that every case runs the same way."""
    values = list(values)
    return values[:1] + [pytest.param(v, marks=pytest.mark.slow) for v in values[1:]]


def load_experiment(name: str):
    """The module experiments/NAME.py (experiments/ is not a package)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, REPO / "experiments" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def small_furball_scene(
    strands=40, size=48, shadows="opacity-maps", maps=8, resolution=32, alpha=0.6, **scene_kw
) -> hj.Scene:
    hair = hj.furball(strands=strands, points=6, seed=3, alpha=alpha)
    return hj.Scene(
        strands=hair,
        camera=hj.Camera(eye=(0.0, 0.3, 3.5), target=(0.0, 0.0, 0.0), fov=45.0, width=size, height=size),
        light=hj.Light(direction=(-0.5, -0.7, -0.4)),
        shading=hj.KajiyaKay(
            hj.ShadingParams(kd=(0.6, 0.4, 0.3), ks=0.4, shininess=20.0, kappa=0.8, ambient=0.05)
        ),
        shadows=shadow_method(shadows, maps, resolution),
        **scene_kw,
    )


def scheuermann_scene(size=24, strands=30, shadows="opacity-maps", **maps) -> hj.Scene:
    """A small scalp with Scheuermann shading (docs/model.md §17); `maps` go to
    ScheuermannMaps (textures, noise). For its shading tests and its fit's."""
    hair = hj.scalp(strands=strands, points=6, seed=4, length=0.8, gravity=(0.0, -0.4, 0.0), alpha=0.6)
    return hj.Scene(
        hair,
        camera=hj.Camera(eye=(1.6, 0.6, 2.4), target=(0.0, 0.0, 0.0), width=size, height=size),
        light=hj.Light(direction=(-0.3, -0.6, -0.75)),
        shading=hj.Scheuermann(
            hj.ScheuermannParams(
                kd=(0.5, 0.35, 0.2),
                ambient=0.05,
                primary_color=0.4,
                primary_exponent=30.0,
                primary_shift=0.15,
                secondary_color=(0.4, 0.3, 0.2),
                secondary_exponent=8.0,
                secondary_shift=-0.2,
                kappa=0.9,
            ),
            hj.ScheuermannMaps(normal_center=(0.0, 0.0, 0.0), **maps),
        ),
        shadows=shadow_method(shadows, 6, 24),
    )


def fit_terms(scene, params, names, target):
    """The fit's per-target terms (hairjax/_fit/_shading_fit.py) for `target` (an image)."""
    from hairjax._fit import _shading_fit

    h, w = scene.camera.height, scene.camera.width
    model = _shading_fit.fit_model(type(scene.shading))
    return model.prepare(
        scene, params, tuple(names), np.asarray(target)[..., :3].reshape(-1, 3), np.ones((h * w, 1))
    )


def fit_image(terms, kd, ks, shininess, kappa, ambient, plain=False):
    """The fit's own Kajiya-Kay image `[HW, 3]` of `terms` at these values (with `plain`,
    through plain autodiff instead of the fit's one-pass derivative rule)."""
    from hairjax._fit import _shading_fit

    params = hj.ShadingParams(kd=kd, ks=ks, shininess=shininess, kappa=kappa, ambient=ambient)
    return _shading_fit.target_image(terms, params, plain=plain)


@contextlib.contextmanager
def refused(field: str, message: str, error: type[Exception] = hj.SceneError):
    """The block is refused a value of the wrong type for `field`: `error` (SceneError)
    matching `message`, or the annotation check's TypeCheckError naming the parameter
    (pytest runs jaxtyping's import hook: a value of the wrong type meets the annotation
    check before the constructor's own; users without the hook get `error`)."""
    with pytest.raises((error, TypeCheckError)) as info:
        yield
    if isinstance(info.value, TypeCheckError):
        assert f"parameter '{field}'" in str(info.value), str(info.value)
    else:
        assert re.search(message, str(info.value)), (message, str(info.value))


def cone(model: str):
    """The Kajiya-Kay cone (`seed_cone`, `mirror_cone`) of the registered model `model`."""
    return hj.extend.shading_model_class(model).cone


def shadow_method(method: str, maps: int = 8, resolution: int = 32):
    """`hj.Shadows(method, …)` with the options that method takes."""
    options = {
        "opacity-maps": dict(maps=maps, resolution=resolution),
        "exact": dict(resolution=resolution),
        "deep": dict(resolution=resolution),  # its default 4 layers
    }.get(method, {})
    return hj.Shadows(method, **options)


def central_difference(f, x: float, eps: float) -> float:
    return (f(x + eps) - f(x - eps)) / (2 * eps)


def unexplained_pixels(scene, gl_image, jax_image):
    """Pixels differing by > PIXEL_TOL outside the camera band (hairjax/_disagreement, where the
    tolerances and the bands are), and the band."""
    diff = np.abs(gl_image - jax_image).max(axis=-1).ravel()
    # Any fragment's colour and what lies behind it are ≤ the brightest pixel value, so a
    # toggled fragment changes a pixel by at most its weight times that.
    band = camera_band(scene, colour_bound=float(np.max(jax_image[..., :3])))
    return np.flatnonzero((diff > PIXEL_TOL) & ~band), band


def render_gl_with_edited_shader(scene, omega, old: str, new: str, occluder=None):
    """`render_gl(scene, omega=omega, occluder=occluder).image` with `old` replaced by `new` in model.glsl
    (which must contain it): a wrong shader, for tests that the cross-checks catch one."""
    return gl_with_edited_shader(scene, "model.glsl", old, new, omega=omega, occluder=occluder).image


def gl_with_edited_shader(scene, shader: str, old: str, new: str, **render):
    """`render_gl(scene, **render)` with `old` replaced by `new` in the shader file `shader`
    (which must contain it). The shader cache is cleared before and after, so later
    renders use the real shader."""
    import pytest

    from hairjax.gl import _programs, render_gl

    original = _programs.shader_source

    def edited(name):
        text = original(name)
        if name == shader:
            assert old in text
            text = text.replace(old, new)
        return text

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(_programs, "shader_source", edited)
        _programs.clear_cache()
        try:
            return render_gl(scene, **render)
        finally:
            patch.undo()
            _programs.clear_cache()


FRAGMENT_FIELDS = ("frag_pixel", "frag_i0", "frag_t", "frag_weight")


def real_fragments(geometry) -> dict[str, np.ndarray]:
    """A `Geometry`'s fragment arrays without their bucket's padding (docs/model.md §6:
    pixel H·W, weight 0, all after the real ones)."""
    pixel = np.asarray(geometry.frag_pixel)
    n = int(np.sum(pixel < geometry.height * geometry.width))
    assert np.all(pixel[n:] == geometry.height * geometry.width)  # the padding is the tail
    return {name: np.asarray(getattr(geometry, name))[:n] for name in FRAGMENT_FIELDS}
