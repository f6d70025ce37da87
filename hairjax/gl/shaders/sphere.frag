#version 450
// §9: the occluder, ray-cast at each pixel centre, drawn first with depth writes.
#include "hairjax_model"

uniform View view;
uniform vec2 raster_size;
uniform vec3 center;
uniform float radius;
uniform vec3 albedo;
uniform vec3 light_rgb;
uniform vec3 light_vector;
uniform bool point_light;
uniform float depth_far;

out vec4 frag_color;

void main() {
    vec2 c = vec2(gl_FragCoord.x, raster_size.y - gl_FragCoord.y);
    vec2 xy = vec2(c.x - view.center.x, -(c.y - view.center.y)) / view.focal;
    vec3 dir = normalize(view.forward + xy.x * view.right + xy.y * view.up);
    vec3 oc = view.origin - center;
    float b = dot(oc, dir);
    float disc = b * b - (dot(oc, oc) - radius * radius);
    if (disc < 0.0) discard;
    float root = sqrt(disc);
    // The nearer intersection in front of the eye; the farther one when the eye is inside.
    float t = (-b - root > 0.0) ? -b - root : -b + root;
    if (!(t > 0.0)) discard;  // fires when the sphere lies behind the eye
    vec3 hit = view.origin + t * dir;
    vec3 n = normalize(hit - center);
    // Unguarded: a point light on the sphere gives normalize(0), undefined (llvmpipe: 0 after max).
    vec3 L = point_light ? normalize(light_vector - hit) : light_vector;
    frag_color = vec4(albedo * light_rgb * max(dot(n, L), 0.0), 1.0);
    gl_FragDepth = dot(hit - view.origin, view.forward) / depth_far;
}
