#version 450
// §13: the occluder's colour where its surface pass covered the pixel centre:
// k·ambient + τ·k·light·max(N·L, 0)·V, τ = exp(−κΩ) at the surface point.
#include "hairjax_model"

uniform sampler2D position_map;
uniform sampler2D normal_map;
uniform sampler2D omega_map;       // Ω at the pixel's surface point (0 without shadows)
uniform sampler2D visibility_map;  // V: 0 where the occluder shadows itself
uniform vec3 albedo;
uniform vec3 ambient;
uniform float kappa;
uniform vec3 light_rgb;
uniform vec3 light_vector;
uniform bool point_light;

out vec4 frag_color;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 p = texelFetch(position_map, px, 0);
    if (p.w == 0.0) discard;  // the surface pass did not cover this pixel centre
    vec3 n = texelFetch(normal_map, px, 0).xyz;
    vec3 L = light_vector;
    if (point_light) {
        vec3 d = light_vector - p.xyz;
        float len = safe_norm(d);
        L = len > 0.0 ? d / len : vec3(0.0);  // fires for a light on the surface: no light
    }
    float tau = transmittance(kappa, texelFetch(omega_map, px, 0).r);
    float vis = texelFetch(visibility_map, px, 0).r;
    frag_color = vec4(albedo * ambient + tau * vis * albedo * light_rgb * max(dot(n, L), 0.0), 1.0);
}
