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

// x / ‖x‖, and 0 for x = 0 (a direction that does not exist contributes nothing).
vec3 safe_normalize(vec3 x) {
    float n = safe_norm(x);
    return x / (n > 0.0 ? n : 1.0);  // fires for zero vectors: the result is 0
}

// log(1 + x) for x > −1, to a few ulps relative: GLSL has no log1p. Not the classic
// log(u)·x/(u − 1), u = 1 + x (Goldberg 1991, Thm 4): it needs log(u) to ½ ulp, but GLSL
// bounds log's error on [0.5, 2] only absolutely (2⁻²¹), and llvmpipe's log(u) just below 1
// errs by ~ulp(1): 10⁵ ulps of log1p(−10⁻⁶), measured. So for −½ < x < 1 (|z| < ⅓):
// log1p(x) = 2 atanh(z), z = x/(2 + x), by its odd series to z¹⁵ (truncation < z¹⁶/17·9/8
// < 2·10⁻⁹ relative; x below ulp(1)/2 needs no special case: z = x/2 then). Fires for x ≤ −½
// or x ≥ 1: there 1 + x is exact (Sterbenz) or |log(1 + x)| ≥ log 2, and plain log is accurate.
float log1p_accurate(float x) {
    if (x <= -0.5 || x >= 1.0) return log(1.0 + x);
    float z = x / (2.0 + x);
    float z2 = z * z;
    float series = 1.0 + z2 * (1.0 / 3.0 + z2 * (1.0 / 5.0 + z2 * (1.0 / 7.0 + z2 * (1.0 / 9.0
                 + z2 * (1.0 / 11.0 + z2 * (1.0 / 13.0 + z2 * (1.0 / 15.0)))))));
    return 2.0 * z * series;
}

// §8: max(b, 0)^p from gap = 1 − b (kajiya_kay_gap); fires at b ≤ SPECULAR_BASE_EPS (the
// cone's far side): exactly 0, no log1p(−gap ≤ −1).
float specular_power(float gap, float p) {
    return 1.0 - gap > SPECULAR_BASE_EPS ? exp(p * log1p_accurate(-gap)) : 0.0;
}

// §8: 1 − b without cancellation (b^p's condition number in b is p). θ_L, θ_V: the angles of
// L and V to T. kajiya-kay: b = cos(θ_L − θ_V), mirror: b = −cos(θ_L + θ_V); both 1 − b =
// s²/(1 + b) with s = sin(θ_L ∓ θ_V) = sin θ_L cos θ_V ∓ cos θ_L sin θ_V (as _shading.py).
// Fires at b ≤ 0 (power 0 there): 1 − b ≥ 1 directly, so 1 + b → 0 at b = −1 never divides.
float kajiya_kay_gap(int model, float tl, float tv, float sin_tl, float sin_tv) {
    bool seed = model == SHADING_KAJIYA_KAY;
    float b = seed ? tl * tv + sin_tl * sin_tv : sin_tl * sin_tv - tl * tv;
    float s = seed ? sin_tl * tv - tl * sin_tv : sin_tl * tv + tl * sin_tv;
    return b > 0.0 ? s * s / (1.0 + b) : 1.0 - b;
}

struct Shading {
    vec3 kd;
    vec3 ks;
    vec3 ambient;
    float shininess;
    float kappa;
    int model;  // SHADING_KAJIYA_KAY, SHADING_KAJIYA_KAY_MIRROR, SHADING_KAJIYA_KAY_LOOKUP (§14) or SHADING_SCHEUERMANN (§17)
};

// §8: ambient·c + τ·light·(Kd sin(T, L)·c + Ks·max(b, 0)^p).
vec3 shade_point(Shading s, vec3 T, vec3 L, vec3 V, vec3 base, vec3 light_rgb, float tau) {
    float tl = dot(T, L);
    float tv = dot(T, V);
    float sin_tl = safe_norm(cross(T, L));
    float sin_tv = safe_norm(cross(T, V));
    vec3 diffuse = s.kd * sin_tl;
    vec3 specular = s.ks * specular_power(kajiya_kay_gap(s.model, tl, tv, sin_tl, sin_tv), s.shininess);
    return s.ambient * base + tau * light_rgb * (diffuse * base + specular);
}

