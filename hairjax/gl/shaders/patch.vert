#version 450
// §18: a hair patch vertex in the camera's view, as occluder_mesh.vert (§13): clip w = depth,
// so GL's perspective-correct interpolation is the model's λ_i/D_i weighting.
#include "hairjax_model"

in vec3 in_position;
in float in_u;
in float in_v;
in uint in_patch;
in vec3 in_color;

uniform View view;
uniform vec2 raster_size;

out vec3 v_position;
out float v_u;
out float v_v;
flat out uint v_patch;
out vec3 v_color;

void main() {
    vec3 q = project(view, in_position);
    float w = view.perspective ? q.z : 1.0;
    vec2 ndc = vec2(2.0 * q.x / raster_size.x - 1.0, 1.0 - 2.0 * q.y / raster_size.y);
    gl_Position = vec4(ndc * w, 0.0, w);
    v_position = in_position;
    v_u = in_u;
    v_v = in_v;
    v_patch = in_patch;
    v_color = in_color;
}
