//! The `partial_sum_tree` family (Baran, Chen, Ragan-Kelley, Durand, Lehtinen 2010, "A
//! hierarchical volumetric shadow algorithm for single scattering"): per epipolar slice, the
//! slice's view rays answered in one sweep through a partial-sum (Fenwick) tree with a rank-r
//! separable integrand. [`PartialSumTreeVariant`] holds its knobs, [`Separable`] the
//! integrand's factors, [`prepare_partial_sum_tree`] sets up a frame. Derivation, measured
//! error and the kernel design: `docs/partial-sum-tree.md`.
//!
//! # The sum
//!
//! On the shared epipolar layer ([`crate::frame::prepare_frame`], `slice_fit`, `rectify`: the
//! prefiltered family's rectified map, as `minmax` reads it) row `y` of the rectified map is
//! a slice, column `i` a light ray, texel `S_i` the normalised view angle of its first
//! occluder. A view ray of the row with normalised view angle `d` that crosses columns
//! `0 .. n` in-scatters `sum_{i < n - 1, d <= S_i} w_i(theta)` over its whole columns, plus
//! its last column exactly (`lit_span` over `[t_(n-1), s]` where `d <= S_(n-1)`). The
//! column weight is separable up to a rank-r SVD:
//!
//! - directional: `w_i = g(u) K(v_i, theta)`, `K(v, theta) = exp(-sigma_t v / sin theta)`,
//!   `v_i = i delta`, `g(u) = integral_0^u T` with `u = delta / sin theta` (exact per ray);
//! - spot: columns are light-ray angles `psi` from the lamp-eye line, the lamp's `1/r^2`
//!   cancels against `dt/dpsi`, and `w_i = sigma_s / (D sin theta) * integral over column i
//!   of K(psi, theta) cone(psi) dpsi` with `K = p(cos(theta + psi)) exp(-sigma_t D (sin psi +
//!   sin theta) / sin(theta + psi))` (`D` the eye-lamp distance, `p` Henyey-Greenstein). The
//!   cone factor is the light ray's: it goes into the leaves (2-point Gauss-Legendre).
//!
//! `K ~ sum_k gamma_k(v) beta_k(theta)` from the truncated SVD of `K` on a [`GRID`] x
//! [`GRID`] grid over `v` in `[0, max_row(delta Wr)]` and `theta` over the view angles of the
//! rays the frame can query ([`query_theta_range`]: the screen outside the marched rings
//! around the epipole and the anti-epipole; near the axis `K` becomes a step in `v` that no
//! low rank follows). Factors are interpolated linearly between grid nodes.
//!
//! # The factors buffer (`pst_factors`, `array<vec4<f32>>`, [`FACTOR_VECS`] entries)
//!
//! Entry 0: `v_max`, `theta_lo`, `theta_hi`, rank. Entries `1 + 2 j + h` (node `j` of the `v`
//! grid, `h` = 0, 1): `gamma_(4h .. 4h + 3)(v_j)`; entries `1 + 2 GRID + 2 j + h`: the same
//! of `beta(theta_j)`. Bases past the rank are 0.
//!
//! # The sweep (`pst_sweep`, one workgroup per epipolar sample slice)
//!
//! The slice's samples are its queries. With the queries ranked by `d` (rank `j_q`) and each
//! column's count `b_i` of queries that see it lit (`d <= S_i`; the queries with rank below
//! `b_i`), a column's leaf is inserted at tree position `Q - b_i`, and a query's whole
//! columns are `i < n_q - 1` with `b_i > j_q`: the sweep inserts the columns in index order
//! and answers each query, in order of `n_q`, by the prefix over positions below `Q - j_q`.
//! Nothing is removed or subtracted, so no sum cancels; the tree has `Q` positions (Q =
//! samples per slice) and each step costs `log2 Q`. The columns are split over [`TREES`]
//! trees filled at once (each answers the part of a query that lies in its columns); the
//! trees are then summed into exclusive prefixes (a Fenwick tree is linear in its leaves),
//! and each query adds the complete trees before its own.

use crate::family::{Family, KnobSet};
use crate::frame::{
    CameraDesc, FrameError, FrameSettings, FrameUniforms, LightDesc, MediumDesc, PrefilteredFrame,
    Resolutions, ShadowMapDesc, SliceParams, prepare_frame,
};
use crate::sampling::{Sampling, SamplingKnobs};
use crate::variant::{LightKind, PrefilteredVariant, Rectification, VariantError};
use serde::{Deserialize, Serialize};
use std::fmt;

/// The largest rank.
pub const MAX_RANK: u32 = 8;

/// The paper's rank (the default).
pub const DEFAULT_RANK: u32 = 4;

/// Grid nodes per axis of the SVD.
pub const GRID: usize = 96;

/// Entries (`vec4<f32>`) of the factors buffer: the header and two vec4 per node of each
/// factor.
pub const FACTOR_VECS: u32 = 1 + 4 * GRID as u32;

/// Fenwick trees per slice that the sweep fills at once (`pst_sweep`'s step 4: each owns
/// `ceil(Wr / TREES)` consecutive columns).
pub const TREES: u32 = 8;

