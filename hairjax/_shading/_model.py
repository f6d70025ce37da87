"""The abstract shading model and its registry (docs/architecture.md, docs/model.md §8).

A shading model is an immutable `eqx.Module` holding its differentiable parameters
(`params`, a small pytree of arrays) and its static configuration (a table size, how
per-point inputs are made). It owns everything that differs between models:

- `point_inputs`: the per-point inputs it needs from the set-up, in NumPy, from the
  geometry alone (Scheuermann's strand normals and textures; none for Kajiya-Kay);
- `reflectance`: its unshadowed colour per point, as a sum of terms each linear in one
  RGB gain (`Reflectance`): the shading stage applies light, shadow and streaks to the
  lit terms (`hairjax/_shading/_stage.py`) and the fit solves for the gains
  (`hairjax/_fit/`), so neither transcribes the model a second time;
- what the fit and `hj.explore` need to know of its parameters (docs/fitting.md, "What a
  model declares"): `searched`, the parameters the colour is not linear in, with the
  transforms the fit searches them through (a scalar or an RGB `[3]` value, three solver
  coordinates); `plateaus`, where a fit may stall with a parameter without effect, and the
  values it scans there (`Plateau`); `ranges`, each parameter's sensible range (the
  slider's); `grey`, the gains fitted as one grey value unless the caller says otherwise;
- its GL side: `gl_id` (the shader's branch), `gl_uniforms`, `gl_table`, `gl_attributes`;
- its scene-file table: `table_keys` and `from_table`, and back: `table`.

A subclass is registered under its `name` with `@register_shading_model`; the scene
reader, `fit` and the renderers find it there, so a new model is one module plus that
line (docs/architecture.md shows a toy model).
"""

from __future__ import annotations

import abc
import dataclasses
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._errors import SceneError
from .._registry import Registry
from ._transforms import Transform

if TYPE_CHECKING:  # types only: the scene reader imports the registry, not the reverse
    from .._scene._file import Table

__all__ = [
    "rgb_param",
    "scalar_param",
    "rgb_uniform",
    "AbstractShadingModel",
    "Plateau",
    "PointInputs",
    "ShadingPoints",
    "Reflectance",
    "Transform",
    "register_shading_model",
    "shading_model_class",
    "shading_model_names",
    "check_params",
    "RGBLike",
    "param_values",
    "values_repr",
]

# What a parameter class takes for an RGB gain: an array or one number (it broadcasts), or
# a tuple or list of 3 numbers (`ShadingParams(kd=(0.3, 0.5, 0.2))`); it stores `[3]`.
RGBLike = ArrayLike | Sequence[ArrayLike]


def rgb_param(x) -> Float[Array, " 3"]:
    """A parameter's RGB value as the working dtype (a scalar broadcasts to grey)."""
    return jnp.broadcast_to(jnp.asarray(x, dtype=jnp.result_type(float)), (3,))


def scalar_param(x) -> Float[Array, ""]:
    """A parameter's scalar value as the working dtype."""
    return jnp.asarray(x, dtype=jnp.result_type(float))


def rgb_uniform(v) -> tuple:
    """An RGB value as the three Python floats a GL vec3 uniform takes."""
    return tuple(float(x) for x in np.broadcast_to(np.asarray(v, dtype=np.float64), (3,)))


@dataclasses.dataclass(frozen=True)
class Plateau:
    """A stationary set a fit cannot leave by stepping (docs/fitting.md, "When a fit has
    converged"), as a model declares it: where `parameter` has no effect, every value of it
    is stationary. `scan`: the values of `parameter`, in its own units (a shininess, not its
    log), that the fit tries there, restarting from the best; `gain`: the gain that, solved
    to 0, leaves `parameter` without effect (the scan is tried only where that gain is
    solved for, so that each value tried gets its own gain), or None for a parameter that
    can lose its effect on its own (a lobe shifted off every strand)."""

    parameter: str
    scan: tuple[float, ...]
    gain: str | None = None


class PointInputs(eqx.Module):
    """A model's per-point inputs from the set-up (NumPy, geometry only).

    **Fields:** `extra`: a pytree of `[P, …]` arrays the model's `reflectance` reads
    (None: none); `color_factor`: `[P, 3]` multiplying the strands' colour (None: 1);
    `segment_alpha`: `[E]` multiplying each segment's opacity, in the camera and the
    light's views alike (None: 1)."""

    extra: Any = None
    color_factor: np.ndarray | None = None
    segment_alpha: np.ndarray | None = None


