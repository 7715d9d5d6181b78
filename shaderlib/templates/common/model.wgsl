// scatter::model: the single-scattering model's terms in f32, as every kernel evaluates them:
// Henyey-Greenstein phase, transmittance integrals of a homogeneous medium, the spot light's
// cone falloff and in-scattering integrand, 4-point Gauss-Legendre nodes, the spot quadrature
// of a ray span and equiangular sampling of a ray.
//
// Composed into kernels by naga_oil (`#import scatter::model::{...}`); plain WGSL, not an
// askama template. Mirrored line by line by reference/src/kernels/common_model.rs.

#define_import_path scatter::model

const PI: f32 = 3.14159265358979323846f;

// Henyey-Greenstein phase function of `cos_theta`.
fn phase_hg(g: f32, cos_theta: f32) -> f32 {
    let denom = max(1.0 + g * g - 2.0 * g * cos_theta, 1e-8);
    return (1.0 - g * g) / (4.0 * PI * denom * sqrt(denom));
}

// `(1 - exp(-sigma_t len)) / sigma_t`, and `len` as `sigma_t len -> 0` (series below 1e-4).
fn transmittance_integral(sigma_t: f32, len: f32) -> f32 {
    let x = sigma_t * len;
    if x < 1e-4 {
        return len * (1.0 - 0.5 * x);
    }
    return (1.0 - exp(-x)) / sigma_t;
}

// `integral_a^b exp(-sigma_t t) dt`.
fn transmittance_between(sigma_t: f32, a: f32, b: f32) -> f32 {
    return exp(-sigma_t * a) * transmittance_integral(sigma_t, b - a);
}

