// scatter::moments: the moment basis of the prefiltered family (Peters et al. 2016, "Beyond
// Hard Shadows: Moment Shadow Maps for Single Scattering, Soft Shadows and Translucent
// Occluders"): power moments of the rectified depth, and a region's lit fraction
// reconstructed from them by the moment problem's bounds (4 moments: Hamburger 4MSM, Peters &
// Klein 2015; 6 moments: a cubic).
//
// The math. A region's texels up to a column, weighted, are a distribution of occluder depths
// z in [-1, 1] (`moment_z`: the depth mapped from the region's whole depth range, so that
// every region's moments use the full interval); the prefilter stores its power moments b_k = E[z^k], k = 1..2n
// (n = 2 or 3). A ray at depth zf is lit where z >= zf, so the region's visibility is
// 1 - P(z < zf). Among all distributions with these moments, P(z < zf) is least and greatest
// for the one with n + 1 atoms, one at zf (the canonical representation): the others are the
// roots of the kernel polynomial c . (1, z, .., z^n), B c = (1, zf, .., zf^n), B the Hankel
// matrix of the moments; the atom at zf weighs w_f = 1 / (u^T B^-1 u). The lower bound L sums
// the weights of the atoms below zf, the upper adds w_f; the estimate is
// V = 1 - L - MOMENT_SPLIT w_f (the midpoint of the bounds: the least worst-case error).
//
// Stability: the moments are mixed with those of the uniform distribution on [-1, 1]
// (MOMENT_BIAS_4, MOMENT_BIAS_6), which keeps B positive definite where a region's depths
// take fewer than n + 1 values and against f32 rounding in the running mean; an atom beyond
// FAR_ROOT is at infinity (weight 0), and the atom weights are written so that a far atom
// does not cancel the near ones.
//
// Composed into kernels by naga_oil (`#import scatter::moments::{...}`); plain WGSL, not an
// askama template. Mirrored line by line by reference/src/kernels/common_moments.rs.

#define_import_path scatter::moments

#import scatter::model::PI

// The fraction of the uniform distribution on [-1, 1] mixed into 4 moments.
const MOMENT_BIAS_4: f32 = 3e-5f;
// The fraction of the uniform distribution on [-1, 1] mixed into 6 moments.
const MOMENT_BIAS_6: f32 = 3e-4f;
// The share of the atom at the ray's depth counted as shadow (0: the upper bound on
// visibility, 1: the lower).
const MOMENT_SPLIT: f32 = 0.5f;
// A root of the kernel polynomial this far out (in z) is an atom at infinity.
const FAR_ROOT: f32 = 1e4f;

// The least depth range `moment_z` stretches to [-1, 1]: a narrower region's depths fill
// [-w / MOMENT_RANGE_FLOOR, w / MOMENT_RANGE_FLOOR] of it, so the map's rounding grows at
// most 20-fold (accuracy as without a floor down to 0.1; see the mirror).
const MOMENT_RANGE_FLOOR: f32 = 0.1f;

// The moment coordinate of a normalised depth `d` in a region whose depths span
// `range` = (least, greatest): z = (2 d - least - greatest) / max(greatest - least,
// MOMENT_RANGE_FLOOR), so the region's depths fill [-1, 1]. With z = 2 d - 1 over the whole
// map a region's depths filled a fraction of the interval, where the bias below and f32
// rounding blurred them: 6 moments, 8 regions, mean rel L1 over the 24 suite poses
// 1.38 -> 1.10 %, window/ordinary 8.01 -> 4.34 % (`prefiltered_truth`, 320x180).
fn moment_z(d: f32, range: vec2<f32>) -> f32 {
    return (2.0 * d - (range.x + range.y)) / max(range.y - range.x, MOMENT_RANGE_FLOOR);
}

// Layer `layer` of the power moments of z: (z, z^2, z^3, z^4) (layer 0) or (z^5, z^6, 0, 0).
fn moment_layer(z: f32, layer: u32) -> vec4<f32> {
    let z2 = z * z;
    let z4 = z2 * z2;
    if layer == 0u {
        return vec4<f32>(z, z2, z2 * z, z4);
    }
    return vec4<f32>(z4 * z, z4 * z2, 0.0, 0.0);
}

// The first four moments mixed with a share `a` of the uniform distribution on [-1, 1]'s
// (0, 1/3, 0, 1/5).
fn biased4(raw: vec4<f32>, a: f32) -> vec4<f32> {
    return vec4<f32>(raw.x * (1.0 - a), raw.y * (1.0 - a) + a / 3.0, raw.z * (1.0 - a), raw.w * (1.0 - a) + a / 5.0);
}

