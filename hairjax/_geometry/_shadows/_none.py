"""`method = "none"`: no self-shadowing; nothing is planned or evaluated (docs/model.md §7)."""

from __future__ import annotations

import dataclasses

from ._base import AbstractShadowMethod, register_shadow_method
from ._frame import ShadowInputs

__all__ = ["NoShadows"]


@register_shadow_method
@dataclasses.dataclass(frozen=True)
class NoShadows(AbstractShadowMethod):
    """τ = 1 everywhere: the scene builds no shadow work."""

    method = "none"
    casts = False

    def setup(self, inputs: ShadowInputs):
        return None

    def omega(self, setup, alpha):
        raise TypeError("a scene without shadows has no Ω")
