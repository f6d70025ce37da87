"""The shading stage and its models (docs/model.md §8, §14, §16, §17; docs/architecture.md).

Importing this package registers the built-in models: `KajiyaKay` (kim-2003's cone),
`KajiyaKayMirror` (the mirror cone), `KajiyaKayLookup` (wenzel-2002's table) and
`Scheuermann` (scheuermann-2004's two shifted highlights). Streaks (wenzel-2002) are a
modifier of any model, `Scene.streaks`. `LightParams`: the light's direction and colour as
inputs of the shading stage.
"""

from ._kajiya_kay import KajiyaKay as KajiyaKay
from ._kajiya_kay import ShadingParams as ShadingParams
from ._kajiya_kay import kajiya_kay as kajiya_kay
from ._kajiya_kay import kajiya_kay_terms as kajiya_kay_terms
from ._kajiya_kay import seed_cone as seed_cone
from ._kajiya_kay import specular_power as specular_power
from ._light import LightParams as LightParams
from ._lookup import KajiyaKayLookup as KajiyaKayLookup
from ._marschner import Marschner as Marschner
from ._marschner import MarschnerParams as MarschnerParams
from ._mirror import KajiyaKayMirror as KajiyaKayMirror
from ._mirror import mirror_cone as mirror_cone
from ._model import AbstractShadingModel as AbstractShadingModel
from ._model import Plateau as Plateau
from ._model import PointInputs as PointInputs
from ._model import Reflectance as Reflectance
from ._model import ShadingPoints as ShadingPoints
from ._model import register_shading_model as register_shading_model
from ._model import shading_model_class as shading_model_class
from ._model import shading_model_names as shading_model_names
from ._scheuermann import Scheuermann as Scheuermann
from ._scheuermann import ScheuermannParams as ScheuermannParams
from ._scheuermann_inputs import ScheuermannMaps as ScheuermannMaps
from ._stage import occluder_colors as occluder_colors
from ._stage import point_colors as point_colors
from ._stage import shading_stage as shading_stage
from ._streaks import Streaks as Streaks
from ._transmittance import transmittance as transmittance