/// The 2-point Gauss-Legendre node on [-1, 1] (a spot's leaves).
pub const GL2: f32 = 0.577_350_26;

/// The knobs of the `partial_sum_tree` family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PartialSumTreeVariant {
    /// Light type.
    pub light: LightKind,
    /// Rank of the separable integrand, 1..=8 (the paper: 4).
    pub rank: u32,
    /// Must be `epipolar`: the sweep answers an epipolar slice's samples.
    pub sampling: Sampling,
    /// Unused (must stay at its default: the family has no `lowres` sampling).
    pub scale: u32,
    /// The unwarp's depth break in percent of the nearer depth.
    pub depth_break: u32,
    /// The unwarp's light break in percent of the brightest sample.
    pub light_break: u32,
    /// Epipolar slices (one sweep each).
    pub slices: u32,
    /// Samples per slice (the queries of a sweep).
    pub slice_samples: u32,
    /// Must be 1: the sweep answers every sample of its slice.
    pub step: u32,
    /// A spot light's cookie ([`crate::cookie`]; `light = spot` only). It is constant along
    /// each light ray, so it multiplies each column's leaf: per colour channel its own leaf
    /// (the column's quadrature over its light rays with the cookie at each node), three
    /// times the leaf and tree entries, and the last partial column with the cookie.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub cookie: bool,
}

impl Default for PartialSumTreeVariant {
    /// Directional light, rank 4, 512 slices x 256 samples, every sample answered.
    fn default() -> Self {
        Self {
            light: LightKind::Directional,
            rank: DEFAULT_RANK,
            sampling: Sampling::Epipolar,
            scale: SamplingKnobs::DEFAULT_SCALE,
            depth_break: SamplingKnobs::DEFAULT_DEPTH_BREAK,
            light_break: SamplingKnobs::DEFAULT_LIGHT_BREAK,
            slices: SamplingKnobs::DEFAULT_SLICES,
            slice_samples: SamplingKnobs::DEFAULT_SLICE_SAMPLES,
            step: 1,
            cookie: false,
        }
    }
}

crate::sampling::sampling_fields!(PartialSumTreeVariant);

impl PartialSumTreeVariant {
    /// Checks every knob; the error names the first offending one.
    pub fn validate(&self) -> Result<(), VariantError> {
        crate::variant::validate_single_light(self.light)?;
        if !(1..=MAX_RANK).contains(&self.rank) {
            return Err(VariantError {
                knob: "rank",
                value: self.rank.to_string(),
                allowed: format!("in 1..={MAX_RANK}"),
            });
        }
        if self.sampling != Sampling::Epipolar {
            return Err(VariantError {
                knob: "sampling",
                value: self.sampling.name().to_owned(),
                allowed: "epipolar (the sweep answers an epipolar slice's samples in order; \
                          per-pixel queries would need every pixel sorted into its row)"
                    .into(),
            });
        }
        if self.step != 1 {
            return Err(VariantError {
                knob: "step",
                value: self.step.to_string(),
                allowed: "1 (the sweep answers every sample of its slice: nothing to \
                          interpolate)"
                    .into(),
            });
        }
        self.sampling_knobs().validate()?;
        crate::cookie::validate_cookie(self.cookie, self.light)
    }

    /// A short stable id: `directional-r4-epi512x256-s1-b10-l20`, with a cookie
    /// `spot-cookie-r4-epi512x256-s1-b10-l20`.
    pub fn id(&self) -> String {
        format!(
            "{}{}-r{}{}",
            self.light.name(),
            crate::cookie::id_suffix(self.cookie),
            self.rank,
            self.sampling_knobs().id_suffix()
        )
    }

    /// The conformance grid: both lights at rank 4 and 8 (8: two vec4 per leaf), the
    /// directional light at rank 1 and the spot with its cookie at rank 4; 64 slices x 64
    /// samples (the conformance screens are small).
    pub fn grid() -> Vec<PartialSumTreeVariant> {
        let small = |light, rank| PartialSumTreeVariant {
            light,
            rank,
            slices: 64,
            slice_samples: 64,
            ..PartialSumTreeVariant::default()
        };
        vec![
            small(LightKind::Directional, 1),
            small(LightKind::Directional, 4),
            small(LightKind::Spot, 4),
            small(LightKind::Directional, 8),
            small(LightKind::Spot, 8),
            PartialSumTreeVariant {
                cookie: true,
                ..small(LightKind::Spot, 4)
            },
        ]
    }

    /// The prefiltered-family variant whose frame set-up and `rectify` kernel this family
    /// uses: the light, epipolar rectification, one region.
    pub fn prefiltered(&self) -> PrefilteredVariant {
        PrefilteredVariant {
            regions: 1,
            light: self.light,
            rectification: Rectification::Epipolar,
            ..PrefilteredVariant::default()
        }
    }

    /// vec4s of the rank's factors: `ceil(rank / 4)`.
    pub fn rank_vecs(&self) -> u32 {
        self.rank.div_ceil(4)
    }

