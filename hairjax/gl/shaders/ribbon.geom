#version 450
// §5: a segment expanded into its quad (`ribbon_corner`) by a geometry shader, from the
// two points strand.vert placed and shaded.
#include "hairjax_model"
#include "hairjax_ribbon_quad"

layout(lines) in;
layout(triangle_strip, max_vertices = 4) out;

uniform vec2 raster_size;

in VertexOut {
    vec3 screen;  // x, y in pixels (y down), depth
    vec3 color;
    float alpha;
    float width;
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
    float len = length(b - a);
    if (!(len > 0.0)) return;  // zero-length segments draw nothing (§5)
    for (int i = 0; i < 4; ++i) {
        p0 = a;
        delta = b - a;
        seg_length = len;
        color0 = vin[0].color;
        color1 = vin[1].color;
        alpha = vin[0].alpha;
        widths = vec2(vin[0].width, vin[1].width);
        depths = vec2(vin[0].screen.z, vin[1].screen.z);
        gl_Position = ribbon_corner(a, b, len, widths, i, raster_size);
        EmitVertex();
    }
    EndPrimitive();
}
