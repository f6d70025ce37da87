"""Numerical constants of the hair model, each with its reason.

One definition for the JAX renderer, the GLSL shaders (hairjax/gl/_programs.py injects
them as `const` declarations) and the tests.
"""

# Antialiasing: a pixel is a unit box aligned with the ribbon; coverage across the ribbon
# is the overlap of [d - 0.5, d + 0.5] with [-w/2, w/2] (kim-2003 §2, docs/model.md §5).
PIXEL_HALF_EXTENT = 0.5

# Pixel (x, y) is the unit box [x, x + 1) × [y, y + 1): its centre, where coverage, t and
# depth are sampled (docs/model.md §5), lies half its extent from its corner.
PIXEL_CENTRE = PIXEL_HALF_EXTENT

# GL draws each ribbon as a quad (hairjax/gl/shaders/ribbon.geom) that holds every pixel
# centre the ribbon covers (docs/model.md §5: 0 ≤ s < L and d < w/2 + PIXEL_HALF_EXTENT)
# with this many pixels to spare on each side, for where GL rounds the quad's corners: the
# float32 corners (≤ 1e-4 px at 2048 px) and the snap to the subpixel grid, at most
# 1/32 px (GL_SUBPIXEL_BITS ≥ 4). The fragment shader decides coverage, so a larger spare
# changes no image; it only makes fragments that are discarded.
RIBBON_QUAD_SPARE = 0.125

# Opacity maps are sampled with a (2r + 1)² box filter around the texel of the point
# (kim-2003 §4.1 uses 3 × 3).
SHADOW_FILTER_RADIUS = 1

# Below this base the Kajiya-Kay specular power is exactly 0 (value and gradients), so
# pow(0, p) and log(0) never appear. 1e-12^p is < 1e-6 already for p ≥ 0.5, the smallest
# shininess we support, so the cut is below float32 resolution of any visible highlight.
# (The base b is carried as its gap 1 − b, whose float32 resolution at b ≈ 0 is 2^-24:
# there the cut acts at b ≤ 0, as coarse as b's own rounding near 0.)
SPECULAR_BASE_EPS = 1e-12

# Vectors shorter than this are treated as zero by safe normalisation (zero-length
# segments, repeated points, a point light at a strand point).
SAFE_NORM_EPS = 1e-30

# Default near distance of the camera, as a fraction of |target - eye|.
NEAR_FRACTION = 1e-3

# Fitting only: fragments behind a front-to-back transmittance below this are left out of
# the per-step composites. All of a pixel's fragments behind the cut weigh Σ w ≤ T_cut
# together, so the image moves by at most T_cut × the brightest colour (1e-5 of it).
FIT_TRANSMITTANCE_CUTOFF = 1e-5

# The occluder's shadow (docs/model.md §13): a point is shadowed when its light depth
# exceeds the occluder's depth at its texel by more than this many texels' world size.
# A receiver on the occluder's own surface lies up to √2/2 texel from the texel centre
# where the map was sampled, so its depth differs by up to 0.71·tan θ texels (θ between
# the normal and the light): 3 texels keeps surfaces with tan θ < 4.2 (N·L > 0.23) free of
# self-shadowing "acne"; below that Lambert's N·L is small anyway.
OCCLUDER_SHADOW_BIAS = 3.0

# Scheuermann (scheuermann-2004 slide 12, docs/model.md §17): the diffuse term is
# saturate(lerp(SCHEUERMANN_DIFFUSE_FLOOR, 1, N·L)): scheuermann-2004's 0.25 shifts the terminator
# past N·L = 0 "for a softer look" (light reaches N·L > −1/3).
SCHEUERMANN_DIFFUSE_FLOOR = 0.25

# Hair patches (docs/model.md §18, scheuermann-2004 slide 17): a fragment is opaque, and
# passes the Z-priming pass's alpha test, when its texture alpha a ≥ 1 − PATCH_OPAQUE_EPS.
# The profile a(u) reaches exactly 1 on the core; 1e-6 only absorbs float32 rounding of
# the interpolated u in GL there (u's float32 error ~1e-7, a's ≤ 1e-7 / (½ − c/2)).
PATCH_OPAQUE_EPS = 1e-6

# Hair patches (docs/model.md §18): GL decides a triangle's coverage on its window-space
# vertices in fixed point with this many fractional bits, i.e. rounded to 1/256 px, and
# interpolates attributes from the unrounded positions. llvmpipe: FIXED_ORDER = 8 in
# lp_rast.h, GL_SUBPIXEL_BITS = 8; tests/test_patches.py measures both rules. The JAX patch
# rasteriser rounds the same way, so the two agree on which fragments exist.
RASTER_SUBPIXEL_BITS = 8

# Hair patches' strand texture (docs/model.md §18, scheuermann-2004 slide 6: the alpha
# texture "should have fully opaque regions"): this share of the strands across a patch
# reaches alpha 1; the others peak at patch_strand_alpha … 1 − (1 − that)/128.
PATCH_OPAQUE_STRANDS = 0.5

# Strand points and mesh vertices (docs/model.md §1, docs/scenes.md "Input ranges"): every
# coordinate within ±COORDINATE_BOUND. The renderers work in float32 (largest finite value
# 3.4e38), and the projection and the framing square differences of coordinates
# (|p − eye|², |p − q|²). For points within 5 bounds of the origin on every axis (the hair,
# and a camera placed a few hair sizes away) a squared distance is at most
# 3 · (10 · 1e18)² = 3e38, still finite in float32; the perspective divide (§2) is by depths
# kept ≥ near, so it adds no factor the bound must cover.
COORDINATE_BOUND = 1e18

# The hair fibre's index of refraction (docs/model.md §19): Marschner et al. 2003's and
# Mitsuba's `hair` BSDF's default (amber, 1.55), over air taken as 1 (the reference
# renders with ext_ior = 1, docs/reference.md).
HAIR_ETA = 1.55

# Absorption per unit fibre radius of one unit of each pigment, RGB (d'Eon et al. 2011, as
# Mitsuba 3's `hair` BSDF defines σ_a = eumelanin·EUMELANIN + pheomelanin·PHEOMELANIN in
# its RGB variants, src/bsdfs/hair.cpp).
EUMELANIN_SIGMA_A = (0.419, 0.697, 1.37)
PHEOMELANIN_SIGMA_A = (0.187, 0.4, 1.05)

# Karis 2016's azimuthal approximations (docs/model.md §19): h_TT = cos(φ/2)(1 + a(0.6 −
# 0.8 cos φ)) and N_TT ∝ exp(−3.65 cos φ − 3.98), as (0.6, 0.8, 3.65, 3.98); N_TRT ∝
# exp(17 cos φ − 16.78), as (17, 16.78); the TRT lobe's offset h = √3/2.
KARIS_TT = (0.6, 0.8, 3.65, 3.98)
KARIS_TRT = (17.0, 16.78)
HAIR_TRT_OFFSET = 0.8660254037844386

# Below this 1 − f·T the TRT remainder's geometric series (docs/model.md §19) is taken as
# 0: f → 1 only at grazing incidence (cos → 0), where the remainder, ≤ (1 − f), is 0 already.
HAIR_SERIES_EPS = 1e-12