// §14: Kajiya-Kay's (sin θ_L, max(b, 0)^p) read from the lookup table (hairjax/_lookup.py)
// at ((L·T + 1)/2, (V·T + 1)/2) with LINEAR filtering and CLAMP_TO_EDGE, level 0; then as
// shade_point. Fires for zero vectors (§1: a zero tangent, a point light at the point): no
// diffuse without T and L, no highlight without V too, as in §8 (the table reads 1 at u = ½).
vec3 shade_point_lookup(Shading s, sampler2D table, vec3 T, vec3 L, vec3 V, vec3 base,
                        vec3 light_rgb, float tau) {
    vec2 terms = textureLod(table, 0.5 * (1.0 + vec2(dot(L, T), dot(V, T))), 0.0).rg;
    bool lit = dot(T, T) > 0.0 && dot(L, L) > 0.0;
    float sin_tl = lit ? terms.x : 0.0;
    float spec = lit && dot(V, V) > 0.0 ? terms.y : 0.0;
    return s.ambient * base + tau * light_rgb * (s.kd * sin_tl * base + s.ks * spec);
}

// §16: H(y) = ∫₀^y g, g the periodic linear interpolant of the streak texture in texel units;
// texel k of `streak` holds (N_{k mod m}, P_k), P the running integral (hairjax/_streaks.py).
float streak_antiderivative(sampler2D streak, int m, float y) {
    float k = floor(y);
    float f = y - k;
    float q = floor(k / float(m));
    // r = K mod m; the clamp fires only if float rounding of K/m puts r at m.
    int r = int(clamp(k - q * float(m), 0.0, float(m - 1)));
    float n0 = texelFetch(streak, ivec2(r, 0), 0).x;
    float n1 = texelFetch(streak, ivec2((r + 1) % m, 0), 0).x;
    return q * texelFetch(streak, ivec2(m, 0), 0).y + texelFetch(streak, ivec2(r, 0), 0).y
         + f * n0 + 0.5 * f * f * (n1 - n0);
}

// §16: the streak texture's mean over [u, u + width] (a hair's span across its ribbon).
float streak_factor(sampler2D streak, int m, float u, float width) {
    float a = u * float(m) - 0.5;
    float b = (u + width) * float(m) - 0.5;
    return (streak_antiderivative(streak, m, b) - streak_antiderivative(streak, m, a)) / (width * float(m));
}

// §7: the slice of depth z, (z − D₀)·N/span clamped to [0, N] (fires by float32 rounding at D₀, D_N).
int slice_of(float z, float zmin, float span, int maps) {
    return int(clamp(floor((z - zmin) * float(maps) / span), 0.0, float(maps)));
}

// §7 deep opacity maps: u = (z − z₀)·K/(KΔ), the depth behind a texel's first hair z₀ in
// layers (hairjax/_geometry/_shadows/_deep.py's layer_coordinate, term by term).
float deep_layer_coordinate(float z, float z0, int layers, float depth_range) {
    return (z - z0) * float(layers) / depth_range;
}

// docs/model.md §7: the transmittance τ = exp(−κΩ) through the opacity Ω in front of a point.
float transmittance(float kappa, float omega) {
    return exp(-kappa * omega);
}

// §17 Scheuermann (scheuermann-2004 slides 10–12), as hairjax/_scheuermann.py.
struct Scheuermann {
    vec3 kd;
    vec3 ambient;
    vec3 primary_color;
    vec3 secondary_color;
    float primary_exponent;
    float secondary_exponent;
    float primary_shift;
    float secondary_shift;
};

// normalize(T + shift·N): N ⟂ T, both unit (or both 0), so |T + shift·N| = √(1 + shift²).
vec3 shift_tangent(vec3 T, vec3 N, float shift) {
    return (T + shift * N) / sqrt(1.0 + shift * shift);
}