class ShadingPoints(eqx.Module):
    """What every model reads at the strand points (JAX arrays, geometry only): unit
    tangent T, unit to-light L and to-eye V (0 where undefined, docs/model.md §1), the
    per-point colour c (the strands' colour times the model's `color_factor`), the
    model's own `extra` inputs (`PointInputs.extra`, as JAX arrays) and Ω, the opacity in
    front of each point toward the light (§7; None where the scene has no shadows), which
    a model that scatters light between fibres reads (§19)."""

    tangent: Float[Array, "P 3"]
    to_light: Float[Array, "P 3"]
    to_eye: Float[Array, "P 3"]
    base_color: Float[Array, "P 3"]
    extra: Any = None
    omega: Float[Array, " P"] | None = None


class Reflectance(eqx.Module):
    """A model's unshadowed colour at the points, split by gain: the colour is

        Σ_g  params.g ⊙ ambient[g]  +  shade(Σ_g params.g ⊙ lit[g])

    where `shade` multiplies by the light's colour, τ = exp(−κΩ) (§7), the occluder's
    visibility V (§13) — and the streak factor (§16) multiplies the whole. `scattered`
    (empty but for light scattered between fibres, §19) adds Σ_g params.g ⊙ scattered[g]
    lit by the light's colour and V but not τ: light that reached the point through the
    hair in front, which τ counts as blocked. Each term is `[P, 3]` and holds no gain
    itself, so the image is linear in every gain (docs/fitting.md: variable projection)."""

    ambient: dict[str, Float[Array, "P 3"]]
    lit: dict[str, Float[Array, "P 3"]]
    scattered: dict[str, Float[Array, "P 3"]] = eqx.field(default_factory=dict)


def check_params(
    params: eqx.Module,
    *,
    colors: tuple[str, ...] = (),
    positive: tuple[str, ...] = (),
    non_negative: tuple[str, ...] = (),
    finite: tuple[str, ...] = (),
) -> None:
    """Raise `SceneError` naming `shading.<field>` unless the parameters' concrete values
    are in range: `colors` finite and ≥ 0 (RGB), `positive` finite and > 0, `non_negative`
    finite and ≥ 0, `finite` finite. Traced parameters (inside `jax.grad`, `jit`, a fit's
    step) have no values yet and pass: the check is for values a user gives."""
    if any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(params)):
        return
    for names, ok, text in (
        (colors, lambda v: v >= 0, ">= 0"),
        (positive, lambda v: v > 0, "> 0"),
        (non_negative, lambda v: v >= 0, ">= 0"),
        (finite, lambda v: True, "finite"),
    ):
        for name in names:
            v = np.asarray(getattr(params, name), dtype=np.float64)
            if not (np.all(np.isfinite(v)) and np.all(ok(v))):
                shown = "[" + ", ".join(f"{x:g}" for x in v) + "]" if v.ndim else f"{float(v):g}"
                raise SceneError(f"shading.{name} must be {text}, got {shown}")


def param_values(params: eqx.Module) -> dict[str, Any]:
    """Each field of a parameter pytree that holds a value, as TOML data: a float, or a
    list of floats (an RGB gain), each the shortest decimal that reads back to the same
    value in the array's own precision (0.55, not float32's 0.550000011920929)."""
    out: dict[str, Any] = {}
    for field in dataclasses.fields(params):
        value = getattr(params, field.name)
        if value is not None:
            array = np.asarray(value)
            # str of a NumPy scalar is its shortest round-tripping decimal, in its dtype.
            numbers = [float(str(x)) for x in array.ravel()]
            out[field.name] = numbers if array.ndim else numbers[0]
    return out


def values_repr(params: eqx.Module) -> str:
    """`Name(kd=[0.6, 0.6, 0.6], shininess=40, …)`: a parameter pytree's values (6
    significant digits), where equinox's repr shows shapes only; traced values (inside
    `jax.jit` or `jax.grad`) as equinox shows them."""
    leaves = jax.tree_util.tree_leaves(params)
    if any(isinstance(x, jax.core.Tracer) for x in leaves):
        return eqx.tree_pformat(params)

    def show(value) -> str:
        if value is None:
            return "None"
        array = np.asarray(value, dtype=np.float64)
        if array.ndim == 0:
            return f"{float(array):.6g}"
        return "[" + ", ".join(f"{x:.6g}" for x in array.ravel()) + "]"

    fields = ", ".join(f"{f.name}={show(getattr(params, f.name))}" for f in dataclasses.fields(params))
    return f"{type(params).__name__}({fields})"


