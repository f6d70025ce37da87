// §5: the screen-aligned quad a segment is drawn as, holding every pixel centre with
// 0 ≤ s < L and d < w/2 + ½ (w the wider end's width), with RIBBON_QUAD_SPARE pixels to
// spare on each side for GL's rounding of the corners; the fragment shader decides.
// Shared by the two ways of drawing ribbons (hairjax/gl/_ribbons.py): ribbon.geom and
// ribbon_pulled.vert. Corner k of the strip (a−, a+, b−, b+) in normalised device
// coordinates; `len` = |b − a| > 0.
vec4 ribbon_corner(vec2 a, vec2 b, float len, vec2 widths, int k, vec2 raster_size) {
    vec2 u = (b - a) / len;
    vec2 n = vec2(-u.y, u.x);
    float reach = 0.5 * max(widths.x, widths.y) + PIXEL_HALF_EXTENT + RIBBON_QUAD_SPARE;
    vec2 along = RIBBON_QUAD_SPARE * u;
    vec2 corner = (k < 2 ? a - along : b + along) + (k % 2 == 0 ? -n : n) * reach;
    return vec4(2.0 * corner.x / raster_size.x - 1.0, 1.0 - 2.0 * corner.y / raster_size.y, 0.0, 1.0);
}