// smoothstep(−1, 0, x) written out (as _scheuermann.py), t = clamp(x + 1, 0, 1).
float smoothstep_attenuation(float x) {
    float t = clamp(x + 1.0, 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// smoothstep(−1, 0, T·H)·sin(T, H)^p, the power from the gap 1 − sin = cos²/(1 + sin).
// Fires where T or H is the zero vector (no tangent; L = −V): cos² + sin² = 0, power 0.
float strand_specular(vec3 T, vec3 H, float p) {
    float c = dot(T, H);
    float s = safe_norm(cross(T, H));
    float gap = c * c + s * s > 0.5 ? c * c / (1.0 + s) : 1.0;
    return smoothstep_attenuation(c) * specular_power(gap, p);
}

// saturate(lerp(0.25, 1, N·L)); fires at points without tangent (N = 0): ambient only.
float scheuermann_diffuse(vec3 N, vec3 L) {
    float wrapped = clamp(SCHEUERMANN_DIFFUSE_FLOOR + (1.0 - SCHEUERMANN_DIFFUSE_FLOOR) * dot(N, L), 0.0, 1.0);
    return dot(N, N) > 0.5 ? wrapped : 0.0;
}

// §17: c·(ambient + τ·light·(Kd·D + C₁·S(T₁) + m·C₂·S(T₂))), c = colour·base(u)·AO.
vec3 shade_scheuermann(Scheuermann s, vec3 T, vec3 N, vec3 L, vec3 V, float shift, float mask,
                       vec3 base, vec3 light_rgb, float tau) {
    vec3 diffuse = s.kd * scheuermann_diffuse(N, L);
    vec3 LV = L + V;
    float n = safe_norm(LV);
    vec3 H = LV / (n > 0.0 ? n : 1.0);  // fires for L = −V: H = 0, no highlight
    vec3 t1 = shift_tangent(T, N, s.primary_shift + shift);
    vec3 t2 = shift_tangent(T, N, s.secondary_shift + shift);
    vec3 specular = s.primary_color * strand_specular(t1, H, s.primary_exponent)
                  + s.secondary_color * (mask * strand_specular(t2, H, s.secondary_exponent));
    return base * (s.ambient + tau * light_rgb * (diffuse + specular));
}

// §19 marschner: Karis's R/TT/TRT factorisation with Chiang et al. 2016's lobe variances
// and tilt, as hairjax/_shading/_marschner_lobes.py, term by term (fibre_angles,
// longitudinal_arguments, azimuthal_lobes, marschner_lobes); dual scattering as
// _dual_scattering.py's dual_terms. The host computes what depends on the parameters
// alone with the JAX functions (hairjax/_shading/_marschner.py, `gl_uniforms`, `gl_table`).
struct Marschner {
    vec3 sigma_a;     // absorption(params): σ_a per unit fibre radius, from melanin
    vec3 widths;      // lobe_widths(β_m): the Gaussians' standard deviations (R, TT, TRT)
    vec4 tilts;       // k·α in radians, k from TILT_MULTIPLES (R, TT, TRT, the remainder)
    vec3 weight_r;
    vec3 weight_tt;
    vec3 weight_trt;
    bool dual;                // multiple_scattering = "dual": the tables are bound
    float density_forward;    // Zinke et al. 2008's d_f
    float density_back;       // and d_b
};

// Unpolarised Fresnel reflectance from air at cosine cos_i onto the fibre (index HAIR_ETA).
float fresnel_dielectric(float cos_i) {
    // Fires where cos_i rounds above 1 (unit vectors off by an ulp); 1 − cos² ≥ 0 then.
    cos_i = clamp(cos_i, 0.0, 1.0);
    // cos_t ≥ √(1 − 1/η²) > 0: no guard needed, and the denominators are ≥ η·cos_t > 0.
    float cos_t = sqrt(1.0 - (1.0 - cos_i * cos_i) / (HAIR_ETA * HAIR_ETA));
    float r_s = (cos_i - HAIR_ETA * cos_t) / (cos_i + HAIR_ETA * cos_t);
    float r_p = (HAIR_ETA * cos_i - cos_t) / (HAIR_ETA * cos_i + cos_t);
    return 0.5 * (r_s * r_s + r_p * r_p);
}

// √max(x, 0): fires at the end of a range (cos θ_d = 0, h = 1), where rounding may give x < 0.
float safe_sqrt(float x) {
    return x > 0.0 ? sqrt(x) : 0.0;
}

// Karis's M_p: the normal density g(std; x) (std > 0: β_m > 0 is checked on input).
vec3 lobe_gaussian(vec3 std, vec3 x) {
    vec3 z = x / std;
    return exp(-0.5 * z * z) / (sqrt(2.0 * acos(-1.0)) * std);
}

// sin(θ + angle) from sin θ and cos θ (the scales' tilt).
float tilted(float sin_t, float cos_t, float angle) {
    return sin_t * cos(angle) + cos_t * sin(angle);
}

struct FibreAngles {
    float sin_l, sin_v, cos_l, cos_v, cos_d, cos_phi, cos_half;
};

// sin θ and cos θ of L and V, cos θ_d, cos φ and cos(φ/2), finite for zero vectors and for
// L or V along the fibre.
FibreAngles fibre_angles(vec3 T, vec3 L, vec3 V) {
    FibreAngles a;
    a.sin_l = dot(T, L);
    a.sin_v = dot(T, V);
    a.cos_l = safe_norm(cross(T, L));
    a.cos_v = safe_norm(cross(T, V));
    // cos θ_d = √((1 + cos(θ_V − θ_L))/2), without asin at ±1; the argument is 0 only for
    // L and V along the fibre, opposite.
    a.cos_d = safe_sqrt(0.5 * (1.0 + a.cos_l * a.cos_v + a.sin_l * a.sin_v));
    // φ from the projections on the normal plane; cos(φ/2) = ‖L̂p + V̂p‖/2, not √(½ + ½cos φ)
    // (infinite derivative at φ = π). A projection is 0 for L or V along the fibre: then
    // cos φ = 0 and cos(φ/2) = ½.
    vec3 lp = safe_normalize(L - a.sin_l * T);
    vec3 vp = safe_normalize(V - a.sin_v * T);
    a.cos_phi = dot(lp, vp);
    a.cos_half = 0.5 * safe_norm(lp + vp);
    return a;
}

// The arguments of M_R, M_TT, M_TRT and the remainder's M: sin θ_L + sin(θ_V + kα).
vec4 longitudinal_arguments(FibreAngles a, vec4 tilts) {
    return vec4(a.sin_l + tilted(a.sin_v, a.cos_v, tilts.x), a.sin_l + tilted(a.sin_v, a.cos_v, tilts.y),
                a.sin_l + tilted(a.sin_v, a.cos_v, tilts.z), a.sin_l + tilted(a.sin_v, a.cos_v, tilts.w));
}

// e^{−σ_a·2 cos γ_t / cos θ_t}: absorption along the path through the fibre at offset h.
vec3 fibre_transmittance(vec3 sigma_a, float h, float a, float cos_t) {
    float cos_gamma_t = sqrt(1.0 - (h * a) * (h * a));  // h·a ≤ 1/η < 1
    return exp(-sigma_a * (2.0 * cos_gamma_t / cos_t));
}

// A_p·N_p of R (n_r), TT, TRT and the TRT remainder (uniform, A_3+/(2π)) at θ_d and φ.
void azimuthal_lobes(FibreAngles g, vec3 sigma_a, out float n_r, out vec3 n_tt, out vec3 n_trt,
                     out vec3 n_rest) {
    // a = 1/η' = cos θ_d / √(η² − sin²θ_d): no division by cos θ_d, 0 at grazing
    // incidence; η² − sin²θ_d ≥ η² − 1 > 0.
    float a = g.cos_d / sqrt(HAIR_ETA * HAIR_ETA - 1.0 + g.cos_d * g.cos_d);
    // cos θ_t = √(1 − sin²θ_d/η²) ≥ √(1 − 1/η²) > 0.
    float cos_t = sqrt(1.0 - (1.0 - g.cos_d * g.cos_d) / (HAIR_ETA * HAIR_ETA));

    n_r = 0.25 * g.cos_half * fresnel_dielectric(g.cos_d * g.cos_half);

    float h_tt = g.cos_half * (1.0 + a * (KARIS_TT[0] - KARIS_TT[1] * g.cos_phi));
    float f_tt = fresnel_dielectric(g.cos_d * safe_sqrt(1.0 - h_tt * h_tt));
    float d_tt = exp(-KARIS_TT[2] * g.cos_phi - KARIS_TT[3]);
    n_tt = (1.0 - f_tt) * (1.0 - f_tt) * fibre_transmittance(sigma_a, h_tt, a, cos_t) * d_tt;

    float f_trt = fresnel_dielectric(g.cos_d * sqrt(1.0 - HAIR_TRT_OFFSET * HAIR_TRT_OFFSET));
    vec3 t_trt = fibre_transmittance(sigma_a, HAIR_TRT_OFFSET, a, cos_t);
    vec3 a_trt = (1.0 - f_trt) * (1.0 - f_trt) * f_trt * t_trt * t_trt;
    float d_trt = exp(KARIS_TRT[0] * g.cos_phi - KARIS_TRT[1]);
    vec3 series = 1.0 - f_trt * t_trt;
    // Fires only where f·T → 1 (grazing and no absorption); the remainder is 0 there.
    bvec3 ok = greaterThan(series, vec3(HAIR_SERIES_EPS));
    vec3 a_rest = mix(vec3(0.0), a_trt * f_trt * t_trt / mix(vec3(1.0), series, ok), ok);
    n_trt = a_trt * d_trt;
    n_rest = a_rest / (2.0 * acos(-1.0));
}

// (R, TT, TRT): π·M_p·N_p of each lobe at a point; R has no colour. Zero vectors (no
// tangent, a point light at the point) give finite values; τ·light·… is 0 there through L.
void marschner_lobes(Marschner m, vec3 T, vec3 L, vec3 V, out float r, out vec3 tt, out vec3 trt) {
    FibreAngles g = fibre_angles(T, L, V);
    vec4 args = longitudinal_arguments(g, m.tilts);
    float m_r = lobe_gaussian(vec3(m.widths.x), vec3(args.x)).x;
    float m_tt = lobe_gaussian(vec3(m.widths.y), vec3(args.y)).x;
    float m_trt = lobe_gaussian(vec3(m.widths.z), vec3(args.z)).x;
    float m_rest = lobe_gaussian(vec3(m.widths.z), vec3(args.w)).x;
    float n_r;
    vec3 n_tt, n_trt, n_rest;
    azimuthal_lobes(g, m.sigma_a, n_r, n_tt, n_trt, n_rest);
    float pi = acos(-1.0);
    r = pi * m_r * n_r;
    tt = pi * m_tt * n_tt;
    trt = pi * (m_trt * n_trt + m_rest * n_rest);
}

// §19 dual scattering's tables (Marschner.gl_table packs them): texel (j, row) holds a
// table's RGB at the light's j-th sin θ; rows: ā_f, β̄_f², A_b, Δ_b, σ_b, the shares
// a_b^p/ā_b of R, TT, TRT, then N^G_p at the k-th cos φ in row DUAL_N_G + 3k + p.
const int DUAL_A_F = 0;
const int DUAL_VAR_F = 1;
const int DUAL_A_BACK = 2;
const int DUAL_SHIFT_BACK = 3;
const int DUAL_STD_BACK = 4;
const int DUAL_SHARE = 5;
const int DUAL_N_G = 8;

// Index and weight of x's cell on the uniform grid of n nodes on [lo, 1]; the clamp fires
// only for sin θ or cos φ an ulp outside [−1, 1].
void grid_cell(float x, float lo, int n, out int i, out float w) {
    float t = clamp((x - lo) / (1.0 - lo) * float(n - 1), 0.0, float(n - 1));
    float fi = min(floor(t), float(n - 2));
    i = int(fi);
    w = t - fi;
}

// Row `row` of the tables, linear in the light's sin θ between columns i and i + 1.
vec3 dual_at(sampler2D tables, int row, int i, float w) {
    return (1.0 - w) * texelFetch(tables, ivec2(i, row), 0).rgb + w * texelFetch(tables, ivec2(i + 1, row), 0).rgb;
}

// Dual scattering at a point (Zinke et al. 2008, as _dual_scattering.py's dual_terms), per
// lobe: `direct` (τ multiplies it with the lobes) d_b·share_p·2A_b·g(σ_b; x − Δ_b), and
// `scattered` (τ does not) Ψ·(π·M^G_p·N^G_p + π·d_b·share_p·2A_b·g(√(σ_b² + σ_f²); x − Δ_b)),
// with count n fibres in front toward the light.
void dual_terms(Marschner m, sampler2D tables, vec3 T, vec3 L, vec3 V, float count,
                out vec3 direct[3], out vec3 scattered[3]) {
    FibreAngles g = fibre_angles(T, L, V);
    ivec2 size = textureSize(tables, 0);
    int i, k;
    float w, v;
    grid_cell(g.sin_l, -1.0, size.x, i, w);
    grid_cell(g.cos_phi, -1.0, (size.y - DUAL_N_G) / 3, k, v);
    vec3 a_f = dual_at(tables, DUAL_A_F, i, w);
    vec3 var_s = count * dual_at(tables, DUAL_VAR_F, i, w);  // σ_f²
    vec3 a_back = dual_at(tables, DUAL_A_BACK, i, w);
    vec3 shift_back = dual_at(tables, DUAL_SHIFT_BACK, i, w);
    vec3 std_back = dual_at(tables, DUAL_STD_BACK, i, w);
    vec3 x = vec3(g.sin_l + g.sin_v);
    vec3 back = 2.0 * a_back * lobe_gaussian(std_back, x - shift_back);
    vec3 back_s = 2.0 * a_back * lobe_gaussian(sqrt(std_back * std_back + var_s), x - shift_back);
    vec4 args = longitudinal_arguments(g, m.tilts);
    // e^{−n(1−ā_f)} − e^{−n} = e^{−n(1−ā_f)}·(1 − e^{−n·ā_f}), as JAX's: both factors ≤ 1
    // (ā_f < 1), so no overflow deep in the hair (n in the thousands). GLSL has no expm1:
    // 1 − e^{−x} errs by ≤ ulp(1) absolute, < 10⁻⁶ of the light after the factors (the
    // cross-check's is 10⁻⁴).
    vec3 psi = m.density_forward * exp(-count * (1.0 - a_f)) * (1.0 - exp(-count * a_f));
    float pi = acos(-1.0);
    for (int p = 0; p < 3; p++) {
        vec3 share = dual_at(tables, DUAL_SHARE + p, i, w);
        vec3 n_g = (1.0 - v) * dual_at(tables, DUAL_N_G + 3 * k + p, i, w)
                 + v * dual_at(tables, DUAL_N_G + 3 * (k + 1) + p, i, w);
        vec3 m_g = lobe_gaussian(sqrt(m.widths[p] * m.widths[p] + var_s), vec3(args[p]));
        direct[p] = m.density_back * share * back;
        scattered[p] = psi * (pi * m_g * n_g + pi * m.density_back * share * back_s);
    }
}

// §19: ambient + τ·light·(w_R·R + w_TT·TT + w_TRT·TRT) (hairjax/_shading/_stage.py's
// composition; the strands' colour is not read), with dual scattering's direct part added
// to each lobe and its scattered part lit by light·V but not τ (`Reflectance.scattered`).
vec3 shade_marschner(Marschner m, sampler2D tables, vec3 ambient, vec3 T, vec3 L, vec3 V, vec3 light_rgb,
                     float tau, float visibility, float count) {
    float r;
    vec3 lobes[3];
    marschner_lobes(m, T, L, V, r, lobes[1], lobes[2]);
    lobes[0] = vec3(r);
    vec3 weights[3] = vec3[3](m.weight_r, m.weight_tt, m.weight_trt);
    vec3 lit = vec3(0.0);
    vec3 scattered_sum = vec3(0.0);
    if (m.dual) {
        vec3 direct[3], scattered[3];
        dual_terms(m, tables, T, L, V, count, direct, scattered);
        for (int p = 0; p < 3; p++) {
            lobes[p] += direct[p];
            scattered_sum += weights[p] * scattered[p];
        }
    }
    for (int p = 0; p < 3; p++) lit += weights[p] * lobes[p];
    return ambient + tau * light_rgb * lit + visibility * light_rgb * scattered_sum;
}