    /// vec4s per leaf and tree node: [`Self::rank_vecs`], three times that with a cookie (one
    /// leaf per colour channel, channel `c` at `c * rank_vecs ..`).
    pub fn leaf_vecs(&self) -> u32 {
        if self.cookie {
            3 * self.rank_vecs()
        } else {
            self.rank_vecs()
        }
    }
}

impl fmt::Display for PartialSumTreeVariant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.id())
    }
}

impl KnobSet for PartialSumTreeVariant {
    const FAMILY_NAME: &'static str = "partial_sum_tree";
    const FAMILY: Family = Family::PartialSumTree;
    const SUMMARY: &'static str = "Baran et al. 2010, partial-sum trees: per epipolar slice, one sweep \
         answers every sample through a Fenwick tree of a rank-r separable integrand";

    fn validate(&self) -> Result<(), VariantError> {
        PartialSumTreeVariant::validate(self)
    }

    fn id(&self) -> String {
        PartialSumTreeVariant::id(self)
    }

    fn light(&self) -> LightKind {
        self.light
    }

    fn with_light(self, light: LightKind) -> Self {
        Self { light, ..self }
    }

    /// `r4-ep512` (the rank, `-cookie` with a cookie, then the sampling's marker).
    fn marker(&self) -> String {
        format!(
            "r{}{}{}",
            self.rank,
            crate::cookie::id_suffix(self.cookie),
            self.sampling_knobs().marker_suffix()
        )
    }

    fn sampling(&self) -> SamplingKnobs {
        self.sampling_knobs()
    }

    fn with_sampling(self, s: SamplingKnobs) -> Self {
        self.with_sampling_knobs(s)
    }

    fn grid() -> Vec<Self> {
        PartialSumTreeVariant::grid()
    }

    fn cookie(&self) -> bool {
        self.cookie
    }

    fn with_cookie(self, cookie: bool) -> Option<Self> {
        Some(Self { cookie, ..self })
    }
}

/// Why a separable approximation cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PstError {
    /// The rank must lie in `1..=MAX_RANK`.
    #[error("partial-sum-tree rank must be in 1..={MAX_RANK}, got {0}")]
    Rank(usize),
}

/// A rank-r separable approximation `K(v, theta) ~ sum_k gamma_k(v) beta_k(theta)` of a kernel
/// sampled on a `v` x `theta` grid, from its truncated SVD; both factors are interpolated
/// linearly between grid nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct Separable {
    /// Rank.
    pub rank: usize,
    /// `v` grid: [`GRID`] nodes over `[0, v_max]`.
    pub v_max: f32,
    /// `theta` grid: [`GRID`] nodes over `[theta_lo, theta_hi]`.
    pub theta_lo: f32,
    /// Upper end of the `theta` grid.
    pub theta_hi: f32,
    /// `gamma_k(v_j) = U_jk s_k`, node-major (`GRID * rank`).
    pub gamma: Vec<f32>,
    /// `beta_k(theta_j) = V_jk`, node-major (`GRID * rank`).
    pub beta: Vec<f32>,
    /// The leading singular values, largest first: the kept `rank` and the
    /// [`OVERSAMPLE`] after them ([`svd_truncated`]'s block), so `singular[rank] /
    /// singular[0]` is the first dropped one's share.
    pub singular: Vec<f64>,
}

impl Separable {
    /// The rank-`rank` approximation of the directional light's kernel
    /// `exp(-sigma_t v / sin theta)` over `v` in `[0, v_max]`, `theta` in `[theta_lo,
    /// theta_hi]` (clamped to `[1e-3, pi - 1e-3]`).
    ///
    /// # Errors
    ///
    /// [`PstError::Rank`] for a rank outside `1..=MAX_RANK`.
    pub fn sun(
        sigma_t: f32,
        v_max: f32,
        theta_lo: f32,
        theta_hi: f32,
        rank: usize,
    ) -> Result<Separable, PstError> {
        let sigma = f64::from(sigma_t);
        Separable::from_kernel(
            &|v, theta| (-sigma * v / theta.sin()).exp(),
            v_max,
            theta_lo,
            theta_hi,
            rank,
        )
    }

    /// The rank-`rank` approximation of a spot light's kernel in the light-ray angle `psi`
    /// (the `v` axis) and the view angle `theta` ([`spot_kernel`]).
    ///
    /// # Errors
    ///
    /// [`PstError::Rank`] for a rank outside `1..=MAX_RANK`.
    pub fn spot(
        sigma_t: f32,
        g: f32,
        eye_lamp: f32,
        psi_max: f32,
        theta_lo: f32,
        theta_hi: f32,
        rank: usize,
    ) -> Result<Separable, PstError> {
        let (sigma, g, dist) = (f64::from(sigma_t), f64::from(g), f64::from(eye_lamp));
        Separable::from_kernel(
            &|psi, theta| spot_kernel(sigma, g, dist, psi, theta),
            psi_max,
            theta_lo,
            theta_hi,
            rank,
        )
    }

