"""Several targets of one fit as one batch (hairjax/_fit/_batch.py; docs/fitting.md,
"Several views and lights")."""

import dataclasses

import jax
import numpy as np
import pytest
from helpers import real_fragments, small_furball_scene

import hairjax as hj
from hairjax._fit import _batch, _problem, _shading_fit

TRUE = hj.ShadingParams(kd=(0.3, 0.5, 0.2), ks=0.4, shininess=25.0, kappa=2.5, ambient=0.05)
INIT = hj.ShadingParams(kd=0.5, ks=0.2, shininess=10.0, kappa=1.0, ambient=0.05)
NAMES = ("kd", "ks", "shininess", "kappa")


@pytest.fixture(scope="module")
def views():
    base = small_furball_scene(strands=100, size=24)
    eyes = [(0.0, 0.3, 3.5), (3.0, 0.6, 1.8), (-2.5, 1.0, 2.5)]
    scenes = [dataclasses.replace(base, camera=dataclasses.replace(base.camera, eye=e)) for e in eyes]
    return scenes, [np.asarray(hj.render(s, TRUE)) for s in scenes]


def prepared(scenes, targets):
    model = _shading_fit.fit_model(hj.KajiyaKay)
    arrays = [_problem.target_arrays(s, t, None, None) for s, t in zip(scenes, targets)]
    return model, [model.prepare(s, INIT, NAMES, t, w) for s, (t, w) in zip(scenes, arrays)]


def test_the_batch_gives_each_target_s_image_and_residuals(views):
    """The views' fragment counts differ; padded and stacked, each view's image is its own."""
    model, data = prepared(*views)
    assert len({real_fragments(d.geometry)["frag_pixel"].size for d in data}) == 3
    (stacked,) = _batch.batched(data)
    batch = _batch.batched_model(model)
    expected = np.concatenate([model.image(d, TRUE) for d in data])
    # Padded fragments add exact zeros: the same sums, to float64 rounding.
    np.testing.assert_allclose(batch.image(stacked, TRUE), expected, rtol=0, atol=1e-13)
    fixed, images = batch.gain_images(stacked, TRUE)
    parts = [model.gain_images(d, TRUE) for d in data]
    np.testing.assert_allclose(fixed, np.concatenate([p[0] for p in parts]), atol=1e-13)
    assert [n for n, _ in images] == [n for n, _ in parts[0][1]]
    for k, (_, image) in enumerate(images):
        np.testing.assert_allclose(image, np.concatenate([p[1][k][1] for p in parts]), atol=1e-13)
    np.testing.assert_allclose(
        _problem.residuals_at(batch, INIT, [stacked]), _problem.residuals_at(model, INIT, data), atol=1e-13
    )


def test_the_step_does_not_grow_with_the_number_of_targets(views):
    """Under vmap the residuals' program is one copy of the model's, for 2 targets or 3."""

    def equations(n):
        model, data = prepared(views[0][:n], views[1][:n])
        batch, stacked = _batch.batched_model(model), _batch.batched(data)
        return len(jax.make_jaxpr(lambda p: _problem.residuals_at(batch, p, stacked))(INIT).eqns)

    assert equations(2) == equations(3)


def test_targets_that_do_not_stack_stay_a_list(views):
    scenes, targets = views
    small = small_furball_scene(strands=100, size=16)
    _, data = prepared([scenes[0], small], [targets[0], np.asarray(hj.render(small, TRUE))])
    assert _batch.batched(data) is data  # 24² and 16²: different image sizes
