"""GL's deep opacity maps against JAX's (docs/model.md §7, §11; Yuksel & Keyser 2008),
point by point and pixel by pixel, with the disagreement band of hairjax/_disagreement
(`_deep.py`: fragments near a segment end or a layer boundary, unsure first depths z₀,
points near the last boundary)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import MAX_BAND, PIXEL_TOL, gl_with_edited_shader, unexplained_pixels

import hairjax as hj
from hairjax._disagreement import omega_uncertainty
from hairjax._geometry._shadows import ShadowInputs, light_fragments

SPHERE = hj.Occluder(center=(0.0, 0.0, 0.0), radius=0.3, color=(0.8, 0.6, 0.5))


def ball(occluder=None, layers=4, spacing=0.0, lookup="layer") -> hj.Scene:
    """300 strands from one root at 48² (tests/disagreement/test_band.py's Ω scene: dense
    enough that GL's float32 puts some fragments on the other side of a boundary)."""
    return hj.Scene(
        hj.furball(300, 8, seed=1, alpha=0.5),
        camera=hj.Camera(eye=(0, 0.3, 3.5), width=48, height=48),
        light=hj.Light(direction=(-0.5, -0.7, -0.4)),
        shading=hj.KajiyaKay(
            hj.ShadingParams(kd=(0.6, 0.4, 0.3), ks=0.4, shininess=20.0, kappa=2.0, ambient=0.05)
        ),
        shadows=hj.Shadows("deep", layers, 64, spacing, lookup=lookup),
        occluder=occluder,
    )


def rounding_bound(scene, omega):
    """How far float32 alone moves Ω (no boundary crossed), per strand point: 1e-5·(1 + Ω)
    for the sums (Ω ≲ 10² from ~10² fragments: ~1e-6 relative, as test_band.py), plus the
    interpolation weight's: f comes from u = (z − z₀)·K/(KΔ), z and z₀ each within 16
    float32 ulps of the largest light depth (the band's depth delta, hairjax/_disagreement/_deep.py;
    measured ≤ 5.2 ulps of u on the fur balls), times |Ω̄_{k+1} − Ω̄_k| ≤ Ω̄_total, the
    3 × 3 average of the texels' summed alpha (by hand here from the light's fragments)."""
    s, r = scene.strands, scene.shadows.resolution
    segs = s.segments()
    lf = light_fragments(ShadowInputs(s.points, segs, s.strand_of_point[segs[:, 0]], s.width, scene.light), r)
    total = np.bincount(lf.frags.pixel, s.alpha[lf.frag_strand] * lf.frag_coverage, r * r).reshape(r, r)
    padded = np.pad(total, 1)
    box = sum(padded[i : i + r, j : j + r] for i in range(3) for j in range(3)) / 9
    n = s.num_points
    tx, ty = np.clip(lf.tx[:n], 0, r - 1), np.clip(lf.ty[:n], 0, r - 1)
    ulp = float(np.spacing(np.float32(np.abs(lf.frame.depth[lf.frame.seen]).max())))
    du = 2 * 16 * ulp * scene.shadows.layers / scene.shadows.depth_range(lf.frame)
    return 1e-5 * (1 + omega) + du * np.where(lf.inside[:n], box[ty, tx], 0.0)


@pytest.mark.parametrize("lookup", ["layer", "depth"])
@pytest.mark.parametrize("occluder", [None, SPHERE], ids=["ball", "sphere"])
def test_gl_matches_jax_outside_the_band(gl, occluder, lookup):
    from hairjax.gl import occluder_light, render_gl

    scene = ball(occluder, lookup=lookup)
    geometry = hj.geometry_stage(scene)
    jax_image = np.asarray(hj.shading_stage(geometry, scene.params))
    omega = np.asarray(geometry.omega)
    result = render_gl(scene)
    # Ω point by point: GL's own within the band's bound and float32 rounding.
    slack = np.abs(result.omega - omega) - omega_uncertainty(scene)
    assert np.all(slack <= rounding_bound(scene, omega))
    # Pixels: every difference > PIXEL_TOL lies in the band (at most 0.1 % may not).
    band = hj.experimental.renderer_band(scene, colour_bound=float(jax_image[..., :3].max()))
    differs = np.abs(result.image - jax_image).max(axis=-1) > PIXEL_TOL
    assert np.mean(differs & ~band) <= MAX_BAND
    # The camera pass with JAX's Ω (and occluder light): only the camera band differs.
    same_omega = render_gl(scene, omega=omega, occluder=occluder_light(scene, geometry)).image
    bad, camera = unexplained_pixels(scene, same_omega, jax_image)
    assert bad.size == 0 and camera.mean() <= MAX_BAND
    assert np.abs(result.omega).max() > 1.0  # the scene does shadow


@pytest.mark.parametrize("lookup", ["layer", "depth"])
def test_more_layer_passes_and_a_set_spacing(gl, lookup):
    """K = 9: three passes of four boundaries (the total in the third); Δ = 0.05, so much
    of the hair lies beyond the last boundary. With lookup "depth" a point's nine texels
    fall in different passes, each adding its share."""
    from hairjax.gl import render_gl

    scene = ball(layers=9, spacing=0.05, lookup=lookup)
    omega = np.asarray(hj.geometry_stage(scene).omega)
    slack = np.abs(render_gl(scene).omega - omega) - omega_uncertainty(scene)
    assert np.all(slack <= rounding_bound(scene, omega))


@pytest.mark.parametrize("lookup", ["layer", "depth"])
def test_a_wrong_layer_coordinate_fails_the_check(gl, lookup):
    """Layers 1 % thinner in GLSL than in JAX: Ω differs where no boundary explains it."""
    from hairjax.gl import render_gl

    scene = ball(lookup=lookup)
    omega = np.asarray(hj.geometry_stage(scene).omega)
    old = "return (z - z0) * float(layers) / depth_range;"
    wrong = gl_with_edited_shader(
        scene, "model.glsl", old, old.replace("/ depth_range", "/ (0.99 * depth_range)")
    ).omega
    slack = np.abs(wrong - omega) - omega_uncertainty(scene)
    assert np.sum(slack > rounding_bound(scene, omega)) > 20
    # And the real shader is back afterwards.
    slack = np.abs(render_gl(scene).omega - omega) - omega_uncertainty(scene)
    assert np.all(slack <= rounding_bound(scene, omega))


def test_the_light_passes_draw_the_hosts_projection(gl, monkeypatch):
    """The light passes read each point's place in the light's raster from the host's
    float64 projection (`Strands.screen_buffer`, docs/model.md §7), as the JAX raster
    does: GL's Ω is then closer to JAX's than with its own float32 projection, and a
    buffer moved by two texels moves it."""
    from hairjax.gl import _buffers, _uniforms, render_gl

    scene = ball()
    omega = np.asarray(hj.geometry_stage(scene).omega)
    given = np.abs(render_gl(scene).omega - omega)
    original = _uniforms.light_pass_uniforms
    monkeypatch.setattr(  # the shader's own projection, as before the host's was given
        _uniforms, "light_pass_uniforms", lambda *a: {**original(*a), "given_screen": False}
    )
    for module in ("_deep_maps", "_opacity_maps", "_exact_opacity"):
        monkeypatch.setattr(f"hairjax.gl.{module}.light_pass_uniforms", _uniforms.light_pass_uniforms)
    projected = np.abs(render_gl(scene).omega - omega)
    assert given.sum() < projected.sum() and given.max() <= projected.max()
    monkeypatch.undo()
    screen_buffer = _buffers.Strands.screen_buffer

    def moved(self, frame):
        return screen_buffer(self, frame.__class__(**{**frame.__dict__, "xy": frame.xy + 2.0}))

    monkeypatch.setattr(_buffers.Strands, "screen_buffer", moved)
    assert np.abs(render_gl(scene).omega - omega).max() > 10 * given.max()
