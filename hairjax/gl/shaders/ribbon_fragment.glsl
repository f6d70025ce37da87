// §5 at one pixel centre: coverage, position t along the segment and depth. Shared by
// the camera pass and the light passes. Discards pixels the ribbon does not cover.
flat in vec2 p0;
flat in vec2 delta;
flat in float seg_length;
flat in vec3 color0;
flat in vec3 color1;
flat in float alpha;
flat in vec2 widths;
flat in vec2 depths;

uniform vec2 raster_size;

struct RibbonSample {
    float coverage;
    float t;
};

RibbonSample ribbon_sample() {
    // Pixel centre in the model's coordinates: GL's window y points up.
    vec2 c = vec2(gl_FragCoord.x, raster_size.y - gl_FragCoord.y);
    float inv_len = 1.0 / seg_length;
    vec2 r = c - p0;
    float s = (r.x * delta.x + r.y * delta.y) * inv_len;
    float dist = abs(r.x * delta.y - r.y * delta.x) * inv_len;
    float t = s * inv_len;
    // w₀ + t(w₁ − w₀) is exactly w₀ for ribbons of constant width (pixel widths).
    float cov = ribbon_coverage(dist, widths.x + t * (widths.y - widths.x));
    if (!(cov > 0.0) || s < 0.0 || !(s < seg_length)) discard;
    return RibbonSample(cov, t);
}
