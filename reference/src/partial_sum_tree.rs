//! The partial-sum-tree method of Baran et al. 2010 ("A hierarchical volumetric shadow
//! algorithm for single scattering"), on the CPU: the method's independent reference (issue
//! 15), a removal sweep over every pixel of the screen, beside the `partial_sum_tree` family's
//! kernels (`pst_sweep` and its mirror `kernels::pst_sweep`, which sweep epipolar samples by
//! insertion). It checks the method's math against brute force (derivation and measurements:
//! `docs/partial-sum-tree.md`).
//!
//! It works on the shared epipolar layer (the frame set-up, `slice_fit` and `rectify` every
//! rectified family runs): row `y` of the rectified map is a slice, column `i` a light ray, and
//! the texel holds the normalised view angle `S_i` of the ray's first occluder. A view ray of
//! the slice (a pixel's, [`pixel_ray`]) has a constant normalised view angle `d` and crosses
//! columns `0 .. n`; texel `i` is lit for it iff `d <= S_i`, and in-scatters
//! `w_i(theta) = integral of T(t) dt` over the ray's part `[t_i, t_i+1]` inside column `i`
//! (directional light: `t_i = i delta / sin theta`). The brute-force sum over the columns is
//! `minmax`'s reference walk ([`walk_texels`]); this module computes the same sum with
//!
//! - **a separable integrand.** `w_i(theta) = g(u) exp(-sigma_t v_i / sin theta)` with
//!   `v_i = i delta` (the light ray's distance from the eye's axis), `u = delta / sin theta`
//!   and `g(u) = integral_0^u T`, exact per query. The kernel `K(v, theta) =
//!   exp(-sigma_t v / sin theta)` is not separable; its rank-r truncated SVD on a grid over
//!   the frame's `v` and `theta` ranges, `K ~ sum_k Gamma_k(v) B_k(theta)`, is ([`Separable`],
//!   the paper's rank-4 SVD; factors interpolated linearly between grid nodes; a spot
//!   light's kernel below);
//! - **a Fenwick tree per slice.** Queries sorted by `d`; before a query every column whose
//!   occluder lies before it (`S_i < d`) is removed (its `Gamma(v_i)` subtracted), then the
//!   prefix over columns `0 .. n - 1` gives `P_k`, and the ray's sum is
//!   `g(u) sum_k B_k(theta) P_k` plus its last, partial column evaluated exactly (the paper's
//!   fractional leaf). `O((W + Q) log W)` per slice for `W` columns and `Q` rays, against
//!   `O(W Q)` for the walk.
//!
//! Pixels near the epipole and the anti-epipole are marched as every epipolar family marches
//! them. A spot light's columns are light-ray angles `psi` from the lamp-eye line: there the
//! lamp's `1/r^2` cancels against `dt/dpsi`, and the weight of column `i` is
//! `sigma_s / (D sin theta)` times the integral over the column of `K(psi, theta) cone(psi)`
//! with `K = p(cos(theta + psi)) exp(-sigma_t D (sin psi + sin theta) / sin(theta + psi))`
//! (`D` the eye-lamp distance, `p` Henyey-Greenstein): `K` is separated as the sun's kernel
//! is, the cone factor (a function of the light ray alone) goes into the leaves.

use crate::kernels::common_epipolar::{row_phi, slice_e};
use crate::kernels::common_model::{cone_falloff, transmittance_between};
use crate::kernels::minmax_traverse::{
    Pixel, RowRay, TraverseInputs, edge_t, lit_span, pixel_ray, radiance,
};
use crate::kernels::texture::{Tex, xyz};
use scatter_shaderlib::prefiltered::FrameUniforms;

/// A Fenwick (binary indexed) tree over `n` leaves of `rank` values each: prefix sums and
/// point updates in `O(log n)`.
#[derive(Clone, Debug)]
pub struct Fenwick {
    n: usize,
    rank: usize,
    /// Node `j` (1-based) at `[(j - 1) * rank ..]`: the sum of leaves `(j - lowbit(j), j]`.
    nodes: Vec<f32>,
}

