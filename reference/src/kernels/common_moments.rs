//! CPU mirror of `shaderlib/templates/common/moments.wgsl` (`scatter::moments`): the moment
//! basis of the prefiltered family (Peters et al. 2016): power moments of the rectified
//! depth, and a region's lit fraction reconstructed from them by the moment problem's
//! bounds (4 moments: Hamburger 4MSM; 6 moments: a cubic). Written line by line like the WGSL.
//!
//! The math. A region's texels up to a column, weighted, are a distribution of occluder
//! depths `z` in `[-1, 1]` ([`moment_z`]: the depth mapped from the region's whole depth
//! range, so that every region's moments use the full interval); the prefilter stores its power moments
//! `b_k = E[z^k]`, `k = 1..=2n` (`n` = 2 or 3). A ray at depth `zf` is lit where `z >= zf`,
//! so the region's visibility is `1 - P(z < zf)`. Among all distributions with these
//! moments, `P(z < zf)` is least and greatest for the one with `n + 1` atoms, one of them at
//! `zf` (the canonical representation): its other atoms are the roots of the polynomial
//! `c . (1, z, .., z^n)` with `B c = (1, zf, .., zf^n)`, `B` the Hankel matrix of the
//! moments, and the atom at `zf` weighs `w_f = 1 / (u^T B^-1 u)`. The lower bound `L` sums
//! the weights of the atoms below `zf`; the upper adds `w_f`. The estimate is
//! `V = 1 - L - MOMENT_SPLIT * w_f`: the atom at `zf` stands for depths on both sides of
//! it, and the midpoint of the bounds is the estimate with the least worst-case error. It
//! also measured best: 6 moments, 8 regions, mean rel L1 over the 24 suite poses 1.43 % at
//! the midpoint, 2.59 % with the atom counted as lit, 2.74 % with it counted as shadow.
//!
//! Stability: the moments are mixed with those of the uniform distribution on `[-1, 1]`
//! (`MOMENT_BIAS_4`, `MOMENT_BIAS_6`), which keeps `B` positive definite when a region's
//! depths take fewer than `n + 1` distinct values and against f32 rounding in the running
//! mean; an atom beyond `FAR_ROOT` is treated as at infinity (weight 0), and the atom
//! weights are written so that a far atom does not cancel the near ones.

use super::common_model::{PI, clamp};

/// The fraction of the uniform distribution on `[-1, 1]` mixed into 4 moments.
pub const MOMENT_BIAS_4: f32 = 3e-5;
/// The fraction of the uniform distribution on `[-1, 1]` mixed into 6 moments.
pub const MOMENT_BIAS_6: f32 = 3e-4;
/// Where between the bounds the estimate lies: the share of the atom at the ray's depth
/// counted as shadow (0: the upper bound on visibility, 1: the lower).
pub const MOMENT_SPLIT: f32 = 0.5;
/// A root of the kernel polynomial this far out (in `z`) is an atom at infinity: its weight
/// is below 1e-4 and its position no longer matters.
pub const FAR_ROOT: f32 = 1e4;

/// The least depth range [`moment_z`] stretches to `[-1, 1]`: a narrower region's depths
/// fill `[-w / MOMENT_RANGE_FLOOR, w / MOMENT_RANGE_FLOOR]` of it, so the map's rounding
/// (the GPU's and the mirror's rectified depths differ by ~1e-6) grows at most 20-fold.
/// Accuracy is the same as without a floor down to 0.1 (mean rel L1 over the 24 suite poses
/// 1.098 % at 6 moments and 8 regions, 0.669 % at 16; 0.3: 1.103 / 0.675 %).
pub const MOMENT_RANGE_FLOOR: f32 = 0.1;

/// The moment coordinate of a normalised depth `d` in a region whose depths span
/// `range = [least, greatest]`: `z = (2 d - least - greatest) / max(greatest - least,
/// MOMENT_RANGE_FLOOR)`, so the region's depths fill `[-1, 1]`. With `z = 2 d - 1` over the
/// whole map a region's depths filled a fraction of the interval, where the bias and f32
/// rounding blurred them: 6 moments, 8 regions, mean rel L1 over the 24 suite poses 1.38 ->
/// 1.10 %, window/ordinary 8.01 -> 4.34 % (`prefiltered_truth`, 320x180).
pub fn moment_z(d: f32, range: [f32; 2]) -> f32 {
    (2.0 * d - (range[0] + range[1])) / (range[1] - range[0]).max(MOMENT_RANGE_FLOOR)
}

