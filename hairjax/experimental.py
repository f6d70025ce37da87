"""hairjax.experimental: the internals the experiments and notebooks measure, beyond the
public names of `hairjax` (docs/api.md). They may change without notice: the set-up and its
draw orders, the fragment buckets, the placement of the set-up's kernels, batched views'
parts, the renderers' agreement band, the distillation's views, the per-scene cache, the
framing helpers, and the atomic file writers the experiments save their results with.
"""

from ._cache import forget as forget
from ._disagreement import renderer_band as renderer_band
from ._distill import DISTILL_VIEWS as DISTILL_VIEWS
from ._distill import DistillView as DistillView
from ._geometry._capacity import fragment_bucket as fragment_bucket
from ._geometry._ordering import draw_order as draw_order
from ._geometry._ordering import hair_centre as hair_centre
from ._geometry._ordering import segment_depth as segment_depth
from ._geometry._ordering import static_order as static_order
from ._geometry._placement import Placement as Placement
from ._geometry._placement import default_placement as default_placement
from ._geometry._projection import camera_view as camera_view
from ._geometry_stage._setup import prepare as prepare
from ._geometry_stage._setup import render_cutoff as render_cutoff
from ._geometry_stage._setup import visibility_order as visibility_order
from ._io._files import atomic_path as atomic_path
from ._io._files import write_csv as write_csv
from ._io._files import write_json as write_json
from ._io._files import write_text as write_text
from ._scene._framing import frame_camera as frame_camera
from ._scene._framing import key_light as key_light
from ._views import shade_views as shade_views
from ._views import stack_geometries as stack_geometries
from ._views import view_scenes as view_scenes

__all__ = [
    "DISTILL_VIEWS",
    "DistillView",
    "Placement",
    "atomic_path",
    "camera_view",
    "default_placement",
    "draw_order",
    "forget",
    "fragment_bucket",
    "frame_camera",
    "hair_centre",
    "key_light",
    "prepare",
    "render_cutoff",
    "renderer_band",
    "segment_depth",
    "shade_views",
    "stack_geometries",
    "static_order",
    "view_scenes",
    "visibility_order",
    "write_csv",
    "write_json",
    "write_text",
]