impl Fenwick {
    /// A tree over `leaves` (`n * rank` values, leaf-major), built in `O(n rank)`.
    ///
    /// Panics if `rank` is 0 or does not divide the number of values (a caller's bug).
    pub fn from_leaves(leaves: &[f32], rank: usize) -> Fenwick {
        assert!(
            rank > 0 && leaves.len().is_multiple_of(rank),
            "leaves must be n * rank values"
        );
        let n = leaves.len() / rank;
        let mut nodes = leaves.to_vec();
        for j in 1..=n {
            let parent = j + (j & j.wrapping_neg());
            if parent <= n {
                for k in 0..rank {
                    nodes[(parent - 1) * rank + k] += nodes[(j - 1) * rank + k];
                }
            }
        }
        Fenwick { n, rank, nodes }
    }

    /// Leaves.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the tree has no leaf.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Adds `delta` (`rank` values) to leaf `i`.
    pub fn add(&mut self, i: usize, delta: &[f32]) {
        let mut j = i + 1;
        while j <= self.n {
            for (k, d) in delta.iter().enumerate().take(self.rank) {
                self.nodes[(j - 1) * self.rank + k] += d;
            }
            j += j & j.wrapping_neg();
        }
    }

    /// The sum of leaves `0 .. i` (`i` clamped to the leaf count) into `out` (`rank` values).
    pub fn prefix(&self, i: usize, out: &mut [f32]) {
        out[..self.rank].fill(0.0);
        let mut j = i.min(self.n);
        while j > 0 {
            for (k, o) in out.iter_mut().enumerate().take(self.rank) {
                *o += self.nodes[(j - 1) * self.rank + k];
            }
            j -= j & j.wrapping_neg();
        }
    }
}

pub use scatter_shaderlib::partial_sum_tree::{
    GL2, GRID, PstError, Separable, spot_kernel, svd_jacobi,
};

/// The largest rank [`Separable::sun`] accepts.
pub const MAX_RANK: usize = scatter_shaderlib::partial_sum_tree::MAX_RANK as usize;

/// The kernel of one frame: its rank-r integrand over the frame's `v` range (the widest
/// row) and the view angles `[theta_lo, theta_hi]` of the rays it will be asked for. The
/// frame's whole range (`f.theta`) reaches the axis, where `exp(-sigma_t v / sin theta)`
/// becomes a step in `v` that no low rank follows (measured: rank-4 errors of 0.69-0.76 on
/// the suite's epipole and light-behind poses); those rays lie in the marched ring.
pub fn frame_separable(
    f: &FrameUniforms,
    slices: &[scatter_shaderlib::prefiltered::SliceParams],
    theta_lo: f32,
    theta_hi: f32,
    spot: bool,
    rank: usize,
) -> Result<Separable, PstError> {
    let width = f.sizes[2] as f32;
    let v_max = slices
        .iter()
        .map(|s| s.delta * width)
        .fold(0.0f32, f32::max);
    if spot {
        return Separable::spot(
            f.medium[0],
            f.medium[2],
            f.axis[3],
            v_max,
            theta_lo,
            theta_hi,
            rank,
        );
    }
    Separable::sun(f.medium[0], v_max, theta_lo, theta_hi, rank)
}

/// The output of [`partial_sum_tree`].
#[derive(Clone, Debug)]
pub struct PstImage {
    /// Radiance before rounding (f32), row-major; `[0, 0, 0, 1]` where no ray was traced.
    pub exact: Vec<[f32; 4]>,
    /// The separable kernel of the frame.
    pub separable: Separable,
    /// Fenwick updates (columns removed) over all slices.
    pub updates: u64,
    /// Fenwick queries over all slices.
    pub queries: u64,
}