    /// The rank-`rank` truncated SVD ([`svd_truncated`], a block of `rank + OVERSAMPLE`) of
    /// `kernel(v, theta)` sampled on a [`GRID`] x [`GRID`] grid over `[0, v_max]` x
    /// `[theta_lo, theta_hi]` (clamped to `[1e-3, pi - 1e-3]`).
    ///
    /// # Errors
    ///
    /// [`PstError::Rank`] for a rank outside `1..=MAX_RANK`.
    pub fn from_kernel(
        kernel: &dyn Fn(f64, f64) -> f64,
        v_max: f32,
        theta_lo: f32,
        theta_hi: f32,
        rank: usize,
    ) -> Result<Separable, PstError> {
        if rank == 0 || rank > MAX_RANK as usize {
            return Err(PstError::Rank(rank));
        }
        let lo = theta_lo.clamp(1e-3, std::f32::consts::PI - 1e-3);
        let hi = theta_hi.clamp(lo, std::f32::consts::PI - 1e-3);
        let v_max = v_max.max(1e-6);
        let (m, n) = (GRID, GRID);
        let v_at = |j: usize| f64::from(v_max) * j as f64 / (m - 1) as f64;
        let t_at = |j: usize| f64::from(lo) + f64::from(hi - lo) * j as f64 / (n - 1) as f64;
        let mut a = vec![0.0f64; m * n];
        for i in 0..m {
            for j in 0..n {
                a[i * n + j] = kernel(v_at(i), t_at(j));
            }
        }
        let p = (rank + OVERSAMPLE).min(n);
        let (u, s, v) = svd_truncated(&a, m, n, p);
        let mut gamma = vec![0.0f32; m * rank];
        let mut beta = vec![0.0f32; n * rank];
        for k in 0..rank.min(s.len()) {
            for i in 0..m {
                gamma[i * rank + k] = (u[i * p + k] * s[k]) as f32;
            }
            for j in 0..n {
                beta[j * rank + k] = v[j * p + k] as f32;
            }
        }
        Ok(Separable {
            rank,
            v_max,
            theta_lo: lo,
            theta_hi: hi,
            gamma,
            beta,
            singular: s,
        })
    }

    /// `gamma_k(v)` for every `k` into `out` (`v` clamped to the grid).
    pub fn gamma_at(&self, v: f32, out: &mut [f32]) {
        interpolate(&self.gamma, self.rank, GRID, v / self.v_max, out);
    }

    /// `beta_k(theta)` for every `k` into `out` (`theta` clamped to the grid).
    pub fn beta_at(&self, theta: f32, out: &mut [f32]) {
        let x = (theta - self.theta_lo) / (self.theta_hi - self.theta_lo).max(1e-12);
        interpolate(&self.beta, self.rank, GRID, x, out);
    }

    /// The approximation at `(v, theta)`.
    pub fn eval(&self, v: f32, theta: f32) -> f32 {
        let mut g = [0.0f32; MAX_RANK as usize];
        let mut b = [0.0f32; MAX_RANK as usize];
        self.gamma_at(v, &mut g);
        self.beta_at(theta, &mut b);
        (0..self.rank).map(|k| g[k] * b[k]).sum()
    }

    /// The factors buffer (`pst_factors`, [`FACTOR_VECS`] vec4; layout in the module docs).
    pub fn pack(&self) -> Vec<[f32; 4]> {
        let mut out = vec![[0.0f32; 4]; FACTOR_VECS as usize];
        out[0] = [self.v_max, self.theta_lo, self.theta_hi, self.rank as f32];
        for j in 0..GRID {
            for k in 0..self.rank {
                out[1 + 2 * j + k / 4][k % 4] = self.gamma[j * self.rank + k];
                out[1 + 2 * GRID + 2 * j + k / 4][k % 4] = self.beta[j * self.rank + k];
            }
        }
        out
    }
}

/// The spot light's kernel in f64: `p(cos(theta + psi)) exp(-sigma D (sin psi + sin theta) /
/// sin(theta + psi))`, `p` Henyey-Greenstein with `g`, `D` the eye-lamp distance; 0 where
/// `theta + psi >= pi` (a light ray the view ray never meets).
pub fn spot_kernel(sigma: f64, g: f64, dist: f64, psi: f64, theta: f64) -> f64 {
    let sum = theta + psi;
    if sum >= std::f64::consts::PI - 1e-6 {
        return 0.0;
    }
    let c = sum.cos();
    let denom = (1.0 + g * g - 2.0 * g * c).max(1e-8);
    let phase = (1.0 - g * g) / (4.0 * std::f64::consts::PI * denom * denom.sqrt());
    phase * (-sigma * dist * (psi.sin() + theta.sin()) / sum.sin()).exp()
}

/// Linear interpolation of a node-major table of `nodes` x `rank` at `x` in `[0, 1]`.
fn interpolate(table: &[f32], rank: usize, nodes: usize, x: f32, out: &mut [f32]) {
    let p = (x.clamp(0.0, 1.0) * (nodes - 1) as f32).min((nodes - 1) as f32);
    let j = (p.floor() as usize).min(nodes - 2);
    let f = p - j as f32;
    for k in 0..rank {
        out[k] = table[j * rank + k] * (1.0 - f) + table[(j + 1) * rank + k] * f;
    }
}

