#version 450
// §18: a hair patch fragment in one of slide 17's four passes. GLSL has no fixed-function
// alpha test: `discard` is it. The depth is the view depth D, written by every pass from
// the same inputs, so pass 2's Z test EQUAL meets pass 1's value bit for bit.
#include "hairjax_model"

in vec3 v_position;
in float v_u;
in vec3 v_color;

uniform View view;
uniform vec2 depth_range;  // view depth → [0, 1): (D − lo)/(hi − lo)
uniform float core;        // opaque fraction c of the across-profile
uniform bool opaque_pass;  // passes 1–2 keep opaque fragments, passes 3–4 the others

layout(location = 0) out vec4 out_color;

void main() {
    float d = dot(v_position - view.origin, view.forward);
    gl_FragDepth = (d - depth_range.x) / (depth_range.y - depth_range.x);
    float half_width = 0.5 - 0.5 * core;
    float edge = 0.5 - abs(v_u - 0.5);
    // Fires for c = 1 only (no fading band): the whole patch is opaque.
    float a = half_width > 0.0 ? clamp(edge / half_width, 0.0, 1.0) : 1.0;
    bool opaque = a >= 1.0 - PATCH_OPAQUE_EPS;
    if (opaque != opaque_pass) discard;
    // The opaque pass writes the colour unblended (alpha 1); the others blend "over".
    out_color = opaque_pass ? vec4(v_color, 1.0) : vec4(v_color, a);
}
