#version 450
// §7, kim-2003 Routine 2 line 10 with §4.2's clipping at fragment level, four maps a pass
// (kim-2003 §4.1: one per colour channel): only fragments of slice `slice` add their alpha
// (the pass blends GL_ONE, GL_ONE), to channel c when slice < first_boundary + c, i.e. to
// every map of the pass behind them (α·0 = 0 and x + 0 = x: the others keep their sums).
#include "hairjax_model"
#include "hairjax_ribbon_fragment"

uniform bool light_perspective;
uniform float zmin;
uniform float span;
uniform int maps;
uniform int slice;
uniform int first_boundary;

out vec4 frag_alpha;

void main() {
    RibbonSample r = ribbon_sample();
    float z = fragment_depth(depths.x, depths.y, r.t, light_perspective);
    if (slice_of(z, zmin, span, maps) != slice) discard;
    frag_alpha = alpha * r.coverage * vec4(greaterThan(first_boundary + ivec4(0, 1, 2, 3), ivec4(slice)));
}
