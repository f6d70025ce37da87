#version 450
// §13: a mesh occluder's vertex in the pass's view (camera or light). Clip coordinates
// reproduce project(): x, y from pixel coordinates, w = depth (1 for orthographic views),
// so GL's perspective-correct interpolation is the model's λ_i/D_i weighting; z = 0 keeps
// every vertex inside the depth clip planes (depth is written by the fragment shader).
#include "hairjax_model"

in vec3 in_position;
in vec3 in_normal;

uniform View view;
uniform vec2 raster_size;

out vec3 v_position;
out vec3 v_normal;

void main() {
    vec3 q = project(view, in_position);
    float w = view.perspective ? q.z : 1.0;
    vec2 ndc = vec2(2.0 * q.x / raster_size.x - 1.0, 1.0 - 2.0 * q.y / raster_size.y);
    gl_Position = vec4(ndc * w, 0.0, w);
    v_position = in_position;
    v_normal = in_normal;
}
