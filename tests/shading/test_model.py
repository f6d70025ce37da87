"""A shading model defined here, in the test, and used through registration alone
(docs/architecture.md, "Adding a shading model"): rendered, fitted, read from TOML, and
refused clearly where it has no side (GL)."""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import small_furball_scene
from jaxtyping import Array, ArrayLike, Float

import hairjax as hj
from hairjax._shading import _model


class ToyParams(eqx.Module):
    """Kd, ambient (RGB), a fall-off exponent `power` and κ."""

    kd: Float[Array, " 3"]
    ambient: Float[Array, " 3"]
    power: Float[Array, ""]
    kappa: Float[Array, ""]

    def __init__(
        self, kd: ArrayLike = 0.5, ambient: ArrayLike = 0.05, power: ArrayLike = 2.0, kappa: ArrayLike = 1.0
    ):
        self.kd = jnp.broadcast_to(jnp.asarray(kd, dtype=float), (3,))
        self.ambient = jnp.broadcast_to(jnp.asarray(ambient, dtype=float), (3,))
        self.power = jnp.asarray(power, dtype=float)
        self.kappa = jnp.asarray(kappa, dtype=float)

    def __check_init__(self):
        hj.extend.check_params(self, colors=("kd", "ambient"), positive=("power",), non_negative=("kappa",))


class Toy(hj.extend.AbstractShadingModel):
    """colour = ambient·c + τ·light·Kd·c·exp(−power·(T·L)²): brightest across the light."""

    params: ToyParams = eqx.field(default_factory=ToyParams)

    name: ClassVar[str] = "toy-test"
    params_type: ClassVar[type] = ToyParams
    table_keys: ClassVar[tuple[str, ...]] = ("kd", "ambient", "power", "kappa")
    fittable: ClassVar[tuple[str, ...]] = ("kd", "power", "kappa")
    searched: ClassVar[dict] = {"power": hj.extend.LOG, "kappa": hj.extend.LOG}
    ranges: ClassVar[dict] = {"power": (0.1, 100.0)}

    def reflectance(self, points, params):
        cos = jnp.sum(points.tangent * points.to_light, axis=1)
        fall_off = jnp.exp(-params.power * cos * cos)
        return hj.extend.Reflectance(
            ambient={"ambient": points.base_color}, lit={"kd": fall_off[:, None] * points.base_color}
        )

    @classmethod
    def from_table(cls, table):
        return cls(
            ToyParams(
                **table.given(
                    kd=table.rgb("kd", scalar=True),
                    ambient=table.rgb("ambient", scalar=True),
                    power=table.number("power"),
                    kappa=table.number("kappa"),
                )
            )
        )


@pytest.fixture
def toy(monkeypatch):
    """The toy model registered for one test only (the registry restored afterwards)."""
    monkeypatch.setattr(_model.SHADING_MODELS, "classes", dict(_model.SHADING_MODELS.classes))
    hj.extend.register_shading_model(Toy)
    return Toy


TRUE = ToyParams(kd=(0.6, 0.4, 0.3), ambient=0.05, power=3.0, kappa=1.5)


def toy_scene(params=TRUE):
    return small_furball_scene(strands=120, size=40).replace(shading=Toy(params))


def test_renders_through_both_stages(toy):
    scene = toy_scene()
    image = np.asarray(hj.render(scene))
    assert image[..., 3].max() > 0.5 and image[..., :3].max() > 0.05
    other = np.asarray(hj.render(scene, ToyParams(kd=(0.6, 0.4, 0.3), ambient=0.05, power=0.2, kappa=1.5)))
    assert np.abs(other - image).max() > 1e-2  # the exponent reaches the image
    np.testing.assert_array_equal(image, np.asarray(hj.shading_stage(hj.geometry_stage(scene), scene.params)))


def test_is_fitted_through_its_own_terms(toy):
    scene = toy_scene()
    target = np.asarray(hj.render(scene))
    start = ToyParams(kd=0.3, ambient=0.05, power=1.0, kappa=0.5)
    result = hj.fit(scene, target, init=start)
    assert result.termination == "converged"
    for name in ("kd", "power", "kappa"):
        # float64, noise-free, every pixel: the optimum is the truth to the solver's rtol.
        np.testing.assert_allclose(getattr(result.params, name), getattr(TRUE, name), rtol=1e-5)
    with pytest.raises(hj.FitError, match="unknown parameter 'ks' for a toy-test scene"):
        hj.fit(scene, target, variables=("ks",))


def test_is_read_from_a_scene_file(toy, tmp_path):
    path = tmp_path / "toy.toml"
    path.write_text(
        '[hair]\nsource = "furball"\nstrands = 20\n[shading]\nmodel = "toy-test"\nkd = 0.25\npower = 4\n'
    )
    scene = hj.load_scene(path)
    assert isinstance(scene.shading, Toy)
    np.testing.assert_allclose(scene.params.kd, 0.25)
    assert float(scene.params.power) == 4.0
    path.write_text('[hair]\nsource = "furball"\nstrands = 20\n[shading]\nmodel = "toy-test"\npower = -1\n')
    with pytest.raises(hj.SceneError, match=r"toy\.toml: shading\.power must be > 0, got -1"):
        hj.load_scene(path)
    path.write_text(
        '[hair]\nsource = "furball"\nstrands = 20\n[shading]\nmodel = "toy-test"\nshininess = 4\n'
    )
    with pytest.raises(hj.SceneError, match=r"shading\.shininess is not a key of model = 'toy-test'"):
        hj.load_scene(path)


def test_gl_refuses_a_model_without_a_gl_side(toy, gl):
    from hairjax.gl import render_gl

    with pytest.raises(TypeError, match="shading model 'toy-test' has no GL renderer"):
        render_gl(toy_scene())


def test_unregistered_it_is_unknown(tmp_path):
    path = tmp_path / "toy.toml"
    path.write_text('[hair]\nsource = "furball"\nstrands = 20\n[shading]\nmodel = "toy-test"\n')
    with pytest.raises(hj.SceneError, match="shading.model must be one of"):
        hj.load_scene(path)


def test_its_declared_range_sets_the_slider(toy):
    """`ranges` gives `hj.explore`'s slider: log where `searched` says LOG, widened to hold
    the value; a parameter without one keeps the slider its check implies."""
    from hairjax._explore import slider_range

    assert slider_range(TRUE, "power", Toy) == ("log", -1.0, 2.0)  # 0.1 … 100
    far = ToyParams(kd=0.5, power=1e3)
    assert slider_range(far, "power", Toy(far)) == ("log", -1.0, 3.0)  # widened to 1000
    # κ declares none: [0, max(1, 2κ)] from its check (κ ≥ 0), as without a model.
    assert slider_range(TRUE, "kappa", Toy) == slider_range(TRUE, "kappa") == ("linear", 0.0, 3.0)
