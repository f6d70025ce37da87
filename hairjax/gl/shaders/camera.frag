#version 450
// §5, §6: the fragment's colour (endpoint colours interpolated in screen space by t, not
// by perspective-correct varyings) and alpha = a·coverage; blending does the "over".
#include "hairjax_model"
#include "hairjax_ribbon_fragment"

uniform float depth_far;  // view depth → [0, 1) for the occluder's depth test

out vec4 frag_color;

void main() {
    RibbonSample r = ribbon_sample();
    gl_FragDepth = fragment_depth(depths.x, depths.y, r.t, true) / depth_far;
    frag_color = vec4(mix(color0, color1, r.t), alpha * r.coverage);
}
