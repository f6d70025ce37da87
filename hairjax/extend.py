"""hairjax.extend: what a new shading model, shadow method or ordering is written against
(docs/architecture.md, "Adding a shading model", "Adding a shadow method", "Adding an
ordering"): the abstract classes, their registries, the records a model reads and
returns, the parameter checks and transforms, and the geometry stage's output.
"""

from ._geometry._ordering import AbstractOrdering as AbstractOrdering
from ._geometry._ordering import register_ordering as register_ordering
from ._geometry._shadows import AbstractShadowMethod as AbstractShadowMethod
from ._geometry._shadows import register_shadow_method as register_shadow_method
from ._geometry_stage._stage import Geometry as Geometry
from ._shading import AbstractShadingModel as AbstractShadingModel
from ._shading import PointInputs as PointInputs
from ._shading import Reflectance as Reflectance
from ._shading import ShadingPoints as ShadingPoints
from ._shading import kajiya_kay as kajiya_kay
from ._shading import register_shading_model as register_shading_model
from ._shading import shading_model_class as shading_model_class
from ._shading import transmittance as transmittance
from ._shading._model import Plateau as Plateau
from ._shading._model import check_params as check_params
from ._shading._transforms import IDENTITY as IDENTITY
from ._shading._transforms import LOG as LOG
from ._shading._transforms import SOFTPLUS as SOFTPLUS
from ._shading._transforms import Transform as Transform

__all__ = [
    "AbstractOrdering",
    "AbstractShadingModel",
    "AbstractShadowMethod",
    "Geometry",
    "IDENTITY",
    "LOG",
    "Plateau",
    "PointInputs",
    "Reflectance",
    "SOFTPLUS",
    "ShadingPoints",
    "Transform",
    "check_params",
    "kajiya_kay",
    "register_ordering",
    "register_shading_model",
    "register_shadow_method",
    "shading_model_class",
    "transmittance",
]
