#version 450
// §13: the occluder's shadow at points: light depth z against the occluder's depth at the
// texel ⌊xy⌋ of its light-view surface pass; z > depth + bias is shadowed (V = 0). Points
// outside the map or behind a point light's near plane are lit.
layout(local_size_x = 64) in;
#include "hairjax_model"

layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) buffer Visibility { float visibility[]; };

uniform sampler2D light_position_map;
uniform View light;
uniform int count;
uniform int resolution;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= count) return;
    vec3 p = vec3(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]);
    vec3 q = project(light, p);
    ivec2 texel = ivec2(floor(q.xy));
    bool inside = all(greaterThanEqual(texel, ivec2(0))) && all(lessThan(texel, ivec2(resolution)))
                  && (!light.perspective || q.z > light.near);
    float v = 1.0;
    if (inside) {
        vec4 m = texelFetch(light_position_map, ivec2(texel.x, resolution - 1 - texel.y), 0);
        float bias = OCCLUDER_SHADOW_BIAS * (light.perspective ? q.z : 1.0) / light.focal;
        if (m.w > 0.0 && q.z > dot(m.xyz - light.origin, light.forward) + bias) v = 0.0;
    }
    visibility[i] = v;
}
