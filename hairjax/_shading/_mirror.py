"""Kajiya-Kay with the mirror cone (docs/model.md §8): the highlight where the view lies
on the cone of mirror directions about the tangent, b = −cos(θ_L + θ_V), instead of the
seed's retro-reflection cone. Same parameters, terms and GL branch otherwise."""

from __future__ import annotations

from typing import ClassVar

from ._kajiya_kay import Cone, KajiyaKay
from ._model import register_shading_model

__all__ = ["KajiyaKayMirror", "mirror_cone"]


def mirror_cone(tl, tv, sin_tl, sin_tv):
    """(b, s) = (−cos(θ_L + θ_V), sin(θ_L + θ_V)) from cos θ = T·X, sin θ = ‖T × X‖."""
    return sin_tl * sin_tv - tl * tv, sin_tl * tv + tl * sin_tv


@register_shading_model
class KajiyaKayMirror(KajiyaKay):
    """`KajiyaKay` with the mirror cone (`mirror_cone`)."""

    name: ClassVar[str] = "kajiya-kay-mirror"
    gl_id: ClassVar[int | None] = 1
    cone: ClassVar[Cone] = staticmethod(mirror_cone)