/// Layer `layer` of the power moments of `z`: `(z, z^2, z^3, z^4)` (layer 0) or
/// `(z^5, z^6, 0, 0)` (layer 1).
pub fn moment_layer(z: f32, layer: u32) -> [f32; 4] {
    let z2 = z * z;
    let z4 = z2 * z2;
    if layer == 0 {
        return [z, z2, z2 * z, z4];
    }
    [z4 * z, z4 * z2, 0.0, 0.0]
}

/// The first four moments mixed with a share `a` of the uniform distribution on `[-1, 1]`'s
/// `(0, 1/3, 0, 1/5)`.
pub fn biased4(raw: [f32; 4], a: f32) -> [f32; 4] {
    [
        raw[0] * (1.0 - a),
        raw[1] * (1.0 - a) + a / 3.0,
        raw[2] * (1.0 - a),
        raw[3] * (1.0 - a) + a / 5.0,
    ]
}

/// Weight of atom `x` of a discrete distribution with atoms `{x, u, far}` and moments
/// `(1, b1, b2)`: `E[(z - u)(z - far)] / ((x - u)(x - far))`, written as
/// `(E[z - u] + E[(z - u)(z - x)] k) / (x - u)` with `k = 1 / (x - far)` (0 for an atom at
/// infinity), which does not cancel when `far` is large.
pub fn atom_weight2(b1: f32, b2: f32, x: f32, u: f32, k: f32) -> f32 {
    let e1 = b1 - u;
    let e2 = b2 - b1 * (u + x) + u * x;
    (e1 + e2 * k) / (x - u)
}

/// Weight of atom `x` of a discrete distribution with atoms `{x, u, v, far}` and moments
/// `(1, b1, b2, b3)`, written like [`atom_weight2`]:
/// `(E[(z - u)(z - v)] + E[(z - u)(z - v)(z - x)] k) / ((x - u)(x - v))`, `k = 1 / (x - far)`.
#[allow(clippy::too_many_arguments, reason = "the WGSL function's parameters")]
pub fn atom_weight3(b1: f32, b2: f32, b3: f32, x: f32, u: f32, v: f32, k: f32) -> f32 {
    let s = u + v;
    let p = u * v;
    let e2 = b2 - b1 * s + p;
    let e3 = b3 - b2 * (s + x) + b1 * (p + s * x) - p * x;
    (e2 + e3 * k) / ((x - u) * (x - v))
}

/// `x` with the sign of `s` (`s >= 0`: positive).
pub fn sign_of(x: f32, s: f32) -> f32 {
    if s >= 0.0 {
        return x;
    }
    -x
}

/// `q`, or the smallest normal f32 where `q` is 0 (the quadratic formula divides by it).
pub fn nonzero(q: f32) -> f32 {
    if q == 0.0 {
        return f32::MIN_POSITIVE;
    }
    q
}

/// `1 / (x - far)`, or 0 where `far` is an atom at infinity.
pub fn far_k(x: f32, far: f32, at_infinity: bool) -> f32 {
    if at_infinity {
        return 0.0;
    }
    1.0 / (x - far)
}

/// The lit fraction at depth `zf` of a region with 4 moments `raw` (Hamburger 4MSM, Peters
/// & Klein 2015, with the estimate between the bounds described in the module docs).
pub fn lit_moments4(raw: [f32; 4], zf: f32) -> f32 {
    let [b1, b2, b3, b4] = biased4(raw, MOMENT_BIAS_4);
    // LDL^T of the Hankel matrix [[1, b1, b2], [b1, b2, b3], [b2, b3, b4]].
    let d2 = b2 - b1 * b1;
    let l32 = (b3 - b1 * b2) / d2;
    let d3 = b4 - b2 * b2 - l32 * l32 * d2;
    // L y = (1, zf, zf^2); the weight of the atom at zf is 1 / (y^T D^-1 y).
    let y2 = zf - b1;
    let y3 = zf * zf - b2 - l32 * y2;
    let wf = 1.0 / (1.0 + y2 * y2 / d2 + y3 * y3 / d3);
    // c = L^-T D^-1 y: the kernel polynomial c1 + c2 z + c3 z^2, whose roots are the other atoms.
    let c3 = y3 / d3;
    let c2 = y2 / d2 - l32 * c3;
    let c1 = 1.0 - b1 * c2 - b2 * c3;
    // Its roots: the stable quadratic formula; with |c3| tiny one root is at infinity.
    let disc = (c2 * c2 - 4.0 * c1 * c3).max(0.0);
    let q = nonzero(-0.5 * (c2 + sign_of(disc.sqrt(), c2)));
    let near = c1 / q;
    let at_infinity = c3.abs() * FAR_ROOT <= q.abs();
    let far = if at_infinity { 0.0 } else { q / c3 };
    // The lower bound on P(z < zf): the weights of the atoms below zf.
    let mut shadow = 0.0;
    if near < zf {
        shadow += atom_weight2(b1, b2, near, zf, far_k(near, far, at_infinity));
    }
    if !at_infinity && far < zf {
        shadow += atom_weight2(b1, b2, far, zf, 1.0 / (far - near));
    }
    clamp(1.0 - shadow - MOMENT_SPLIT * wf, 0.0, 1.0)
}

