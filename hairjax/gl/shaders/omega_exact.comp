#version 450
// §7 `exact`: Ω = 3 × 3 average over texels of the alpha of fragments strictly nearer
// the light than the point, read from the per-texel lists.
layout(local_size_x = 64) in;
#include "hairjax_model"

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Ids { uint ids[]; };
layout(std430, binding = 2) buffer Omega { float omega[]; };
layout(std430, binding = 3) readonly buffer Counts { uint counts[]; };
layout(std430, binding = 4) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 5) readonly buffer Entries { vec2 entries[]; };

uniform View light;
uniform int count;
uniform int resolution;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= count) return;
    uint id = ids[i];
    vec3 p = vec3(positions[3 * id], positions[3 * id + 1], positions[3 * id + 2]);
    vec3 q = project(light, p);
    ivec2 texel = ivec2(floor(q.xy));
    float sum = 0.0;
    for (int dy = -SHADOW_FILTER_RADIUS; dy <= SHADOW_FILTER_RADIUS; ++dy) {
        for (int dx = -SHADOW_FILTER_RADIUS; dx <= SHADOW_FILTER_RADIUS; ++dx) {
            ivec2 t = texel + ivec2(dx, dy);
            // Texels outside the map count 0: fires for points beyond the ±80° of a point light.
            if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ivec2(resolution)))) continue;
            uint k = uint(t.y * resolution + t.x);
            for (uint e = offsets[k]; e < offsets[k] + counts[k]; ++e) {
                if (entries[e].x < q.z) sum += entries[e].y;
            }
        }
    }
    float side = float(2 * SHADOW_FILTER_RADIUS + 1);
    omega[id] = sum / (side * side);
}