/// The method on a whole screen: every pixel's ray (as `minmax_traverse` sets it up: nearest
/// row, marched near the epipoles), the rays of each row swept in `d` order through the
/// row's Fenwick tree. `rectified` is the frame's rectified map (`rectify`).
pub fn partial_sum_tree(
    inp: &TraverseInputs,
    rectified: &Tex,
    spot: bool,
    rank: usize,
) -> Result<PstImage, PstError> {
    if rank == 0 || rank > MAX_RANK {
        return Err(PstError::Rank(rank));
    }
    let f = inp.frame;
    let [w, h] = [f.sizes[0], f.sizes[1]];
    let rows = f.sizes[3] as usize;
    let width = f.sizes[2] as usize;
    let mut exact = vec![[0.0f32, 0.0, 0.0, 1.0]; (w * h) as usize];
    // Rays per row: (pixel index, ray).
    let mut per_row: Vec<Vec<(usize, RowRay)>> = vec![Vec::new(); rows];
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            match pixel_ray([x, y, 0], spot, inp) {
                Some(Pixel::Marched(c)) => exact[i] = c,
                Some(Pixel::Row(r)) => per_row[r.row as usize].push((i, r)),
                None => {}
            }
        }
    }
    let (lo, hi) = per_row
        .iter()
        .flatten()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), (_, r)| {
            (lo.min(r.theta), hi.max(r.theta))
        });
    let sep = if lo <= hi {
        frame_separable(f, inp.slices, lo, hi, spot, rank)?
    } else {
        frame_separable(f, inp.slices, f.theta[0], f.theta[1], spot, rank)?
    };
    let (mut updates, mut queries) = (0u64, 0u64);
    let mut leaves = vec![0.0f32; width * rank];
    let mut g = [0.0f32; MAX_RANK];
    let mut b = [0.0f32; MAX_RANK];
    let mut p = [0.0f32; MAX_RANK];
    let mut neg = [0.0f32; MAX_RANK];
    for (row, rays) in per_row.iter_mut().enumerate() {
        if rays.is_empty() {
            continue;
        }
        let delta = inp.slices[row].delta;
        if spot {
            // A spot's leaf: gamma times the light ray's cone factor, integrated over the
            // column's angles (2-point Gauss-Legendre).
            let e = slice_e(f, row_phi(f, row as u32));
            let axis = xyz(f.axis);
            for i in 0..width {
                leaves[i * rank..(i + 1) * rank].fill(0.0);
                for q in [-GL2, GL2] {
                    let psi = (i as f32 + 0.5 + 0.5 * q) * delta;
                    let l = -axis * psi.cos() + e * psi.sin();
                    let cone =
                        cone_falloff(l.dot(xyz(f.light_dir)), f.light_pos[3], f.light_dir[3]);
                    sep.gamma_at(psi, &mut g);
                    for k in 0..rank {
                        leaves[i * rank + k] += 0.5 * delta * cone * g[k];
                    }
                }
            }
        } else {
            for i in 0..width {
                sep.gamma_at((i as f32) * delta, &mut g);
                leaves[i * rank..(i + 1) * rank].copy_from_slice(&g[..rank]);
            }
        }
        let mut tree = Fenwick::from_leaves(&leaves, rank);
        // Columns in order of their occluder depth; rays in order of theirs.
        let occluder = |i: usize| rectified.load(i as u32, row as u32);
        let mut columns: Vec<usize> = (0..width).collect();
        columns.sort_by(|&a, &c| occluder(a).total_cmp(&occluder(c)));
        rays.sort_by(|a, c| a.1.d.total_cmp(&c.1.d));
        let mut next = 0;
        for (pixel, r) in rays.iter() {
            // Remove every column blocked before this ray: lit iff d <= S_i.
            while next < width && occluder(columns[next]) < r.d {
                let i = columns[next];
                for k in 0..rank {
                    neg[k] = -leaves[i * rank + k];
                }
                tree.add(i, &neg[..rank]);
                updates += 1;
                next += 1;
            }
            queries += 1;
            let total = ray_sum(f, &sep, &tree, rectified, row, r, spot, &mut b, &mut p);
            exact[*pixel] = radiance(f, r, total, spot);
        }
    }
    Ok(PstImage {
        exact,
        separable: sep,
        updates,
        queries,
    })
}