/// The real roots of `c1 + c2 z + c3 z^2 + c4 z^3` (three, as the kernel polynomial of a
/// positive definite Hankel matrix has): `(r0, r1, r2, at_infinity)` with `r2` the root of
/// largest magnitude, at infinity when `|c4|` is negligible (then `r0`, `r1` are the roots of
/// the quadratic). The root of largest magnitude from the trigonometric solution of the monic
/// cubic, polished by two Newton steps on the unscaled polynomial; the other two from the
/// deflated quadratic.
pub fn cubic_roots(c1: f32, c2: f32, c3: f32, c4: f32) -> ([f32; 3], bool) {
    if c4.abs() * FAR_ROOT <= c3.abs() {
        let disc = (c2 * c2 - 4.0 * c1 * c3).max(0.0);
        let q = nonzero(-0.5 * (c2 + sign_of(disc.sqrt(), c2)));
        return ([c1 / q, q / c3, 0.0], true);
    }
    let a = c3 / c4;
    let b = c2 / c4;
    let c = c1 / c4;
    let p = (b - a * a / 3.0).min(-1e-12);
    let qq = 2.0 * a * a * a / 27.0 - a * b / 3.0 + c;
    let m = 2.0 * (-p / 3.0).sqrt();
    let theta = clamp(3.0 * qq / (p * m), -1.0, 1.0).acos() / 3.0;
    // The root of largest magnitude: the greatest or the least of the trigonometric
    // solution (theta in [0, pi / 3]: k = 0 and k = 2), polished by Newton's method.
    let greatest = m * theta.cos() - a / 3.0;
    let least = m * (theta - 4.0 * PI / 3.0).cos() - a / 3.0;
    let mut z = if greatest.abs() >= least.abs() {
        greatest
    } else {
        least
    };
    for _ in 0..2 {
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
    let disc = (q1 * q1 - 4.0 * q0 * q2).max(0.0);
    let q = nonzero(-0.5 * (q1 + sign_of(disc.sqrt(), q1)));
    ([q0 / q, q / nonzero(q2), big], false)
}

/// The lit fraction at depth `zf` of a region with 6 moments `raw0 = (b1, b2, b3, b4)`,
/// `raw1 = (b5, b6)` (the canonical representation with four atoms; see the module docs).
pub fn lit_moments6(raw0: [f32; 4], raw1: [f32; 2], zf: f32) -> f32 {
    let a = MOMENT_BIAS_6;
    let [b1, b2, b3, b4] = biased4(raw0, a);
    let b5 = raw1[0] * (1.0 - a);
    let b6 = raw1[1] * (1.0 - a) + a / 7.0;
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
    let (r, at_infinity) = cubic_roots(c1, c2, c3, c4);
    // The lower bound on P(z < zf): the weights of the atoms below zf. Each near atom's
    // weight treats r[2] (the largest in magnitude) as the far one.
    let mut shadow = 0.0;
    if r[0] < zf {
        shadow += atom_weight3(b1, b2, b3, r[0], zf, r[1], far_k(r[0], r[2], at_infinity));
    }
    if r[1] < zf {
        shadow += atom_weight3(b1, b2, b3, r[1], zf, r[0], far_k(r[1], r[2], at_infinity));
    }
    if !at_infinity && r[2] < zf {
        shadow += atom_weight3(b1, b2, b3, r[2], zf, r[0], 1.0 / (r[2] - r[1]));
    }
    clamp(1.0 - shadow - MOMENT_SPLIT * wf, 0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact lit fraction of weighted depths, and the moment estimate's bounds from f64.
    fn truth(depths: &[(f32, f32)], zf: f32) -> f32 {
        let total: f32 = depths.iter().map(|p| p.1).sum();
        depths
            .iter()
            .filter(|p| p.0 >= zf)
            .map(|p| p.1)
            .sum::<f32>()
            / total
    }

    fn moments(depths: &[(f32, f32)]) -> ([f32; 4], [f32; 2]) {
        let total: f64 = depths.iter().map(|p| p.1 as f64).sum();
        let mut m = [0.0f64; 6];
        for &(z, w) in depths {
            for (k, mk) in m.iter_mut().enumerate() {
                *mk += w as f64 * (z as f64).powi(k as i32 + 1) / total;
            }
        }
        (
            [m[0] as f32, m[1] as f32, m[2] as f32, m[3] as f32],
            [m[4] as f32, m[5] as f32],
        )
    }

    /// The moment coordinate fills [-1, 1] over a region's range, a part of it below the
    /// floor, and is 0 for one depth.
    #[test]
    fn moment_z_spans_the_range() {
        assert!((moment_z(0.2, [0.2, 0.6]) + 1.0).abs() < 1e-6);
        assert!((moment_z(0.6, [0.2, 0.6]) - 1.0).abs() < 1e-6);
        assert!((moment_z(0.4, [0.2, 0.6])).abs() < 1e-6);
        assert!((moment_z(0.52, [0.5, 0.54]) + 0.0).abs() < 1e-6);
        assert!((moment_z(0.54, [0.5, 0.54]) - 0.4).abs() < 1e-5);
        assert_eq!(moment_z(0.3, [0.3, 0.3]), 0.0);
    }

    /// Two depths: 4 moments already determine the distribution, so the reconstruction is
    /// exact away from the atoms up to the moment bias (the uniform distribution mixed in
    /// puts a small atom at zf: 2.3e-3 with 6 moments' bias of 3e-4).
    #[test]
    fn two_depths_are_exact() {
        let d = [(-0.4, 0.3), (0.5, 0.7)];
        let (m0, m1) = moments(&d);
        for zf in [-0.8, -0.5, -0.3, 0.0, 0.4, 0.6, 0.9] {
            let t = truth(&d, zf);
            let v4 = lit_moments4(m0, zf);
            let v6 = lit_moments6(m0, m1, zf);
            assert!((v4 - t).abs() < 1e-3, "4 moments at {zf}: {v4} vs {t}");
            assert!((v6 - t).abs() < 5e-3, "6 moments at {zf}: {v6} vs {t}");
        }
    }

    /// Three depths: exact with 6 moments, bounded with 4.
    #[test]
    fn three_depths_are_exact_with_six_moments() {
        let d = [(-0.6, 0.2), (0.1, 0.5), (0.7, 0.3)];
        let (m0, m1) = moments(&d);
        for zf in [-0.8, -0.3, 0.0, 0.3, 0.5, 0.9] {
            let t = truth(&d, zf);
            let v6 = lit_moments6(m0, m1, zf);
            assert!((v6 - t).abs() < 5e-3, "6 moments at {zf}: {v6} vs {t}");
        }
    }

    /// A continuous (uniform-like) distribution: the estimate lies within half the weight
    /// of the atom at zf of the truth, which the bounds guarantee, and 6 moments are closer.
    #[test]
    fn continuous_depths_are_within_the_bounds() {
        let d: Vec<(f32, f32)> = (0..200)
            .map(|i| {
                (
                    -0.9 + 1.6 * (i as f32 + 0.5) / 200.0,
                    1.0 + (i as f32 * 0.1).sin() * 0.5,
                )
            })
            .collect();
        let (m0, m1) = moments(&d);
        let (mut e4, mut e6) = (0.0f32, 0.0f32);
        for i in 0..=16 {
            let zf = -0.8 + 1.6 * i as f32 / 16.0;
            let t = truth(&d, zf);
            e4 = e4.max((lit_moments4(m0, zf) - t).abs());
            e6 = e6.max((lit_moments6(m0, m1, zf) - t).abs());
        }
        assert!(e4 < 0.25, "4 moments: max error {e4}");
        assert!(e6 < 0.2, "6 moments: max error {e6}");
        assert!(e6 < e4, "6 moments {e6} not closer than 4 moments {e4}");
    }

    /// No NaN, values in [0, 1] over degenerate inputs: one depth, depths at the interval's
    /// ends, zf on an atom.
    #[test]
    fn degenerate_moments_stay_finite() {
        for d in [
            vec![(0.3f32, 1.0f32)],
            vec![(-1.0, 0.5), (1.0, 0.5)],
            vec![(1.0, 1.0)],
            vec![(-1.0, 1.0)],
            vec![(0.2, 0.999), (0.9, 0.001)],
        ] {
            let (m0, m1) = moments(&d);
            for i in 0..=40 {
                let zf = -1.0 + 2.0 * i as f32 / 40.0;
                for v in [lit_moments4(m0, zf), lit_moments6(m0, m1, zf)] {
                    assert!((0.0..=1.0).contains(&v), "{d:?} at {zf}: {v}");
                }
            }
        }
    }
}
