"""The physically based reference (docs/reference.md): a scene's strands as fibres with
Chiang et al. 2016's hair BSDF, path traced by Mitsuba 3, an optional extra
(`pip install 'hairjax[reference]'`), imported only when a reference is rendered.

`_fibres`: the strands as curves (radius from the ribbons' world width); `_mitsuba_scene`:
the camera, light, occluder and BSDF as Mitsuba's scene description; `_support`: the
import and the features refused; `_render`: `reference_image`.
"""

from ._render import reference_image as reference_image

__all__ = ["reference_image"]
