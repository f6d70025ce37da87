// The hair model's formulas for the GL renderer, term by term as docs/model.md writes them
// and as hairjax/_raster.py, _shading.py and _projection.py compute them in JAX.
// Constants come from the generated include "hairjax_constants" (hairjax/_constants.py).
#include "hairjax_constants"

// §2 / §7: a view maps p to pixel coordinates (x right, y down) and a depth along its axis.
struct View {
    vec3 origin;
    vec3 forward;
    vec3 right;
    vec3 up;
    float focal;
    vec2 center;
    float near;
    bool perspective;
};

vec3 project(View v, vec3 p) {
    vec3 rel = p - v.origin;
    float z = dot(rel, v.forward);
    vec2 lateral = vec2(dot(rel, v.right), dot(rel, v.up));
    // Points at or behind the eye belong to culled segments; the max keeps this finite.
    if (v.perspective) lateral /= max(z, v.near);
    return vec3(v.center.x + v.focal * lateral.x, v.center.y - v.focal * lateral.y, z);
}

// §5: overlap of a unit pixel box at distance d from the ribbon axis with width w.
float ribbon_coverage(float d, float w) {
    float half_w = 0.5 * w;
    return clamp(min(d + PIXEL_HALF_EXTENT, half_w) - max(d - PIXEL_HALF_EXTENT, -half_w), 0.0, 1.0);
}

// §5: depth at t along a segment, perspective-correct (1/z linear) or linear.
float fragment_depth(float z0, float z1, float t, bool perspective) {
    if (!perspective) return z0 + t * (z1 - z0);
    // Constant-depth segments keep z exactly (as in JAX, no rounding in 1/(1/z)).
    if (z0 == z1) return z0;
    return 1.0 / ((1.0 - t) / z0 + t / z1);
}

// ‖x‖; fires for zero vectors (T ∥ L in ‖T × L‖, zero tangents): SAFE_NORM_EPS² is 0 in float32.
float safe_norm(vec3 x) {
    float sq = dot(x, x);
    return sq > SAFE_NORM_EPS * SAFE_NORM_EPS ? sqrt(sq) : 0.0;
}

// §8: max(b, 0)^p; fires at b ≤ SPECULAR_BASE_EPS (the cone's far side): exactly 0, no log(b ≤ 0).
float specular_power(float b, float p) {
    return b > SPECULAR_BASE_EPS ? exp(p * log(b)) : 0.0;
}

struct Shading {
    vec3 kd;
    vec3 ks;
    vec3 ambient;
    float shininess;
    float kappa;
    int model;  // SHADING_KAJIYA_KAY or SHADING_KAJIYA_KAY_MIRROR
};

// §8: ambient·c + τ·light·(Kd sin(T, L)·c + Ks·max(b, 0)^p).
vec3 shade_point(Shading s, vec3 T, vec3 L, vec3 V, vec3 base, vec3 light_rgb, float tau) {
    float tl = dot(T, L);
    float tv = dot(T, V);
    float sin_tl = safe_norm(cross(T, L));
    float sin_tv = safe_norm(cross(T, V));
    float b = (s.model == SHADING_KAJIYA_KAY) ? tl * tv + sin_tl * sin_tv
                                              : sin_tl * sin_tv - tl * tv;
    vec3 diffuse = s.kd * sin_tl;
    vec3 specular = s.ks * specular_power(b, s.shininess);
    return s.ambient * base + tau * light_rgb * (diffuse * base + specular);
}

// §7: the slice of depth z, (z − D₀)·N/span clamped to [0, N] (fires by float32 rounding at D₀, D_N).
int slice_of(float z, float zmin, float span, int maps) {
    return int(clamp(floor((z - zmin) * float(maps) / span), 0.0, float(maps)));
}
