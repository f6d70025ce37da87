#version 450
// §9: the sphere occluder's surface, ray-cast at each pixel centre of the pass's view
// (the camera, or the light for its shadow): point, normal and depth (z-buffer).
#include "hairjax_model"

uniform View view;
uniform vec2 raster_size;
uniform vec3 center;
uniform float radius;
uniform vec2 depth_range;  // view depth → [0, 1): (D − lo)/(hi − lo)

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    vec2 c = vec2(gl_FragCoord.x, raster_size.y - gl_FragCoord.y);
    vec2 xy = vec2(c.x - view.center.x, -(c.y - view.center.y)) / view.focal;
    vec3 origin = view.origin;
    vec3 dir = view.forward;
    if (view.perspective) dir = normalize(view.forward + xy.x * view.right + xy.y * view.up);
    else origin += xy.x * view.right + xy.y * view.up;
    vec3 oc = origin - center;
    float b = dot(oc, dir);
    float disc = b * b - (dot(oc, oc) - radius * radius);
    if (disc < 0.0) discard;
    float root = sqrt(disc);
    // Perspective: the nearer intersection in front of the eye, the farther one when the
    // eye is inside. Orthographic: rays run through the whole scene, t may be negative.
    float t = -b - root;
    if (view.perspective) {
        t = (-b - root > 0.0) ? -b - root : -b + root;
        if (!(t > 0.0)) discard;  // fires when the sphere lies behind the eye
    }
    vec3 hit = origin + t * dir;
    gl_FragDepth = (dot(hit - view.origin, view.forward) - depth_range.x) / (depth_range.y - depth_range.x);
    out_position = vec4(hit, 1.0);
    out_normal = vec4(normalize(hit - center), 0.0);
}
