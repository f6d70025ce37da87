#version 450
// §7 deep opacity maps: Ω of the points whose upper boundary this pass drew (boundaries
// 4·group + 1 … 4·group + 4 in cur_map, the group before in prev_map). lookup "layer":
// interpolated at the point's depth behind its own texel's z₀, each boundary map averaged
// over the 3 × 3 texels around the point. lookup "depth": each of the 3 × 3 texels read
// at the point's depth behind that texel's own z₀; the pass adds the texels whose upper
// boundary it drew, so Ω accumulates over the passes.
layout(local_size_x = 64) in;
#include "hairjax_model"

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Ids { uint ids[]; };
layout(std430, binding = 2) buffer Omega { float omega[]; };

uniform sampler2D first_map;
uniform sampler2D prev_map;
uniform sampler2D cur_map;
uniform View light;
uniform int count;
uniform int group;
uniform int layers;
uniform float depth_range;
uniform int resolution;
uniform bool depth_lookup;

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

// Ω̄ on boundary b (0 … K + 1, K + 1 the total) from this group's and the previous one's maps.
float boundary(int b, vec4 prev, vec4 cur) {
    if (b == 0) return 0.0;  // nothing lies in front of z₀
    int g = (b - 1) / 4;
    return (g == group ? cur : prev)[(b - 1) % 4];
}

// Lower boundary k and weight f at layer coordinate u (as _deep.deep_points).
void layer_weight(float u, out int lower, out float f) {
    if (u > float(layers)) {
        lower = layers;  // beyond the last boundary: the texel's total
        f = 1.0;
    } else {
        // The clamps fire in front of z₀ (u < 0: boundary 0) and at u = K (k = K − 1, f = 1).
        lower = clamp(int(floor(u)), 0, layers - 1);
        f = clamp(u - float(lower), 0.0, 1.0);
    }
}

// lookup "depth": this pass's share of (1/9) Σ_t' [(1 − f') Ω_k'(t') + f' Ω_k'+1(t')].
void depth_lookup_omega(uint id, vec3 q, ivec2 texel) {
    float sum = 0.0;
    for (int dy = -SHADOW_FILTER_RADIUS; dy <= SHADOW_FILTER_RADIUS; ++dy) {
        for (int dx = -SHADOW_FILTER_RADIUS; dx <= SHADOW_FILTER_RADIUS; ++dx) {
            ivec2 t = texel + ivec2(dx, dy);
            // Texels outside the map count 0.
            if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ivec2(resolution)))) continue;
            ivec2 g = ivec2(t.x, resolution - 1 - t.y);
            float z0 = texelFetch(first_map, g, 0).r;
            if (isinf(z0)) continue;  // no hair in this texel: it adds 0
            int lower;
            float f;
            layer_weight(deep_layer_coordinate(q.z, z0, layers, depth_range), lower, f);
            if (lower / 4 != group) continue;  // the pass that draws its upper boundary lower + 1
            vec4 prev = texelFetch(prev_map, g, 0);
            vec4 cur = texelFetch(cur_map, g, 0);
            sum += (1.0 - f) * boundary(lower, prev, cur) + f * boundary(lower + 1, prev, cur);
        }
    }
    float side = float(2 * SHADOW_FILTER_RADIUS + 1);
    omega[id] += sum / (side * side);
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= count) return;
    uint id = ids[i];
    vec3 p = vec3(positions[3 * id], positions[3 * id + 1], positions[3 * id + 2]);
    vec3 q = project(light, p);
    // The clamp keeps the cast defined; beyond −2 or R + 1 every texel of the filter is
    // outside the map either way (as _deep.filter_texels).
    ivec2 texel = ivec2(floor(clamp(q.xy, vec2(-2.0), vec2(float(resolution + 1)))));
    if (depth_lookup) {
        depth_lookup_omega(id, q, texel);
        return;
    }
    // Outside the map: no shadow (Ω stays at the buffer's 0, as in JAX).
    if (any(lessThan(texel, ivec2(0))) || any(greaterThanEqual(texel, ivec2(resolution)))) return;
    float z0 = texelFetch(first_map, ivec2(texel.x, resolution - 1 - texel.y), 0).r;
    if (isinf(z0)) return;  // no hair in the point's texel: Ω = 0
    int lower;
    float f;
    layer_weight(deep_layer_coordinate(q.z, z0, layers, depth_range), lower, f);
    if (lower / 4 != group) return;  // the pass that draws its upper boundary lower + 1
    vec4 prev = box(prev_map, texel);
    vec4 cur = box(cur_map, texel);
    omega[id] = (1.0 - f) * boundary(lower, prev, cur) + f * boundary(lower + 1, prev, cur);
}
