#version 450
// §7: Ω of the points in slice `plane`, between map B_prev = Ω(D_plane) and
// B_current = Ω(D_plane+1), each averaged over the 3 × 3 texels around the point
// (kim-2003 Routine 2, loop 4).
layout(local_size_x = 64) in;
#include "hairjax_model"

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Ids { uint ids[]; };
layout(std430, binding = 2) buffer Omega { float omega[]; };

uniform sampler2D prev_map;
uniform sampler2D cur_map;
uniform View light;
uniform int first;
uniform int count;
uniform int plane;
uniform float zmin;
uniform float span;
uniform int maps;
uniform int resolution;

float box(sampler2D map, ivec2 texel) {
    float sum = 0.0;
    for (int dy = -SHADOW_FILTER_RADIUS; dy <= SHADOW_FILTER_RADIUS; ++dy) {
        for (int dx = -SHADOW_FILTER_RADIUS; dx <= SHADOW_FILTER_RADIUS; ++dx) {
            ivec2 q = texel + ivec2(dx, dy);
            // Texels outside the map count 0.
            if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(resolution))))
                sum += texelFetch(map, ivec2(q.x, resolution - 1 - q.y), 0).r;
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
    float f = clamp((q.z - zmin) * float(maps) / span - float(plane), 0.0, 1.0);
    omega[id] = (1.0 - f) * box(prev_map, texel) + f * box(cur_map, texel);
}
