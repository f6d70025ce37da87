"""hairjax.fit's held-out views and lights (docs/fitting.md, "Held-out views and lights")."""

import dataclasses

import numpy as np
import pytest
from helpers import refused, small_furball_scene

import hairjax as hj

TRUE = hj.ShadingParams(kd=(0.3, 0.5, 0.2), ks=0.4, shininess=25.0, kappa=2.5, ambient=0.05)
INIT = hj.ShadingParams(kd=0.5, ks=0.2, shininess=10.0, kappa=1.0, ambient=0.05)


@pytest.fixture(scope="module")
def views():
    """The same hair from the front and from the side, the side under another light."""
    front = small_furball_scene(strands=120, size=32)
    side = dataclasses.replace(
        front,
        camera=dataclasses.replace(front.camera, eye=(3.0, 0.6, 1.8)),
        light=hj.Light(direction=(0.6, -0.7, -0.3)),
    )
    return front, side


def by_hand(scene, params, target):
    """The RMSE written out: the render's RGB against the target's, over every pixel."""
    image = np.asarray(hj.render(scene, params), np.float64)[..., :3]
    return np.sqrt(np.mean((image - np.asarray(target)[..., :3]) ** 2))


def test_held_out_rmse_is_the_rmse_of_the_fitted_params_on_the_held_out_view(views):
    front, side = views
    target = np.asarray(hj.render(front, TRUE))
    # The held-out view was rendered with another Kd: the fitted parameters cannot follow it.
    other = dataclasses.replace(TRUE, kd=np.asarray([0.5, 0.3, 0.2]))
    held = [np.asarray(hj.render(side, TRUE)), np.asarray(hj.render(side, other))]
    r = hj.fit(front, hj.FitTargets(target, holdout=(side, held)), init=INIT, stop=hj.FitStop(max_steps=200))
    assert r.termination == "converged"
    # Pooled over the two held-out targets, each over all its pixels.
    expected = np.sqrt((by_hand(side, r.params, held[0]) ** 2 + by_hand(side, r.params, held[1]) ** 2) / 2)
    # Two evaluations of one sum in float64: agreement to rounding.
    np.testing.assert_allclose(r.holdout_rmse, expected, rtol=1e-9)
    # The second target is off by ΔKd = 0.2 in two channels: far above the fit's residual.
    assert r.holdout_rmse > 100 * r.rmse
    assert r.to_json()["holdout_rmse"] == r.holdout_rmse


def test_noise_free_fit_holds_on_a_view_and_light_it_did_not_see(views):
    """Parameters recovered from one view (within the recovery bound, 1e-3 relative)
    render the other view and light as the truth does: the held-out RMSE is as small as
    the training one, relative to the image."""
    front, side = views
    target_side = np.asarray(hj.render(side, TRUE))
    target = np.asarray(hj.render(front, TRUE))
    r = hj.fit(
        front, hj.FitTargets(target, holdout=(side, target_side)), init=INIT, stop=hj.FitStop(max_steps=200)
    )
    assert r.termination == "converged"
    # 1e-3 relative parameters move the image by about 1e-3 of its RMS brightness.
    assert r.holdout_rmse < 1e-3 * np.sqrt(np.mean(target_side[..., :3] ** 2))
    assert hj.fit(front, target, init=INIT, stop=hj.FitStop(max_steps=1)).holdout_rmse is None


def test_held_out_targets_are_checked_before_the_fit(views):
    front, side = views
    target = np.zeros((32, 32, 4))
    calls = []

    def progress(*args):
        calls.append(args)

    with pytest.raises(hj.FitError, match="target is 16x16 but scene"):
        hj.fit(front, hj.FitTargets(target, holdout=(side, np.zeros((16, 16, 3)))), progress=progress)
    with pytest.raises(hj.FitError, match="holdout: 2 scenes for 3 targets"):
        hj.fit(front, hj.FitTargets(target, holdout=([side, side], [target] * 3)), progress=progress)
    with refused("holdout", r"holdout must be a \(scene or scenes, target or targets\) pair", hj.FitError):
        hj.fit(front, hj.FitTargets(target, holdout=side), progress=progress)
    # A fit of the light renders held-out views at the fitted light: not under another light.
    with pytest.raises(hj.FitError, match="hold out a light with the light held"):
        hj.fit(
            front,
            hj.FitTargets(target, holdout=(side, target)),
            variables=("kd", "light_color"),
            progress=progress,
        )
    assert calls == []