class AbstractShadingModel(eqx.Module):
    """A shading model: differentiable `params` and static configuration (module
    docstring). Subclasses set the class variables and implement `reflectance`."""

    params: eqx.AbstractVar[Any]

    # The name in scene files (`[shading] model = …`) and the registry.
    name: ClassVar[str]
    # The type of `params`, and the [shading] keys this model reads besides `model`.
    params_type: ClassVar[type[Any]]
    table_keys: ClassVar[tuple[str, ...]]
    # The parameters `fit` fits by default, and those among them that are RGB gains the
    # colour is linear in; `searched` maps each other fittable parameter to the transform
    # the solver searches it through (a scalar, or an RGB `[3]` value: one solver
    # coordinate per channel). `ambient` is a gain that is held unless named.
    fittable: ClassVar[tuple[str, ...]]
    searched: ClassVar[Mapping[str, Transform]]
    # Where a fit may stall with a parameter without effect, and what it scans there.
    plateaus: ClassVar[tuple[Plateau, ...]] = ()
    # A parameter's sensible range (low, high) in its own units: `hj.explore`'s slider
    # (logarithmic where `searched` names LOG); a parameter without one gets the slider
    # its validity check implies (`hairjax/_explore.py`, `slider_range`).
    ranges: ClassVar[Mapping[str, tuple[float, float]]] = {}
    # Gains `fit` fits as one grey value unless its `scalar=` names the grey ones itself
    # (docs/fitting.md, "What a model declares").
    grey: ClassVar[tuple[str, ...]] = ()
    # The camera shader's branch for this model (hairjax/gl/shaders/strand.vert), or None
    # where the model has no GL side (the GL renderer then refuses the scene).
    gl_id: ClassVar[int | None] = None

    def point_inputs(self, strands, tangent: np.ndarray) -> PointInputs:
        """The per-point inputs from the geometry (NumPy); none by default."""
        return PointInputs()

    @abc.abstractmethod
    def reflectance(self, points: ShadingPoints, params) -> Reflectance:
        """The unshadowed colour at all points, by gain (`Reflectance`). Batched over
        points (`[P, 3]` terms); differentiable in `params`."""

    def replace_params(self, params) -> AbstractShadingModel:
        """This model with other parameters (of `params_type`)."""
        if not isinstance(params, self.params_type):
            raise TypeError(
                f"shading model {self.name!r} takes {self.params_type.__name__}, got {type(params).__name__}"
            )
        return eqx.tree_at(lambda m: m.params, self, params)

    @property
    def gains(self) -> tuple[str, ...]:
        """The RGB gains the colour is linear in (every name `reflectance` returns)."""
        return tuple(n for n in self.fittable + ("ambient",) if n not in self.searched)

    # ------------------------------------------------------------------ GL side
    def gl_uniforms(self, params) -> dict[str, Any]:
        """Uniforms of the camera shader for this model (names as strand.vert has them)."""
        raise NotImplementedError(f"shading model {self.name!r} has no GL renderer")

    def gl_unsupported(self) -> str | None:
        """Why the GL renderer cannot draw this model as configured, or None where it can
        (by default: where the class has a shader branch, `gl_id`)."""
        return None if self.gl_id is not None else f"shading model {self.name!r} has no GL renderer"

    def gl_table(self, params) -> np.ndarray | None:
        """A `[rows, columns, c]` table (c ≤ 4 components) the shader reads as its model's
        sampler (`kajiya_kay_table`, `marschner_tables`, hairjax/gl/_shading.py), or None."""
        return None

    def gl_attributes(self, inputs: PointInputs) -> list[tuple[np.ndarray, str, str]]:
        """Extra per-vertex attributes `(array, format, name)` from `point_inputs`."""
        return []

    # ------------------------------------------------------------------ scene file
    @classmethod
    @abc.abstractmethod
    def from_table(cls, table: Table) -> AbstractShadingModel:
        """The model from a scene file's [shading] table (`Table` getters check types;
        the parameters' own checks give the ranges)."""

    def table(self) -> dict[str, Any]:
        """The [shading] table `from_table` reads back to this model: `model` and the
        parameters' values; a model with static configuration adds its keys."""
        return {"model": self.name, **param_values(self.params)}


SHADING_MODELS: Registry[AbstractShadingModel] = Registry("shading", "model", "name")
# Class decorator: make a model available under its `name` to scene files, `fit` and the
# renderers (a name registered twice is the later class's).
register_shading_model = SHADING_MODELS.register
shading_model_names = SHADING_MODELS.names
shading_model_class = SHADING_MODELS.get
