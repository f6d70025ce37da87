#version 450
// §7: Ω of the points in slice `plane`, between map B_prev = Ω(D_plane) and
// B_current = Ω(D_plane+1), each averaged over the 3 × 3 texels around the point
// (kim-2003 Routine 2, loop 4).
layout(local_size_x = 64) in;
#include "hairjax_model"

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Ids { uint ids[]; };
layout(std430, binding = 2) buffer Omega { float omega[]; };

uniform sampler2D prev_map;   // the previous pass's maps: its alpha is Ω(D_first_slice)
uniform sampler2D cur_map;    // this pass's: channel c is Ω(D_first_slice + c + 1)
uniform int first_slice;
uniform View light;
uniform int first;
uniform int count;
layout(std430, binding = 3) readonly buffer Planes { int planes[]; };
uniform float zmin;
uniform float span;
uniform int maps;
uniform int resolution;

vec4 box(sampler2D map, ivec2 texel) {
    vec4 sum = vec4(0.0);
    for (int dy = -SHADOW_FILTER_RADIUS; dy <= SHADOW_FILTER_RADIUS; ++dy) {
        for (int dx = -SHADOW_FILTER_RADIUS; dx <= SHADOW_FILTER_RADIUS; ++dx) {
            ivec2 q = texel + ivec2(dx, dy);
            // Texels outside the map count 0.
            if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(resolution))))
                sum += texelFetch(map, ivec2(q.x, resolution - 1 - q.y), 0);
        }
    }
    float side = float(2 * SHADOW_FILTER_RADIUS + 1);
    return sum / (side * side);
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= count) return;
    uint id = ids[first + i];
    vec3 p = vec3(positions[3 * id], positions[3 * id + 1], positions[3 * id + 2]);
    vec3 q = project(light, p);
    ivec2 texel = ivec2(floor(q.xy));
    if (any(lessThan(texel, ivec2(0))) || any(greaterThanEqual(texel, ivec2(resolution)))) {
        omega[id] = 0.0;  // outside the map: no shadow (as in JAX)
        return;
    }
    // The clamp fires by rounding: z is recomputed here in float32, the plane came from NumPy.
    int plane = planes[first + i];
    float f = clamp((q.z - zmin) * float(maps) / span - float(plane), 0.0, 1.0);
    int c = plane - first_slice;  // the point's upper map's channel in this pass
    vec4 upper = box(cur_map, texel);
    float lower = c == 0 ? box(prev_map, texel).a : upper[c - 1];
    omega[id] = (1.0 - f) * lower + f * upper[c];
}