// Weight of atom x of a distribution with atoms {x, u, far} and moments (1, b1, b2):
// (E[z - u] + E[(z - u)(z - x)] k) / (x - u), k = 1 / (x - far) (0 for an atom at infinity).
fn atom_weight2(b1: f32, b2: f32, x: f32, u: f32, k: f32) -> f32 {
    let e1 = b1 - u;
    let e2 = b2 - b1 * (u + x) + u * x;
    return (e1 + e2 * k) / (x - u);
}

// Weight of atom x of a distribution with atoms {x, u, v, far} and moments (1, b1, b2, b3):
// (E[(z - u)(z - v)] + E[(z - u)(z - v)(z - x)] k) / ((x - u)(x - v)), k = 1 / (x - far).
fn atom_weight3(b1: f32, b2: f32, b3: f32, x: f32, u: f32, v: f32, k: f32) -> f32 {
    let s = u + v;
    let p = u * v;
    let e2 = b2 - b1 * s + p;
    let e3 = b3 - b2 * (s + x) + b1 * (p + s * x) - p * x;
    return (e2 + e3 * k) / ((x - u) * (x - v));
}

// x with the sign of s (s >= 0: positive).
fn sign_of(x: f32, s: f32) -> f32 {
    return select(-x, x, s >= 0.0);
}

// q, or the smallest normal f32 where q is 0 (the quadratic formula divides by it).
fn nonzero(q: f32) -> f32 {
    return select(q, 1.17549435e-38f, q == 0.0);
}

// 1 / (x - far), or 0 where far is an atom at infinity.
fn far_k(x: f32, far: f32, at_infinity: bool) -> f32 {
    if at_infinity {
        return 0.0;
    }
    return 1.0 / (x - far);
}

// The lit fraction at depth zf of a region with 4 moments `raw` (Hamburger 4MSM).
fn lit_moments4(raw: vec4<f32>, zf: f32) -> f32 {
    let b = biased4(raw, MOMENT_BIAS_4);
    let b1 = b.x;
    let b2 = b.y;
    let b3 = b.z;
    let b4 = b.w;
    // LDL^T of the Hankel matrix [[1, b1, b2], [b1, b2, b3], [b2, b3, b4]].
    let d2 = b2 - b1 * b1;
    let l32 = (b3 - b1 * b2) / d2;
    let d3 = b4 - b2 * b2 - l32 * l32 * d2;
    // L y = (1, zf, zf^2); the weight of the atom at zf is 1 / (y^T D^-1 y).
    let y2 = zf - b1;
    let y3 = zf * zf - b2 - l32 * y2;
    let wf = 1.0 / (1.0 + y2 * y2 / d2 + y3 * y3 / d3);
    // c = L^-T D^-1 y: the kernel polynomial c1 + c2 z + c3 z^2.
    let c3 = y3 / d3;
    let c2 = y2 / d2 - l32 * c3;
    let c1 = 1.0 - b1 * c2 - b2 * c3;
    // Its roots: the stable quadratic formula; with |c3| tiny one root is at infinity.
    let disc = max(c2 * c2 - 4.0 * c1 * c3, 0.0);
    let q = nonzero(-0.5 * (c2 + sign_of(sqrt(disc), c2)));
    let near = c1 / q;
    let at_infinity = abs(c3) * FAR_ROOT <= abs(q);
    var far = 0.0;
    if !at_infinity {
        far = q / c3;
    }
    // The lower bound on P(z < zf): the weights of the atoms below zf.
    var shadow = 0.0;
    if near < zf {
        shadow += atom_weight2(b1, b2, near, zf, far_k(near, far, at_infinity));
    }
    if !at_infinity && far < zf {
        shadow += atom_weight2(b1, b2, far, zf, 1.0 / (far - near));
    }
    return clamp(1.0 - shadow - MOMENT_SPLIT * wf, 0.0, 1.0);
}

// The real roots of c1 + c2 z + c3 z^2 + c4 z^3, the largest in magnitude last (.z), and
// whether it is at infinity (|c4| negligible: then .x, .y are the quadratic's roots).
// The root of largest magnitude from the trigonometric solution of the monic cubic, polished
// by two Newton steps; the other two from the deflated quadratic.
struct CubicRoots {
    r: vec3<f32>,
    at_infinity: bool,
}

