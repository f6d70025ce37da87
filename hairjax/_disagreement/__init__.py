"""Where the JAX and GL renderers may differ: discontinuities of the model within float32
rounding (docs/model.md §11).

The model has discontinuities: a pixel centre belongs to a segment only for 0 ≤ s < L
(§5), a light-space fragment adds to the slice its depth falls in and a point reads the
texels around the one it falls in (§7), `exact` counts fragments strictly nearer than the
point, deep opacity maps put a fragment in a layer behind its texel's first depth z₀, and
the occluder is point-sampled (§9). GLSL computes in float32, JAX in float64
(or float32 in another order of operations), so a pixel centre, fragment or point within
rounding of such a boundary may land on either side. Everything here is computed from the
geometry alone, in NumPy (JAX only for the rasteriser's kernel and the geometry stage's Ω),
independently of both renderers' per-pixel code:

- `camera_band`: pixels a camera-side boundary within rounding can move by > PIXEL_TOL
  when both renderers use one Ω (tests/gl/test_renderer.py's camera pass);
- `omega_uncertainty`, `shadow_band`: how much, and at which points, a light-side
  boundary within rounding can change Ω; `transmittance_uncertainty`: what that does to τ
  for any κ;
- `renderer_band`: pixels either can move by > PIXEL_TOL — what a fit to GL-rendered
  targets masks (docs/fitting.md, experiments/01_fit_recovery.py).

Tolerances (tests/gl/test_renderer.py gives the measurements behind them):
- PIXEL_TOL, TAU_TOL = 1e-4 per pixel / per τ: float32 arithmetic on values ≤ 1 with ~10²
  operations per fragment and up to ~10³ fragments composited per pixel gives errors
  ~10⁻⁵; 1e-4 is the cross-check's bound (docs/model.md §11).
- `s_delta`, 4 float32 ulps of the raster's largest coordinate, for "near a segment end".
- SLICE_DELTA = 1e-4 slice units for "near a slice boundary": depth relative error ~1e-7,
  times N/span.
- MAX_BAND = 1e-3: the share of pixels the camera band may hold (the cross-check's bound).
"""

from . import _deep, _exact, _opacity_maps  # noqa: F401 (they register their light bands)
from ._band import renderer_band as renderer_band
from ._camera import camera_band as camera_band
from ._camera import end_band as end_band
from ._camera import over_weights_numpy as over_weights_numpy
from ._light import omega_uncertainty as omega_uncertainty
from ._light import register_light_band as register_light_band
from ._light import shadow_band as shadow_band
from ._light import transmittance_uncertainty as transmittance_uncertainty
from ._occluder import occluder_light_uncertainty as occluder_light_uncertainty
from ._tolerances import MAX_BAND as MAX_BAND
from ._tolerances import OCCLUDER_EDGE_DELTA as OCCLUDER_EDGE_DELTA
from ._tolerances import OCCLUDER_VERTEX_STEP as OCCLUDER_VERTEX_STEP
from ._tolerances import PIXEL_TOL as PIXEL_TOL
from ._tolerances import SLICE_DELTA as SLICE_DELTA
from ._tolerances import TAU_TOL as TAU_TOL
from ._tolerances import s_delta as s_delta
