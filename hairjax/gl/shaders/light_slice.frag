#version 450
// §7, kim-2003 Routine 2 line 10 with §4.2's clipping at fragment level: only fragments
// of slice `slice` add their alpha (the pass blends GL_ONE, GL_ONE).
#include "hairjax_model"
#include "hairjax_ribbon_fragment"

uniform bool light_perspective;
uniform float zmin;
uniform float span;
uniform int maps;
uniform int slice;

out float frag_alpha;

void main() {
    RibbonSample r = ribbon_sample();
    float z = fragment_depth(depths.x, depths.y, r.t, light_perspective);
    if (slice_of(z, zmin, span, maps) != slice) discard;
    frag_alpha = alpha * r.coverage;
}
