#version 450
// Per strand point: its position in the pass's view and, in the camera pass, its shaded
// colour (§8, Gouraud: evaluated at points, interpolated along segments).
#include "hairjax_model"

in vec3 in_position;
in vec3 in_tangent;
in vec3 in_color;
in float in_alpha;
in float in_width;
in float in_omega;
in vec3 in_normal;         // §13 (Scheuermann scenes only): strand normal
in vec2 in_maps;           // §13: shift texture σ, noise mask m

uniform View view;
uniform bool shade;        // camera pass: shade points; light passes: geometry only
uniform Shading shading;
uniform Scheuermann scheuermann;  // used when shading.model == SHADING_SCHEUERMANN
uniform vec3 light_rgb;
uniform vec3 light_vector; // −direction (directional) or the light's position (point)
uniform bool point_light;
uniform vec3 eye;

out VertexOut {
    vec3 screen;
    vec3 color;
    float alpha;
    float width;
    float level;
} vout;

vec3 safe_normalize(vec3 x) {
    float n = safe_norm(x);
    return x / (n > 0.0 ? n : 1.0);  // fires for zero vectors: the result is 0
}

void main() {
    vout.screen = project(view, in_position);
    vout.alpha = in_alpha;
    vout.width = in_width;
    vout.level = 0.0;
    vout.color = vec3(0.0);
    if (shade) {
        vec3 L = point_light ? safe_normalize(light_vector - in_position) : light_vector;
        vec3 V = safe_normalize(eye - in_position);
        float tau = exp(-shading.kappa * in_omega);
        if (shading.model == SHADING_SCHEUERMANN)
            vout.color = shade_scheuermann(scheuermann, in_tangent, in_normal, L, V, in_maps.x,
                                           in_maps.y, in_color, light_rgb, tau);
        else
            vout.color = shade_point(shading, in_tangent, L, V, in_color, light_rgb, tau);
    }
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);  // the geometry shader places the ribbon
}
