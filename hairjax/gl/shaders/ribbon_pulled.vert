#version 450
// §5: a segment expanded into its quad (`ribbon_corner`) in the vertex shader, without a
// geometry shader (hairjax/gl/_ribbons.py): vertex gl_VertexID is corner
// CORNER[gl_VertexID % 6] of segment first_segment + gl_VertexID / 6 (two triangles, the
// strip ribbon.geom emits), its ends read from the points strand.vert placed and shaded
// once (transform feedback: screen.xyz, color.rgb, alpha, width) and the index list.
#include "hairjax_model"
#include "hairjax_ribbon_quad"

// Bindings 6 and 7: the passes' own storage buffers take 0 … 5.
layout(std430, binding = 6) readonly buffer ShadedPoints { float shaded[]; };
layout(std430, binding = 7) readonly buffer SegmentEnds { uint ends[]; };

uniform vec2 raster_size;
uniform int first_segment;

flat out vec2 p0;
flat out vec2 delta;
flat out float seg_length;
flat out vec3 color0;
flat out vec3 color1;
flat out float alpha;
flat out vec2 widths;  // the ribbon width at each end (pixels)
flat out vec2 depths;

const int POINT_FLOATS = 8;
const int CORNER[6] = int[6](0, 1, 2, 2, 1, 3);

void main() {
    int segment = first_segment + gl_VertexID / 6;
    uint i0 = uint(POINT_FLOATS) * ends[2 * segment];
    uint i1 = uint(POINT_FLOATS) * ends[2 * segment + 1];
    vec2 a = vec2(shaded[i0], shaded[i0 + 1u]);
    vec2 b = vec2(shaded[i1], shaded[i1 + 1u]);
    float len = length(b - a);
    p0 = a;
    delta = b - a;
    seg_length = len;
    color0 = vec3(shaded[i0 + 3u], shaded[i0 + 4u], shaded[i0 + 5u]);
    color1 = vec3(shaded[i1 + 3u], shaded[i1 + 4u], shaded[i1 + 5u]);
    alpha = shaded[i0 + 6u];
    widths = vec2(shaded[i0 + 7u], shaded[i1 + 7u]);
    depths = vec2(shaded[i0 + 2u], shaded[i1 + 2u]);
    // Zero-length segments draw nothing (§5): all six corners at one point, no area.
    gl_Position = len > 0.0 ? ribbon_corner(a, b, len, widths, CORNER[gl_VertexID % 6], raster_size)
                            : vec4(0.0, 0.0, 0.0, 1.0);
}