fn cubic_roots(c1: f32, c2: f32, c3: f32, c4: f32) -> CubicRoots {
    if abs(c4) * FAR_ROOT <= abs(c3) {
        let disc = max(c2 * c2 - 4.0 * c1 * c3, 0.0);
        let q = nonzero(-0.5 * (c2 + sign_of(sqrt(disc), c2)));
        return CubicRoots(vec3<f32>(c1 / q, q / c3, 0.0), true);
    }
    let a = c3 / c4;
    let b = c2 / c4;
    let c = c1 / c4;
    let p = min(b - a * a / 3.0, -1e-12);
    let qq = 2.0 * a * a * a / 27.0 - a * b / 3.0 + c;
    let m = 2.0 * sqrt(-p / 3.0);
    let theta = acos(clamp(3.0 * qq / (p * m), -1.0, 1.0)) / 3.0;
    // The root of largest magnitude: the greatest or the least of the trigonometric
    // solution (theta in [0, pi / 3]: k = 0 and k = 2), polished by Newton's method.
    let greatest = m * cos(theta) - a / 3.0;
    let least = m * cos(theta - 4.0 * PI / 3.0) - a / 3.0;
    var z = select(least, greatest, abs(greatest) >= abs(least));
    for (var i = 0u; i < 2u; i++) {
        let f = c1 + z * (c2 + z * (c3 + z * c4));
        let df = c2 + z * (2.0 * c3 + 3.0 * z * c4);
        if df != 0.0 {
            z -= f / df;
        }
    }
    // The other two: the polynomial divided by (z - big) from the constant term up (stable
    // for the root of largest magnitude), then the stable quadratic formula. Taken from the
    // trigonometric solution instead, roots near zero are differences of terms of the big
    // root's size: with a far root (604 on a conformance fixture) lavapipe's cos and acos
    // put one of them elsewhere and the GPU and the CPU were 7 % apart at a pixel.
    let big = nonzero(z);
    let q0 = -c1 / big;
    let q1 = (q0 - c2) / big;
    let q2 = (q1 - c3) / big;
    let disc = max(q1 * q1 - 4.0 * q0 * q2, 0.0);
    let q = nonzero(-0.5 * (q1 + sign_of(sqrt(disc), q1)));
    return CubicRoots(vec3<f32>(q0 / q, q / nonzero(q2), big), false);
}

// The lit fraction at depth zf of a region with 6 moments raw0 = (b1, b2, b3, b4),
// raw1 = (b5, b6) (the canonical representation with four atoms).
fn lit_moments6(raw0: vec4<f32>, raw1: vec2<f32>, zf: f32) -> f32 {
    let a = MOMENT_BIAS_6;
    let b = biased4(raw0, a);
    let b1 = b.x;
    let b2 = b.y;
    let b3 = b.z;
    let b4 = b.w;
    let b5 = raw1.x * (1.0 - a);
    let b6 = raw1.y * (1.0 - a) + a / 7.0;
    // LDL^T of the 4x4 Hankel matrix of (1, b1, .., b6).
    let d2 = b2 - b1 * b1;
    let l32 = (b3 - b1 * b2) / d2;
    let l42 = (b4 - b1 * b3) / d2;
    let d3 = b4 - b2 * b2 - l32 * l32 * d2;
    let l43 = (b5 - b2 * b3 - l42 * l32 * d2) / d3;
    let d4 = b6 - b3 * b3 - l42 * l42 * d2 - l43 * l43 * d3;
    // L y = (1, zf, zf^2, zf^3) and the weight of the atom at zf.
    let y2 = zf - b1;
    let y3 = zf * zf - b2 - l32 * y2;
    let y4 = zf * zf * zf - b3 - l42 * y2 - l43 * y3;
    let wf = 1.0 / (1.0 + y2 * y2 / d2 + y3 * y3 / d3 + y4 * y4 / d4);
    // The kernel polynomial c1 + c2 z + c3 z^2 + c4 z^3 and its roots.
    let c4 = y4 / d4;
    let c3 = y3 / d3 - l43 * c4;
    let c2 = y2 / d2 - l32 * c3 - l42 * c4;
    let c1 = 1.0 - b1 * c2 - b2 * c3 - b3 * c4;
    let roots = cubic_roots(c1, c2, c3, c4);
    let r = roots.r;
    let at_infinity = roots.at_infinity;
    // The lower bound on P(z < zf): the weights of the atoms below zf; each near atom's
    // weight treats r.z (the largest in magnitude) as the far one.
    var shadow = 0.0;
    if r.x < zf {
        shadow += atom_weight3(b1, b2, b3, r.x, zf, r.y, far_k(r.x, r.z, at_infinity));
    }
    if r.y < zf {
        shadow += atom_weight3(b1, b2, b3, r.y, zf, r.x, far_k(r.y, r.z, at_infinity));
    }
    if !at_infinity && r.z < zf {
        shadow += atom_weight3(b1, b2, b3, r.z, zf, r.x, 1.0 / (r.z - r.y));
    }
    return clamp(1.0 - shadow - MOMENT_SPLIT * wf, 0.0, 1.0);
}
