"""Numerical stability of the whole render (the shared part and the stages:
tests/stability_helpers.py): compositing (hairjax/_composite.py) at the extremes of
opacity, and random scenes drawn over all the ranges the stages' cases test one at a time,
at once.

| case                            | test_…                                  | scene: own assertions          |
|---------------------------------|-----------------------------------------|--------------------------------|
| opacity 10⁻⁶ … 1                | opacity_extremes                        | mixed: alpha ≤ n·a; a = 1 → 1  |
| random scenes                   | random_scenes                           | hypothesis, all ranges at once |
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import shadow_method
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from stability_helpers import (
    BACKENDS,
    SIZE,
    Runner,
    assert_in_bounds,
    check,
    finite,
    precision,
    runner_scene,
)

import hairjax as hj

# --- compositing ---------------------------------------------------------------------------


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("alpha", [1e-6, 1.0])
def test_opacity_extremes(request, backend, alpha):
    """a = 10⁻⁶ everywhere (the hair all but vanishes) and a = 1 (T = 0 exactly behind a
    fully covered fragment: the product scan, not exp Σ log(1 − α))."""
    image, _ = check(backend, request, "mixed", alpha=alpha)
    n = len(runner_scene("mixed").strands.segments())
    if alpha == 1.0:
        # The wide ribbon covers whole pixels: opaque there, exactly.
        assert image[..., 3].max() == 1.0
    else:
        # 1 − Π(1 − a·coverage) ≤ n·a for a pixel's ≤ n fragments.
        assert 0 < image[..., 3].max() <= n * alpha


# --- random scenes -------------------------------------------------------------------------


@st.composite
def random_scenes(draw):
    """A small random scene within the ranges the stability cases test one at a time
    (tests/stability_helpers.py and each stage's table), as keyword arguments (the scene is
    built inside the drawn precision): fur ball, camera anywhere (inside the fur ball
    below distance ~1.2), directional or point light (possibly inside), opacity 1e-6 … 1,
    width 0.25 … 8, shininess 0.5 … 1e4, κ 0 … 1e3, all scaled by 1e-4, 1 or 1e4."""
    unit = st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1)
    return dict(
        dtype=draw(st.sampled_from(["float64", "float32"])),
        hair=dict(
            strands=draw(st.integers(1, 12)),
            points=draw(st.integers(2, 5)),
            seed=draw(st.integers(0, 2**16)),
            alpha=10.0 ** draw(st.floats(-6.0, 0.0)),
            # widths on a log grid: the rasteriser compiles once per ribbon reach
            width=draw(st.sampled_from([0.25, 0.5, 1.0, 2.0, 4.0, 8.0])),
        ),
        scale=10.0 ** draw(st.sampled_from([-4, 0, 4])),
        eye=np.asarray(draw(unit)),
        distance=draw(st.floats(0.3, 6.0)),
        fov=draw(st.floats(20.0, 120.0)),
        light=draw(
            st.one_of(
                st.tuples(st.just("directional"), unit),
                st.tuples(st.just("point"), st.tuples(*[st.floats(-1.5, 1.5)] * 3)),
            )
        ),
        shadows=draw(st.sampled_from(["none", "opacity-maps", "exact"])),
        maps=draw(st.integers(1, 6)),
        model=draw(st.sampled_from(["kajiya-kay", "kajiya-kay-mirror"])),
        params=dict(
            kd=draw(st.floats(0.0, 1.0)),
            ks=draw(st.floats(0.0, 1.0)),
            ambient=draw(st.floats(0.0, 1.0)),
            shininess=10.0 ** draw(st.floats(np.log10(0.5), 4.0)),
            kappa=draw(st.one_of(st.just(0.0), st.floats(-3.0, 3.0).map(lambda e: 10.0**e))),
        ),
    )


def build_random_scene(spec) -> hj.Scene:
    s = spec["scale"]
    eye = spec["eye"] / np.linalg.norm(spec["eye"]) * spec["distance"]
    up = (0.0, 1.0, 0.0) if abs(eye[1]) < 0.95 * np.linalg.norm(eye) else (1.0, 0.0, 0.0)
    kind, v = spec["light"]
    light = (
        hj.Light(direction=v)
        if kind == "directional"
        else hj.Light(kind="point", position=tuple(s * np.asarray(v)))
    )
    return hj.Scene(
        hj.furball(**spec["hair"]).transformed(s),
        camera=hj.Camera(
            eye=tuple(s * eye), target=(0.0, 0.0, 0.0), up=up, fov=spec["fov"], width=SIZE, height=SIZE
        ),
        light=light,
        shading=hj.extend.shading_model_class(spec["model"])(hj.ShadingParams(**spec["params"])),
        shadows=shadow_method(spec["shadows"], spec["maps"], SIZE),
    )


# Found by hypothesis: one strand 10⁻⁴ long, seen from 5·10⁻⁵ away through its own tip.
EMPTY_VIEW = {
    "dtype": "float64",
    "hair": {"strands": 1, "points": 2, "seed": 0, "alpha": 1.0, "width": 0.25},
    "scale": 0.0001,
    "eye": np.array([0.0, 0.0, 1.0]),
    "distance": 0.5,
    "fov": 20.0,
    "light": ("directional", (0.0, 0.0, 1.0)),
    "shadows": "none",
    "maps": 1,
    "model": "kajiya-kay",
    "params": {"kd": 0.0, "ks": 0.0, "ambient": 0.0, "shininess": 1.0, "kappa": 0.0},
}


# Each example compiles its own scene (~1 s): few examples, no deadline. A random camera
# may see no hair at all (one strand through the eye, say): the set-up then warns that the
# view is empty, and the image must still be finite, which is what this test checks.
@pytest.mark.filterwarnings("ignore::hairjax.EmptyViewWarning")
@given(spec=random_scenes())
@example(spec=EMPTY_VIEW)
@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_random_scenes(spec):
    """Random scenes: finite image and gradients (shading parameters and opacity), pixels
    within the model's maximum."""
    with precision(spec["dtype"]):
        scene = build_random_scene(spec)
        run = Runner(scene)
        res = run(scene.params)
    assert np.all(np.isfinite(res.image)) and res.image.dtype == np.dtype(spec["dtype"])
    assert finite((res.g_params, res.g_alpha)) and np.all(np.isfinite(res.colors))
    assert_in_bounds(res.image, scene, scene.params, np.dtype(spec["dtype"]))
