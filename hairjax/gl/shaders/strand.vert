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
in float in_visibility;  // §13: 0 where the occluder shadows the point
in float in_streak;        // §16: the hair's streak coordinate u_i (bound only with streaks)
in vec3 in_normal;         // §17 (Scheuermann scenes only): strand normal
in vec2 in_maps;           // §17: shift texture σ, noise mask m
in vec3 in_screen;         // light passes: the point in the light's raster, projected on the host

uniform View view;
uniform bool given_screen; // light passes: in_screen, not project(view, in_position) (§7)
uniform bool world_width;  // §5: in_width in world units, w·f/D pixels here (w·f orthographic)
uniform bool shade;        // camera pass: shade points; light passes: geometry only
uniform Shading shading;
uniform Scheuermann scheuermann;  // used when shading.model == SHADING_SCHEUERMANN
uniform Marschner marschner;      // used when shading.model == SHADING_MARSCHNER
uniform vec3 light_rgb;
uniform vec3 light_vector; // −direction (directional) or the light's position (point)
uniform bool point_light;
uniform vec3 eye;
uniform sampler2D kajiya_kay_table;  // §14, bound for SHADING_KAJIYA_KAY_LOOKUP only
uniform sampler2D marschner_tables;  // §19, bound for SHADING_MARSCHNER with dual scattering only
uniform bool streaks;                 // §16
uniform sampler2D streak_texture;     // (N_{k mod m}, P_k), k = 0 … m
uniform int streak_texels;            // m
uniform float streak_width;           // Δ

out VertexOut {
    vec3 screen;
    vec3 color;
    float alpha;
    float width;
} vout;

void main() {
    // The light passes take the host's float64 projection, rounded once, as the JAX
    // raster does (§7): projected here in float32, a fragment ulps from a layer boundary
    // could fall on its other side.
    vout.screen = given_screen ? in_screen : project(view, in_position);
    vout.alpha = in_alpha;
    // Drawn segments lie beyond the near plane, so D > 0 where the width is used.
    vout.width = world_width ? in_width * view.focal / (view.perspective ? vout.screen.z : 1.0)
                             : in_width;
    vout.color = vec3(0.0);
    if (shade) {
        vec3 L = point_light ? safe_normalize(light_vector - in_position) : light_vector;
        vec3 V = safe_normalize(eye - in_position);
        float tau = transmittance(shading.kappa, in_omega) * in_visibility;
        if (shading.model == SHADING_SCHEUERMANN)
            vout.color = shade_scheuermann(scheuermann, in_tangent, in_normal, L, V, in_maps.x,
                                           in_maps.y, in_color, light_rgb, tau);
        else if (shading.model == SHADING_MARSCHNER)
            vout.color = shade_marschner(marschner, marschner_tables, shading.ambient, in_tangent, L, V,
                                         light_rgb, tau, in_visibility, shading.kappa * in_omega);
        else if (shading.model == SHADING_KAJIYA_KAY_LOOKUP)
            vout.color = shade_point_lookup(shading, kajiya_kay_table, in_tangent, L, V, in_color, light_rgb, tau);
        else
            vout.color = shade_point(shading, in_tangent, L, V, in_color, light_rgb, tau);
        if (streaks) vout.color *= streak_factor(streak_texture, streak_texels, in_streak, streak_width);
    }
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);  // the geometry shader places the ribbon
}
