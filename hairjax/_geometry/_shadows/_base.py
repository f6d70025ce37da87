"""The abstract shadow method and its registry (docs/model.md §7, docs/architecture.md).

A shadow method is a small immutable configuration (`[shadows]` in a scene file). It
plans Ω from the geometry alone (`setup`, NumPy, in the geometry stage's set-up) and
evaluates it from the strands' opacity (`omega`, JAX, differentiable in opacity). A new
method is one module with a subclass registered by `@register_shadow_method`; the GL
renderer finds its pass by the same name (hairjax/gl/).
"""

from __future__ import annotations

import abc
import dataclasses
from typing import Any, ClassVar

from jaxtyping import Array, Float

from ..._errors import SceneError
from ..._registry import Registry
from ._frame import ShadowInputs

__all__ = [
    "AbstractShadowMethod",
    "register_shadow_method",
    "shadow_method_class",
    "shadow_method_names",
    "Shadows",
    "check_resolution",
]


@dataclasses.dataclass(frozen=True)
class AbstractShadowMethod(abc.ABC):
    """Self-shadowing of the hair. Subclasses set `method` (the scene-file name) and
    `casts` (False only for no shadows: nothing is planned or evaluated), and implement
    `setup` and `omega`; their dataclass fields are the `[shadows]` keys besides
    `method`."""

    method: ClassVar[str]
    casts: ClassVar[bool] = True
    # Whether its light raster runs as an XLA program where the set-up is placed on the
    # device (`_device_raster`); the others rasterise on the host.
    rasterizes_on_device: ClassVar[bool] = False

    @abc.abstractmethod
    def setup(self, inputs: ShadowInputs) -> Any:
        """What Ω needs that does not depend on opacity (NumPy; the fragments may be JAX
        arrays on an accelerator, docs/model.md §5), for `inputs`' strand points and then
        its receivers (the occluder's surface points, §13); where `inputs.opacity` is
        given, what it needs for those opacities alone, if the method folds them in."""

    @abc.abstractmethod
    def omega(self, setup, alpha: Float[Array, " S"]) -> Float[Array, " PQ"]:
        """Ω at every point of `setup` for per-strand opacity `alpha` (JAX): the
        opacities the setup was planned for, where it was (`ShadowInputs.opacity`)."""

    def planned_maps(self) -> tuple[int, str]:
        """The map cells its Ω accumulates (JAX floats; 0 for a method without maps) and
        the scene keys that set their number, for the capacity estimate (docs/model.md §5)."""
        return 0, ""

    def point_lookups(self) -> int:
        """How many texels each point's plan names (1, or the 3 × 3 filter's 9 where the
        plan keeps one entry per texel): the per-point tables' width, for the capacity
        estimate."""
        return 1

    @property
    def resolution(self) -> int:
        """The light's raster, `resolution` × `resolution` texels, that a method which
        casts shadows plans Ω in (and the occluder's light view uses, §13): such a method
        has it as a field; one with `casts = False` has none."""
        raise AttributeError(f"shadows.method = {self.method!r} casts no shadows: it has no resolution")


SHADOW_METHODS: Registry[AbstractShadowMethod] = Registry("shadows", "method", "method")
register_shadow_method = SHADOW_METHODS.register
shadow_method_names = SHADOW_METHODS.names
shadow_method_class = SHADOW_METHODS.get


def Shadows(method: str = "opacity-maps", *args: Any, **options: Any) -> AbstractShadowMethod:  # noqa: N802 (a factory named like the type it makes)
    """The registered shadow method `method` with its options (its dataclass fields, in
    order or by name), e.g. `Shadows("opacity-maps", 64, 256)`,
    `Shadows("exact", resolution=128)`; `SceneError` for an unknown method or an option it
    does not take."""
    return SHADOW_METHODS.make(method, *args, **options)


def check_resolution(value) -> int:
    """The light's raster size: an integer in [4, 16384] (a 3×3 filter needs a few texels;
    16384² is GL's usual texture limit), or `SceneError`."""
    if isinstance(value, bool) or int(value) != value or not 4 <= value <= 16384:
        raise SceneError(f"shadows.resolution must be an integer in [4, 16384], got {value!r}")
    return int(value)
