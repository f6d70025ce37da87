"""Small scenes and checks shared by the tests."""

from __future__ import annotations

from pathlib import Path

import hairjax as hj

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def small_furball_scene(strands=40, size=48, shadows="opacity-maps", maps=8, resolution=32,
                        alpha=0.6, **scene_kw) -> hj.Scene:
    hair = hj.furball(strands=strands, points=6, seed=3, alpha=alpha)
    return hj.Scene(
        strands=hair,
        camera=hj.Camera(eye=(0.0, 0.3, 3.5), target=(0.0, 0.0, 0.0), fov=45.0,
                         width=size, height=size),
        light=hj.Light(direction=(-0.5, -0.7, -0.4)),
        params=hj.ShadingParams(kd=(0.6, 0.4, 0.3), ks=0.4, shininess=20.0, kappa=0.8,
                                ambient=0.05),
        shadows=hj.Shadows(method=shadows, maps=maps, resolution=resolution),
        **scene_kw,
    )


def central_difference(f, x: float, eps: float) -> float:
    return (f(x + eps) - f(x - eps)) / (2 * eps)
