#version 450
// §7 deep opacity maps, the layer pass (blended GL_ONE, GL_ONE): a fragment of slice j
// (layer j behind its texel's z₀; slice K beyond the last boundary) adds its alpha to every
// boundary b > j. Boundaries 1 … K and the total (b = K + 1) are packed four to an RGBA
// target, as the paper packs its layers into colour channels; this pass draws boundaries
// 4·group + 1 … 4·group + 4.
#include "hairjax_model"
#include "hairjax_ribbon_fragment"

uniform bool light_perspective;
uniform sampler2D first_map;  // z₀ per texel (deep_first.frag), in GL's row order
uniform int layers;
uniform float depth_range;    // KΔ
uniform int group;

out vec4 frag_alpha;

void main() {
    RibbonSample r = ribbon_sample();
    float z = fragment_depth(depths.x, depths.y, r.t, light_perspective);
    float z0 = texelFetch(first_map, ivec2(gl_FragCoord.xy), 0).r;
    // The clamp fires below 0 only by rounding (z₀ is this texel's nearest fragment) and
    // at u ≥ K: slice K, in the total only.
    float u = deep_layer_coordinate(z, z0, layers, depth_range);
    int slice = int(clamp(floor(u), 0.0, float(layers)));
    ivec4 boundary = 4 * group + ivec4(1, 2, 3, 4);
    frag_alpha = alpha * r.coverage * vec4(greaterThan(boundary, ivec4(slice)));
}
