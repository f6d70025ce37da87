"""A fit's point beyond a model's own parameters: `ExtendedParams`, the model's parameters
(`shading`) and others (the light's, `_lit.py`; the strands' opacity, `_opacity_fit.py`)
as one point of the solver's space, read and replaced by name (`_space.value`,
`_space.with_values`)."""

from __future__ import annotations

import abc
from typing import Any

import equinox as eqx

__all__ = ["ExtendedParams"]


class ExtendedParams(eqx.Module):
    """A model's parameters (`shading`) and more, read and replaced by the fit's names."""

    shading: eqx.AbstractVar[Any]

    @abc.abstractmethod
    def get(self, name: str):
        """The value of the fit's name `name`."""

    @abc.abstractmethod
    def replace(self, values: dict) -> ExtendedParams:
        """These parameters with some replaced (`values`: name → array)."""
