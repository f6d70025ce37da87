#version 450
// §13: a mesh occluder's surface at the pixel centre: point, normal and depth (z-buffer).
#include "hairjax_model"

in vec3 v_position;
in vec3 v_normal;

uniform View view;
uniform vec2 depth_range;  // view depth → [0, 1): (D − lo)/(hi − lo)

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    float d = dot(v_position - view.origin, view.forward);
    gl_FragDepth = (d - depth_range.x) / (depth_range.y - depth_range.x);
    float n = safe_norm(v_normal);
    // Fires only between vertices of degenerate triangles (zero vertex normals): no light.
    out_normal = vec4(n > 0.0 ? v_normal / n : vec3(0.0), 0.0);
    out_position = vec4(v_position, 1.0);
}
