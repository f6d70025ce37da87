#version 450
// §7, opacity maps four a pass: each map of a pass starts at Ω(D_first), the previous
// pass's last map (its alpha channel), and its slices add to that (GL_ONE, GL_ONE into a
// target cleared to 0: 0 + x = x), as kim-2003 Routine 2's one accumulation buffer does.
uniform sampler2D lower_map;

out vec4 boundary_alpha;

void main() {
    boundary_alpha = vec4(texelFetch(lower_map, ivec2(gl_FragCoord.xy), 0).a);
}
