"""Self-shadowing of the hair (kim-2003 §4, docs/model.md §7): one module per method,
registered by method name: `none`, `opacity-maps` (kim-2003's opacity shadow maps),
`exact` (their N → ∞ limit) and `deep` (Yuksel & Keyser 2008's deep opacity maps, layers
behind each texel's first hair). `_frame.py` holds what they share: the light's view.
"""

from ._base import AbstractShadowMethod as AbstractShadowMethod
from ._base import Shadows as Shadows
from ._base import register_shadow_method as register_shadow_method
from ._base import shadow_method_class as shadow_method_class
from ._base import shadow_method_names as shadow_method_names
from ._deep import DeepOpacityMaps as DeepOpacityMaps
from ._deep import DeepSetup as DeepSetup
from ._deep import deep_points as deep_points
from ._deep import filter_texels as filter_texels
from ._deep import first_depths as first_depths
from ._deep import layer_coordinate as layer_coordinate
from ._exact import ExactSetup as ExactSetup
from ._exact import ExactShadows as ExactShadows
from ._exact import exact_opacity as exact_opacity
from ._frame import LightFragments as LightFragments
from ._frame import LightFrame as LightFrame
from ._frame import ShadowInputs as ShadowInputs
from ._frame import light_fragments as light_fragments
from ._frame import light_frame as light_frame
from ._frame import light_raster as light_raster
from ._frame import map_margin as map_margin
from ._frame import with_receivers as with_receivers
from ._none import NoShadows as NoShadows
from ._opacity_maps import MAX_MAP_CELLS as MAX_MAP_CELLS
from ._opacity_maps import OpacityMaps as OpacityMaps
from ._opacity_maps import OpacityMapSetup as OpacityMapSetup
from ._opacity_maps import box_filter as box_filter
from ._opacity_maps import opacity_maps as opacity_maps
from ._opacity_maps import point_opacity as point_opacity
from ._opacity_maps import point_planes as point_planes
