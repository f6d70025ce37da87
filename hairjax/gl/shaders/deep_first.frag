#version 450
// §7 deep opacity maps (Yuksel & Keyser 2008), the depth pass: each texel's first hair
// depth z₀, the nearest light-space fragment (the pass blends with MIN into a target
// cleared to +∞; ribbon_sample discards what has no coverage).
#include "hairjax_model"
#include "hairjax_ribbon_fragment"

uniform bool light_perspective;

out float first_depth;

void main() {
    RibbonSample r = ribbon_sample();
    first_depth = fragment_depth(depths.x, depths.y, r.t, light_perspective);
}
