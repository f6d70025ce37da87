#version 450
// §5: expand a segment into a screen-aligned quad that holds every pixel centre with
// 0 ≤ s < L and d < w/2 + ½ (w the wider end's width), with RIBBON_QUAD_SPARE pixels to
// spare on each side for GL's rounding of the corners; the fragment shader decides.
#include "hairjax_model"

layout(lines) in;
layout(triangle_strip, max_vertices = 4) out;

uniform vec2 raster_size;

in VertexOut {
    vec3 screen;  // x, y in pixels (y down), depth
    vec3 color;
    float alpha;
    float width;
    float level;  // the slice (shadow pass) or unused
} vin[];

flat out vec2 p0;
flat out vec2 delta;
flat out float seg_length;
flat out vec3 color0;
flat out vec3 color1;
flat out float alpha;
flat out vec2 widths;  // the ribbon width at each end (pixels)
flat out vec2 depths;

void main() {
    vec2 a = vin[0].screen.xy;
    vec2 b = vin[1].screen.xy;
    vec2 d = b - a;
    float len = length(d);
    if (!(len > 0.0)) return;  // zero-length segments draw nothing (§5)
    vec2 u = d / len;
    vec2 n = vec2(-u.y, u.x);
    float reach = 0.5 * max(vin[0].width, vin[1].width) + PIXEL_HALF_EXTENT + RIBBON_QUAD_SPARE;
    vec2 along = RIBBON_QUAD_SPARE * u;
    vec2 corners[4] = vec2[4](a - along - n * reach, a - along + n * reach,
                              b + along - n * reach, b + along + n * reach);
    for (int i = 0; i < 4; ++i) {
        p0 = a;
        delta = d;
        seg_length = len;
        color0 = vin[0].color;
        color1 = vin[1].color;
        alpha = vin[0].alpha;
        widths = vec2(vin[0].width, vin[1].width);
        depths = vec2(vin[0].screen.z, vin[1].screen.z);
        vec2 ndc = vec2(2.0 * corners[i].x / raster_size.x - 1.0,
                        1.0 - 2.0 * corners[i].y / raster_size.y);
        gl_Position = vec4(ndc, 0.0, 1.0);
        EmitVertex();
    }
    EndPrimitive();
}