/// Columns the block of [`svd_truncated`] carries past the kept rank: its convergence
/// factor per iteration is `(s_(p+1) / s_r)^2` for block size `p`, and these kernels'
/// singular values fall by about an order of magnitude each, so a few iterations converge.
pub const OVERSAMPLE: usize = 4;

/// Most subspace iterations [`svd_truncated`] runs (it stops earlier when the block's
/// singular values settle to 1e-13).
pub const SUBSPACE_ITERATIONS: usize = 64;

/// The `p` leading singular triplets of the row-major `m x n` matrix `a` by block subspace
/// iteration (Golub & Van Loan, Sec. 8.2.4; Halko et al. 2011's range finder with power
/// iterations, deterministic start): `X` (`n x p`) starts as the first `p` cosine vectors;
/// each iteration orthonormalises `A X` and `A^T (A X)`; then the Rayleigh-Ritz step takes
/// the SVD of the small `p x n` matrix `Q^T A` ([`svd_jacobi`] on its transpose). Returns
/// `(U, s, V)`: `U` `m x p`, `V` `n x p`, row-major, `s` descending. About 20x cheaper than
/// [`svd_jacobi`] of the whole 96 x 96 grid, which spent ~35 ms per frame in release builds
/// (`docs/partial-sum-tree.md` has the measurement).
///
/// # Panics
///
/// If `p` is 0 or above `min(m, n)` or `a` is not `m * n` values (a caller's bug).
pub fn svd_truncated(a: &[f64], m: usize, n: usize, p: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    assert!(p >= 1 && p <= m.min(n) && a.len() == m * n);
    // x: n x p, column k the k-th cosine vector (deterministic, spread over the grid).
    let mut x = vec![0.0f64; n * p];
    for j in 0..n {
        for k in 0..p {
            x[j * p + k] = (std::f64::consts::PI * k as f64 * (j as f64 + 0.5) / n as f64).cos();
        }
    }
    let mut y = vec![0.0f64; m * p];
    let mut last = vec![0.0f64; p];
    for _ in 0..SUBSPACE_ITERATIONS {
        orthonormalise(&mut x, n, p);
        mat_mul(a, m, n, &x, p, &mut y, false);
        orthonormalise(&mut y, m, p);
        mat_mul(a, m, n, &y, p, &mut x, true);
        // The norms of A^T q_k approach the singular values once the block has settled.
        let norms: Vec<f64> = (0..p)
            .map(|k| {
                (0..n)
                    .map(|j| x[j * p + k] * x[j * p + k])
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let settled = norms
            .iter()
            .zip(&last)
            .all(|(a, b)| (a - b).abs() <= 1e-13 * norms[0].max(1e-300));
        last = norms;
        if settled {
            break;
        }
    }
    // Rayleigh-Ritz: x = A^T Q (n x p) = W s Z^T, so A ~ Q Q^T A = (Q Z) s W^T.
    let (w, s, z) = svd_jacobi(&x, n, p);
    let mut u = vec![0.0f64; m * p];
    for i in 0..m {
        for k in 0..p {
            u[i * p + k] = (0..p).map(|l| y[i * p + l] * z[l * p + k]).sum();
        }
    }
    (u, s, w)
}

/// `out = A b` (`b` `n x p`, `out` `m x p`) or, with `transpose`, `out = A^T b` (`b` `m x
/// p`, `out` `n x p`); `A` is row-major `m x n`.
fn mat_mul(a: &[f64], m: usize, n: usize, b: &[f64], p: usize, out: &mut [f64], transpose: bool) {
    out.iter_mut().for_each(|o| *o = 0.0);
    for i in 0..m {
        let row = &a[i * n..(i + 1) * n];
        for (j, &aij) in row.iter().enumerate() {
            let (dst, src) = if transpose { (j, i) } else { (i, j) };
            for k in 0..p {
                out[dst * p + k] += aij * b[src * p + k];
            }
        }
    }
}

/// Orthonormalises the `p` columns of the row-major `rows x p` matrix `q` in place
/// (modified Gram-Schmidt, twice for the f64 loss of orthogonality). A column that lies in
/// the span of those before it (what remains is under 1e-12 of its norm: rounding, whose
/// direction means nothing) becomes 0: the block then spans less, as the matrix does.
fn orthonormalise(q: &mut [f64], rows: usize, p: usize) {
    let column_norm = |q: &[f64], k: usize| {
        (0..rows)
            .map(|i| q[i * p + k] * q[i * p + k])
            .sum::<f64>()
            .sqrt()
    };
    for _pass in 0..2 {
        for k in 0..p {
            let before = column_norm(q, k);
            for l in 0..k {
                let d: f64 = (0..rows).map(|i| q[i * p + k] * q[i * p + l]).sum();
                for i in 0..rows {
                    q[i * p + k] -= d * q[i * p + l];
                }
            }
            let norm = column_norm(q, k);
            let inv = if norm > 1e-12 * before && norm > 1e-300 {
                1.0 / norm
            } else {
                0.0
            };
            for i in 0..rows {
                q[i * p + k] *= inv;
            }
        }
    }
}

/// One-sided Jacobi SVD of the row-major `m x n` matrix `a` (`m >= n`): `(U, s, V)` with `U`
/// `m x n` and `V` `n x n` row-major, singular values descending.
///
/// # Panics
///
/// If `m < n` or `a` is not `m * n` values (a caller's bug).
pub fn svd_jacobi(a: &[f64], m: usize, n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    assert!(m >= n && a.len() == m * n);
    // Columns of `w` converge to U s; `v` accumulates the rotations.
    let mut w = a.to_vec();
    let mut v = vec![0.0f64; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    for _sweep in 0..60 {
        let mut rotated = false;
        for p in 0..n {
            for q in p + 1..n {
                let (mut alpha, mut beta, mut gamma) = (0.0, 0.0, 0.0);
                for i in 0..m {
                    let (x, y) = (w[i * n + p], w[i * n + q]);
                    alpha += x * x;
                    beta += y * y;
                    gamma += x * y;
                }
                if gamma.abs() <= 1e-15 * (alpha * beta).sqrt() || gamma == 0.0 {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let t = if zeta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                for i in 0..m {
                    let (x, y) = (w[i * n + p], w[i * n + q]);
                    w[i * n + p] = c * x - s * y;
                    w[i * n + q] = s * x + c * y;
                }
                for i in 0..n {
                    let (x, y) = (v[i * n + p], v[i * n + q]);
                    v[i * n + p] = c * x - s * y;
                    v[i * n + q] = s * x + c * y;
                }
            }
        }
        if !rotated {
            break;
        }
    }
    let norms: Vec<f64> = (0..n)
        .map(|j| {
            (0..m)
                .map(|i| w[i * n + j] * w[i * n + j])
                .sum::<f64>()
                .sqrt()
        })
        .collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| norms[b].total_cmp(&norms[a]));
    let mut u = vec![0.0f64; m * n];
    let mut vs = vec![0.0f64; n * n];
    let mut s = vec![0.0f64; n];
    for (k, &j) in order.iter().enumerate() {
        s[k] = norms[j];
        for i in 0..m {
            u[i * n + k] = if norms[j] > 0.0 {
                w[i * n + j] / norms[j]
            } else {
                0.0
            };
        }
        for i in 0..n {
            vs[i * n + k] = v[i * n + j];
        }
    }
    (u, s, vs)
}

/// The view angle (to the axis towards the light) of the ray through the continuous pixel
/// position `(px, py)` (pixel centres at `x + 0.5`), as the kernels' `pixel_dir` gives it.
fn view_angle(f: &FrameUniforms, px: f64, py: f64) -> f64 {
    let v3 = |a: [f32; 4]| glam::DVec3::new(a[0].into(), a[1].into(), a[2].into());
    let ndc_x = 2.0 * px / f64::from(f.sizes[0]) - 1.0;
    let ndc_y = 1.0 - 2.0 * py / f64::from(f.sizes[1]);
    let t = f64::from(f.cam_forward[3]);
    let dir = (v3(f.cam_forward)
        + v3(f.cam_right) * (ndc_x * t * f64::from(f.cam_right[3]))
        + v3(f.cam_up) * (ndc_y * t))
        .normalize();
    let axis = v3(f.axis);
    dir.cross(axis).length().atan2(dir.dot(axis))
}

/// The view angles `[lo, hi]` of every ray the frame can query: the screen's pixel centres
/// outside the marched rings around the epipole and the anti-epipole. Along every epipolar
/// line the view angle grows from the epipole to the anti-epipole, so its extremes over that
/// region lie on the region's boundary: the screen's edges and the rings' circles, sampled
/// every 1/256 of their length (and widened by 1 % of the range for the points between).
pub fn query_theta_range(f: &FrameUniforms) -> (f32, f32) {
    let (w, h) = (f64::from(f.sizes[0]), f64::from(f.sizes[1]));
    let radius = f64::from(f.epipole[3]);
    let rings: Vec<(f64, f64)> = [f.epipole, f.anti_epipole]
        .iter()
        .filter(|e| e[2] > 0.5)
        .map(|e| (f64::from(e[0]), f64::from(e[1])))
        .collect();
    let outside = |x: f64, y: f64| {
        rings
            .iter()
            .all(|&(ex, ey)| ((x - ex).powi(2) + (y - ey).powi(2)).sqrt() >= radius)
    };
    let (x0, x1, y0, y1) = (0.5, (w - 0.5).max(0.5), 0.5, (h - 0.5).max(0.5));
    let mut points: Vec<(f64, f64)> = Vec::new();
    const STEPS: usize = 256;
    for i in 0..=STEPS {
        let a = i as f64 / STEPS as f64;
        let (x, y) = (x0 + (x1 - x0) * a, y0 + (y1 - y0) * a);
        points.extend([(x, y0), (x, y1), (x0, y), (x1, y)]);
    }
    for &(ex, ey) in &rings {
        for i in 0..STEPS {
            let a = std::f64::consts::TAU * i as f64 / STEPS as f64;
            let (x, y) = (ex + radius * a.cos(), ey + radius * a.sin());
            if (x0..=x1).contains(&x) && (y0..=y1).contains(&y) {
                points.push((x, y));
            }
        }
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (x, y) in points {
        if outside(x, y) {
            let t = view_angle(f, x, y);
            lo = lo.min(t);
            hi = hi.max(t);
        }
    }
    if lo > hi {
        // Every boundary point inside a ring (a screen smaller than the ring): every pixel is
        // marched, the factors are never read.
        return (f.theta[0], f.theta[1]);
    }
    let pad = 0.01 * (hi - lo);
    ((lo - pad) as f32, (hi + pad) as f32)
}

/// The frame's separable kernel: rank `rank`, over `v` in `[0, max_row(delta Wr)]` (the
/// slice table of [`prepare_frame`], which spans rows to the far plane: at least what
/// `slice_fit` leaves) and [`query_theta_range`].
///
/// # Errors
///
/// [`PstError::Rank`] for a rank outside `1..=MAX_RANK`.
pub fn frame_separable(
    f: &FrameUniforms,
    slices: &[SliceParams],
    spot: bool,
    rank: usize,
) -> Result<Separable, PstError> {
    let width = f.sizes[2] as f32;
    let v_max = slices
        .iter()
        .map(|s| s.delta * width)
        .fold(0.0f32, f32::max);
    let (lo, hi) = query_theta_range(f);
    if spot {
        return Separable::spot(
            f.medium[0],
            f.medium[2],
            f.axis[3],
            v_max.min(std::f32::consts::PI),
            lo,
            hi,
            rank,
        );
    }
    Separable::sun(f.medium[0], v_max, lo, hi, rank)
}

/// One frame of the `partial_sum_tree` family.
#[derive(Clone, Debug)]
pub struct PartialSumTreeFrame {
    /// The shared epipolar frame (uniform block, slice table, report).
    pub frame: PrefilteredFrame,
    /// The separable integrand.
    pub separable: Separable,
    /// [`Separable::pack`]: the `pst_factors` buffer.
    pub factors: Vec<[f32; 4]>,
}

/// Sets up one frame of the `partial_sum_tree` family: [`prepare_frame`] with
/// [`PartialSumTreeVariant::prefiltered`], then the separable integrand
/// ([`frame_separable`]).
///
/// # Errors
///
/// As [`prepare_frame`], and [`FrameError::Variant`] for an invalid variant.
pub fn prepare_partial_sum_tree(
    variant: &PartialSumTreeVariant,
    res: &Resolutions,
    camera: &CameraDesc,
    light: &LightDesc,
    medium: &MediumDesc,
    shadow: &ShadowMapDesc,
    settings: &FrameSettings,
) -> Result<PartialSumTreeFrame, FrameError> {
    variant.validate()?;
    // With the sampling knobs: the rows lie on the epipolar sampling's slices (row s of a
    // map with as many rows as slices is slice s's plane, as for `minmax`).
    let frame = prepare_frame(
        &variant
            .prefiltered()
            .with_sampling_knobs(variant.sampling_knobs()),
        res,
        camera,
        light,
        medium,
        shadow,
        settings,
    )?;
    let separable = frame_separable(
        &frame.uniforms,
        &frame.slices,
        variant.light == LightKind::Spot,
        variant.rank as usize,
    )
    .map_err(|_| VariantError {
        knob: "rank",
        value: variant.rank.to_string(),
        allowed: format!("in 1..={MAX_RANK}"),
    })?;
    let factors = separable.pack();
    Ok(PartialSumTreeFrame {
        frame,
        separable,
        factors,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_svd_reconstructs_its_matrix() {
        let (m, n) = (12, 7);
        let a: Vec<f64> = (0..m * n)
            .map(|i| ((i * 37 % 11) as f64 - 5.0) / 3.0)
            .collect();
        let (u, s, v) = svd_jacobi(&a, m, n);
        for w in s.windows(2) {
            assert!(w[0] >= w[1]);
        }
        for i in 0..m {
            for j in 0..n {
                let r: f64 = (0..n).map(|k| u[i * n + k] * s[k] * v[j * n + k]).sum();
                assert!(
                    (r - a[i * n + j]).abs() < 1e-10,
                    "({i}, {j}): {r} vs {}",
                    a[i * n + j]
                );
            }
        }
    }

    /// The rank-r product of the first `r` triplets of `(u, s, v)` (`u` `m x pu`, `v` `n x
    /// pv`, row-major) at `(i, j)`.
    fn product(
        t: &(Vec<f64>, Vec<f64>, Vec<f64>),
        m: usize,
        n: usize,
        r: usize,
        i: usize,
        j: usize,
    ) -> f64 {
        let (pu, pv) = (t.0.len() / m, t.2.len() / n);
        (0..r)
            .map(|k| t.0[i * pu + k] * t.1[k] * t.2[j * pv + k])
            .sum()
    }

    /// A named kernel `K(v, theta)` for the SVD tests.
    type NamedKernel = (&'static str, Box<dyn Fn(f64, f64) -> f64>);

    #[test]
    fn truncated_svd_matches_the_full_one_on_the_kernels() {
        let n = GRID;
        let kernels: Vec<NamedKernel> = vec![
            (
                "sun thin",
                Box::new(|v: f64, t: f64| (-0.02 * v / t.sin()).exp()),
            ),
            (
                "sun dense",
                Box::new(|v: f64, t: f64| (-0.4 * v / t.sin()).exp()),
            ),
            (
                "spot",
                Box::new(|v: f64, t: f64| spot_kernel(0.05, 0.4, 30.0, v, t)),
            ),
            (
                "spot forward",
                Box::new(|v: f64, t: f64| spot_kernel(0.2, 0.9, 10.0, v, t)),
            ),
        ];
        for (name, k) in &kernels {
            let (v_max, lo, hi) = if name.starts_with("sun") {
                (200.0, 0.05, 3.0)
            } else {
                (1.2, 0.05, 3.0)
            };
            let mut a = vec![0.0f64; n * n];
            for i in 0..n {
                for j in 0..n {
                    let v = v_max * i as f64 / (n - 1) as f64;
                    let t = lo + (hi - lo) * j as f64 / (n - 1) as f64;
                    a[i * n + j] = k(v, t);
                }
            }
            let full = svd_jacobi(&a, n, n);
            for rank in [1usize, 4, 8] {
                let p = rank + OVERSAMPLE;
                let fast = svd_truncated(&a, n, n, p);
                for r in 0..rank {
                    let d = (fast.1[r] - full.1[r]).abs() / full.1[0];
                    assert!(
                        d < 1e-10,
                        "{name} rank {rank}: s_{r} {} vs {}",
                        fast.1[r],
                        full.1[r]
                    );
                }
                // The rank-r approximations agree (singular vectors are defined up to sign and,
                // where singular values are close, rotation; their products are not).
                let mut worst = 0.0f64;
                for i in 0..n {
                    for j in 0..n {
                        let d = product(&fast, n, n, rank, i, j) - product(&full, n, n, rank, i, j);
                        worst = worst.max(d.abs());
                    }
                }
                assert!(
                    worst < 1e-8 * full.1[0],
                    "{name} rank {rank}: {worst:e} of s_0 {}",
                    full.1[0]
                );
            }
        }
    }

    #[test]
    fn truncated_svd_of_a_low_rank_matrix() {
        // Rank 2 with p = 5: the block's extra columns carry nothing and do not spoil it.
        let (m, n) = (30, 20);
        let a: Vec<f64> = (0..m * n)
            .map(|x| {
                let (i, j) = ((x / n) as f64, (x % n) as f64);
                (i + 1.0) * (j * 0.5 + 2.0) + (i * 0.3).sin() * (j * 0.7).cos()
            })
            .collect();
        let t = svd_truncated(&a, m, n, 5);
        for i in 0..m {
            for j in 0..n {
                assert!((product(&t, m, n, 2, i, j) - a[i * n + j]).abs() < 1e-9 * t.1[0]);
            }
        }
        assert!(t.1[2] < 1e-9 * t.1[0], "{:?}", t.1);
    }

    #[test]
    fn rank_one_is_exact_without_extinction() {
        let sep = Separable::sun(0.0, 50.0, 0.2, 2.8, 1).unwrap();
        for &(v, t) in &[(0.0, 0.2), (10.0, 1.0), (50.0, 2.8), (33.3, 1.7)] {
            assert!((sep.eval(v, t) - 1.0).abs() < 1e-5, "{}", sep.eval(v, t));
        }
    }

    #[test]
    fn ranks_outside_the_range_are_refused() {
        assert_eq!(
            Separable::sun(0.1, 1.0, 0.1, 1.0, 0).unwrap_err(),
            PstError::Rank(0)
        );
        assert!(Separable::sun(0.1, 1.0, 0.1, 1.0, MAX_RANK as usize + 1).is_err());
        let bad = PartialSumTreeVariant {
            rank: 9,
            ..PartialSumTreeVariant::default()
        };
        assert_eq!(bad.validate().unwrap_err().knob, "rank");
    }

    #[test]
    fn only_epipolar_sampling_with_every_sample() {
        let v = PartialSumTreeVariant::default();
        assert!(v.validate().is_ok());
        let pixels = v.with_sampling_knobs(SamplingKnobs::default());
        assert_eq!(pixels.validate().unwrap_err().knob, "sampling");
        let stepped = PartialSumTreeVariant { step: 8, ..v };
        assert_eq!(stepped.validate().unwrap_err().knob, "step");
        for g in PartialSumTreeVariant::grid() {
            assert!(g.validate().is_ok(), "{g}");
        }
    }

    #[test]
    fn packed_factors_hold_the_tables() {
        let sep = Separable::sun(0.3, 20.0, 0.3, 2.5, 5).unwrap();
        let p = sep.pack();
        assert_eq!(p.len(), FACTOR_VECS as usize);
        assert_eq!(p[0], [sep.v_max, sep.theta_lo, sep.theta_hi, 5.0]);
        assert_eq!(p[1 + 2 * 7 + 1][0], sep.gamma[7 * 5 + 4]);
        assert_eq!(p[1 + 2 * GRID + 2 * 3][2], sep.beta[3 * 5 + 2]);
        assert_eq!(p[1 + 2 * 7 + 1][1], 0.0);
    }
}
