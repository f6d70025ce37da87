#version 450
// §7 `exact`: every light-space fragment goes into its texel's list (an A-buffer), in two
// passes over the same geometry: count, then fill.
#include "hairjax_model"
#include "hairjax_ribbon_fragment"

uniform bool light_perspective;
uniform bool fill;
uniform int resolution;

layout(std430, binding = 0) buffer Counts { uint counts[]; };
layout(std430, binding = 1) buffer Cursor { uint cursor[]; };
layout(std430, binding = 2) readonly buffer Offsets { uint offsets[]; };
layout(std430, binding = 3) writeonly buffer Entries { vec2 entries[]; };  // (depth, alpha)

void main() {
    RibbonSample r = ribbon_sample();
    // The texel in the model's row order (y down).
    int row = resolution - 1 - int(gl_FragCoord.y);
    uint texel = uint(row * resolution + int(gl_FragCoord.x));
    if (!fill) {
        atomicAdd(counts[texel], 1u);
        return;
    }
    float z = fragment_depth(depths.x, depths.y, r.t, light_perspective);
    uint slot = offsets[texel] + atomicAdd(cursor[texel], 1u);
    entries[slot] = vec2(z, alpha * r.coverage);
}