// Smoothstep cone falloff from the cosines of the outer and inner half-angles.
// A hard edge where the two cones coincide. Selected, not branched on: the cosines are
// uniforms, and lavapipe re-specialises a shader branching on uniforms at every dispatch
// (`scatter_shaderlib::uniform_branches`).
fn cone_falloff(cos_angle: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    let x = clamp((cos_angle - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0);
    return select(x * x * (3.0 - 2.0 * x), select(0.0, 1.0, cos_angle >= cos_outer), cos_inner - cos_outer <= 1e-6);
}

// Spot-light integrand `sigma_s p I_cone exp(-sigma_t (d + t)) / d^2` at ray parameter
// `t` (without the light colour), for the view ray `eye + t dir`.
// `medium` = (sigma_t, sigma_s, g, unused), as in the `Frame` uniform.
fn spot_integrand(
    eye: vec3<f32>,
    dir: vec3<f32>,
    t: f32,
    light_pos: vec3<f32>,
    light_dir: vec3<f32>,
    cos_inner: f32,
    cos_outer: f32,
    medium: vec4<f32>,
) -> f32 {
    let x = eye + dir * t;
    let to_x = x - light_pos;
    let d2 = max(dot(to_x, to_x), 1e-12);
    let d = sqrt(d2);
    let travel = to_x / d;
    let cone = cone_falloff(dot(travel, light_dir), cos_inner, cos_outer);
    let p = phase_hg(medium[2], -dot(travel, dir));
    return medium[1] * p * cone * exp(-medium[0] * (d + t)) / d2;
}

// 4-point Gauss-Legendre abscissae on [-1, 1] (ascending). A vector, not an array: naga
// writes a module-scope array constant to HLSL as `static const float X[4] =
// Constructarray4_float_(...)`, and glslang's HLSL front end rejects a function call in a
// static initializer ("Recursion detected", KhronosGroup/glslang#1216); a vector is
// `float4(...)`, which every HLSL compiler takes.
const GL4_X: vec4<f32> = vec4<f32>(-0.8611363f, -0.33998104f, 0.33998104f, 0.8611363f);
// 4-point Gauss-Legendre weights.
const GL4_W: vec4<f32> = vec4<f32>(0.34785485f, 0.65214515f, 0.65214515f, 0.34785485f);

// Unshadowed spot in-scattering over `[a, b]` of the view ray `eye + t dir` (without the
// light colour): `panels` 4-point Gauss-Legendre panels in the angle `gamma` under which the
// lamp sees the ray point. With `t0` the ray's closest approach to the lamp and `h` its
// distance there, `t = t0 + h tan(gamma)` and `dt / d^2 = dgamma / h`: the 1/d^2 peak of a
// ray passing near the lamp becomes flat, and what is left (cone, phase, transmittance) is
// smooth in `gamma`. Quadrature in `t` missed that peak (18.9 % rel L1 for minmax on
// `spot_grate/ordinary`, whose top rows pass 0.3 m from the lamp).
fn spot_span(
    eye: vec3<f32>,
    dir: vec3<f32>,
    a: f32,
    b: f32,
    panels: u32,
    light_pos: vec3<f32>,
    light_dir: vec3<f32>,
    cos_inner: f32,
    cos_outer: f32,
    medium: vec4<f32>,
) -> f32 {
    let t0 = dot(light_pos - eye, dir);
    let h = max(length(eye + dir * t0 - light_pos), 1e-4 * max(b - a, 1e-6));
    let g0 = atan((a - t0) / h);
    let w = (atan((b - t0) / h) - g0) / f32(panels);
    var sum = 0.0;
    // `k + 1u <= panels`: see `span_march` (scatter::epipolar).
    for (var k = 0u; k + 1u <= panels; k++) {
        let mid = g0 + (f32(k) + 0.5) * w;
        for (var q = 0u; q < 4u; q++) {
            let u = tan(mid + 0.5 * w * GL4_X[q]);
            sum += GL4_W[q] * spot_integrand(eye, dir, t0 + h * u, light_pos, light_dir, cos_inner, cos_outer, medium) * (1.0 + u * u);
        }
    }
    return sum * 0.5 * w * h;
}

// Equiangular sampling (Kulla & Fajardo 2012) of `[a, b]` of the view ray `eye + t dir` for a
// point light at `light_pos`, cut into `n` strata of equal angle. With `t0` the ray's closest
// approach to the lamp and `h` its distance there, the lamp sees the ray point
// `t = t0 + h tan(theta)` under the angle `theta` in [`theta_a`, `theta_b`]; samples uniform
// in `theta` have the pdf `h / ((theta_b - theta_a) (h^2 + (t - t0)^2))`, which cancels the
// 1/d^2 peak of the spot integrand. A march uniform in `t` cannot follow that peak: with the
// lamp on screen the pixels next to it overshot the truth 5.6x (issue 12).
struct Equiangular {
    // Closest approach `t0` of the ray to the lamp (naga_oil refuses identifiers that end in
    // a digit).
    t_close: f32,
    // Distance `h` of the lamp from the ray (kept above 1e-4 of the span, as in `spot_span`).
    dist: f32,
    // `theta_a = atan((a - t0) / h)`.
    theta_a: f32,
    // Angle per stratum, `(theta_b - theta_a) / n`.
    dtheta: f32,
}

// The equiangular strata of `[a, b]` (see `Equiangular`).
fn equiangular(eye: vec3<f32>, dir: vec3<f32>, light_pos: vec3<f32>, a: f32, b: f32, n: u32) -> Equiangular {
    let t0 = dot(light_pos - eye, dir);
    let h = max(length(eye + dir * t0 - light_pos), 1e-4 * max(b - a, 1e-6));
    let theta_a = atan((a - t0) / h);
    return Equiangular(t0, h, theta_a, (atan((b - t0) / h) - theta_a) / f32(n));
}

// The sample at stratum position `x` (stratum `k` at offset `u` in [0, 1): `x = k + u`): x = the
// ray parameter `t`, y = its weight `1 / (n pdf(t)) = dtheta h (1 + tan^2 theta)`, so the sum of
// weight times integrand over the `n` strata estimates the integral over `[a, b]`.
fn equiangular_sample(e: Equiangular, x: f32) -> vec2<f32> {
    let tau = tan(e.theta_a + x * e.dtheta);
    return vec2<f32>(e.t_close + e.dist * tau, e.dtheta * e.dist * (1.0 + tau * tau));
}