/// One ray's sum: the tree's prefix over its whole columns `0 .. n - 1` times the separable
/// weights, plus its last, partial column exactly (`lit_span`). The sun's sum is without
/// `sigma_s p E` (as `walk_texels`); a spot's carries `sigma_s / (D sin theta)` here.
#[allow(
    clippy::too_many_arguments,
    reason = "the sweep's state and two scratch arrays, as a kernel would pass them"
)]
fn ray_sum(
    f: &FrameUniforms,
    sep: &Separable,
    tree: &Fenwick,
    rectified: &Tex,
    row: usize,
    r: &RowRay,
    spot: bool,
    b: &mut [f32],
    p: &mut [f32],
) -> f32 {
    if r.n == 0 {
        return 0.0;
    }
    let rank = sep.rank;
    let sigma = f.medium[0];
    let sin_theta = r.theta.sin().max(1e-6);
    tree.prefix((r.n - 1) as usize, p);
    sep.beta_at(r.theta, b);
    let dot: f32 = (0..rank).map(|k| b[k] * p[k]).sum();
    let whole = if spot {
        f.medium[1] * dot / (f.axis[3] * sin_theta)
    } else {
        dot * transmittance_between(sigma, 0.0, r.delta / sin_theta)
    };
    let last = r.n - 1;
    let mut tail = 0.0;
    if r.d <= rectified.load(last, row as u32) {
        let a = edge_t(f, last, r.n, r.delta, r.theta, r.s, spot);
        tail = lit_span(f, r.eye, r.dir, a, r.s, spot);
    }
    whole.max(0.0) + tail
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fenwick_prefix_matches_the_naive_sum() {
        // A fixed LCG: leaves in [-1, 1), rank 3, updates and queries interleaved. The tree
        // sums in f32 (as a kernel would): its error is bounded relative to the magnitude of
        // everything that went into the queried leaves (`mag`), times the tree's depth.
        let mut state = 0x2545f4914f6cdd1du64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as f64 / (1u64 << 31) as f64) as f32 * 2.0 - 1.0
        };
        for n in [1usize, 2, 7, 64, 513] {
            let rank = 3;
            let mut leaves: Vec<f64> = Vec::new();
            let init: Vec<f32> = (0..n * rank).map(|_| next()).collect();
            leaves.extend(init.iter().map(|&v| f64::from(v)));
            let mut mag: Vec<f64> = leaves.iter().map(|v| v.abs()).collect();
            let mut tree = Fenwick::from_leaves(&init, rank);
            let mut out = [0.0f32; 3];
            for step in 0..200 {
                let i = ((next() * 0.5 + 0.5) * n as f32) as usize % n;
                if step % 2 == 0 {
                    let d = [next(), next(), next()];
                    tree.add(i, &d);
                    for k in 0..rank {
                        leaves[i * rank + k] += f64::from(d[k]);
                        mag[i * rank + k] += f64::from(d[k]).abs();
                    }
                }
                let q = ((next() * 0.5 + 0.5) * (n + 1) as f32) as usize % (n + 1);
                tree.prefix(q, &mut out);
                for k in 0..rank {
                    let naive: f64 = (0..q).map(|j| leaves[j * rank + k]).sum();
                    let scale: f64 = (0..q).map(|j| mag[j * rank + k]).sum();
                    let depth = (n as f64).log2().ceil().max(1.0);
                    assert!(
                        (f64::from(out[k]) - naive).abs() <= 1e-6 * scale * depth,
                        "n {n} prefix {q} basis {k}: tree {} naive {naive} (scale {scale})",
                        out[k]
                    );
                }
            }
            // Without updates the bound is the plain one: 1e-6 of the summed magnitudes.
            let fresh = Fenwick::from_leaves(&init, rank);
            for q in 0..=n {
                fresh.prefix(q, &mut out);
                for k in 0..rank {
                    let naive: f64 = (0..q).map(|j| f64::from(init[j * rank + k])).sum();
                    let scale: f64 = (0..q).map(|j| f64::from(init[j * rank + k]).abs()).sum();
                    assert!(
                        (f64::from(out[k]) - naive).abs() <= 1e-6 * scale.max(1e-30),
                        "fresh n {n} prefix {q} basis {k}: tree {} naive {naive}",
                        out[k]
                    );
                }
            }
        }
    }
}
