#version 450
// §18: a hair patch fragment in one of slide 17's four passes. GLSL has no fixed-function
// alpha test: `discard` is it. The depth is the view depth D, written by every pass from
// the same inputs, so pass 2's Z test EQUAL meets pass 1's value bit for bit.
#include "hairjax_model"

in vec3 v_position;
in float v_u;
in float v_v;
flat in uint v_patch;
in vec3 v_color;

uniform View view;
uniform vec2 depth_range;  // view depth → [0, 1): (D − lo)/(hi − lo)
uniform float core;        // opaque fraction c of a strand's profile
uniform int strands;       // n strands across a patch
uniform float strand_alpha;  // m: the lowest peak alpha of the semi-transparent strands
uniform float tips;        // λ: how far the strands' lengths spread below the tip
uniform bool opaque_pass;  // passes 1–2 keep opaque fragments, passes 3–4 the others

layout(location = 0) out vec4 out_color;

// Jarzynski & Olano's pcg_hash (JCGT 2020), uint arithmetic mod 2^32 (as _patches._pcg).
uint pcg_hash(uint x) {
    uint state = x * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// One strand's profile p(t): 1 on the core |t − ½| ≤ c/2, linear to 0 at its edges.
float profile(float t) {
    float half_width = 0.5 - 0.5 * core;
    float edge = 0.5 - abs(t - 0.5);
    // Fires for c = 1 only (no fading band): the whole strand is opaque.
    return half_width > 0.0 ? clamp(edge / half_width, 0.0, 1.0) : 1.0;
}

// §18's alpha texture a(u, v): strand k = min(⌊nu⌋, n − 1) of the patch at t = nu − k,
// a = α_k·p(t), 0 beyond the strand's length; α_k and the length from h = pcg(k + pcg(patch)).
float patch_texture(float u, float v, uint patch_id) {
    float s = float(strands) * u;
    // The clamp fires for u outside [0, 1] (a pixel only the rounded edge covers): p = 0 there.
    float k = clamp(floor(s), 0.0, float(strands - 1));
    float p = profile(s - k);
    uint h = pcg_hash(uint(k) + pcg_hash(patch_id));
    float q = float(h >> 24u) / 256.0;
    float rest = 1.0 - PATCH_OPAQUE_STRANDS;
    float peak = q >= rest ? 1.0 : strand_alpha + (1.0 - strand_alpha) * (q / rest);
    float a = peak * p;
    if (tips > 0.0) {  // λ = 0: every strand runs to the tip
        float g = float(h & 0xFFFFu) / 65536.0;
        if (v > 1.0 - tips * g) a = 0.0;
    }
    return a;
}

void main() {
    float d = dot(v_position - view.origin, view.forward);
    gl_FragDepth = (d - depth_range.x) / (depth_range.y - depth_range.x);
    float a = patch_texture(v_u, v_v, v_patch);
    bool opaque = a >= 1.0 - PATCH_OPAQUE_EPS;
    if (opaque != opaque_pass) discard;
    // The opaque pass writes the colour unblended (alpha 1); the others blend "over".
    out_color = opaque_pass ? vec4(v_color, 1.0) : vec4(v_color, a);
}
