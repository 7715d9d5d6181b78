//! CPU mirror of `shaderlib/templates/common/sampling.wgsl` (`scatter::sampling`): where the
//! samples of `sampling = lowres` stand, which of them stand for a pixel and when a pixel is
//! evaluated itself; and of the families' sampling entry point
//! (`shaderlib/templates/include/sampled_entry.wgsl`), [`run_sampled`], which every family's
//! per-pixel mirror calls with its pixel body.
//! Conventions: `scatter_frame::sampling`.

use super::texture::{Tex, TexArray, quantise, round_f16};
use scatter_shaderlib::prefiltered::Storage;
use scatter_shaderlib::sampling::{Sampling, SamplingKnobs};

/// The sample grid of a screen at block side `scale`: samples at every S-th pixel from the
/// first, and one on the last: ceil((screen - 1) / scale) + 1.
pub fn lowres_grid(screen: [u32; 2], scale: u32) -> [u32; 2] {
    screen.map(|s| (s - 1).div_ceil(scale) + 1)
}

/// The pixel sample `i` stands on: the first pixel of block i, or the screen's last pixel.
pub fn lowres_pixel(i: [u32; 2], screen: [u32; 2], scale: u32) -> [u32; 2] {
    [
        (i[0] * scale).min(screen[0] - 1),
        (i[1] * scale).min(screen[1] - 1),
    ]
}

/// Whether two view depths lie on one surface: equal (sky pixels at +inf included), or
/// within `depth_break` (a fraction) of the nearer one.
pub fn depth_close(a: f32, b: f32, depth_break: f32) -> bool {
    a == b || (a - b).abs() <= depth_break * a.min(b)
}

/// `v` rounded to f16 (to nearest, ties to even) as rgba16float stores it, clamped to f16's
/// largest finite value (WGSL `round_f16`, which does it by bits).
pub fn round_f16_rgb(v: [f32; 3]) -> [f32; 3] {
    v.map(|c| round_f16(c.clamp(-65504.0, 65504.0)))
}

/// The four samples nearest to a pixel and their bilinear weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LowresTaps {
    /// Columns (x0, x1) of the samples (x0, y0), (x1, y0), (x0, y1), (x1, y1), clamped
    /// inside the sample grid.
    pub cols: [u32; 2],
    /// Rows (y0, y1).
    pub rows: [u32; 2],
    /// Their bilinear weights in that order (a weight is exactly 0 where the pixel lies on
    /// the other sample's column or row).
    pub w: [f32; 4],
}

/// The taps of pixel `p` in block p / S: samples p / S and p / S + 1 per axis (the block's
/// first pixel and the next block's), weighted by the pixel's place between their pixels.
pub fn lowres_taps(p: [u32; 2], screen: [u32; 2], scale: u32) -> LowresTaps {
    let grid = lowres_grid(screen, scale);
    let lo = p.map(|v| v / scale);
    let hi = [0, 1].map(|a| (lo[a] + 1).min(grid[a] - 1));
    let p0 = lowres_pixel(lo, screen, scale);
    let p1 = lowres_pixel(hi, screen, scale);
    let fr = [0, 1].map(|a| (p[a] - p0[a]) as f32 / (p1[a] - p0[a]).max(1) as f32);
    LowresTaps {
        cols: [lo[0], hi[0]],
        rows: [lo[1], hi[1]],
        w: [
            (1.0 - fr[0]) * (1.0 - fr[1]),
            fr[0] * (1.0 - fr[1]),
            (1.0 - fr[0]) * fr[1],
            fr[0] * fr[1],
        ],
    }
}

/// The pixel's radiance from its taps (WGSL `lowres_blend`: `w` the blend's weights,
/// `support` the weights that decide which taps stand around the pixel): the blend of the
/// taps with a positive weight within `depth_break` of `d`, or `None` where the pixel needs
/// its own evaluation (no such tap, only one close tap of several with positive support, or
/// the close supported taps' light differs by more than `light_break` of the brightest).
pub fn lowres_blend(
    w: [f32; 4],
    support: [f32; 4],
    depths: [f32; 4],
    light: [[f32; 3]; 4],
    d: f32,
    depth_break: f32,
    light_break: f32,
) -> Option<[f32; 3]> {
    let mut sum = [0.0f32; 3];
    let mut total = 0.0f32;
    let mut lo = [3.4e38f32; 3];
    let mut hi = [0.0f32; 3];
    let (mut taps, mut close) = (0u32, 0u32);
    for k in 0..4 {
        let near = depth_close(depths[k], d, depth_break);
        taps += u32::from(support[k] > 0.0);
        if support[k] > 0.0 && near {
            close += 1;
            for c in 0..3 {
                lo[c] = lo[c].min(light[k][c]);
                hi[c] = hi[c].max(light[k][c]);
            }
        }
        if w[k] > 0.0 && near {
            for c in 0..3 {
                sum[c] += w[k] * light[k][c];
            }
            total += w[k];
        }
    }
    // One close tap of several stands for nothing but itself (its light would be spread
    // over the pixels between it and the far taps, and the light criterion has nothing to
    // compare it with): a pixel beside a silhouette is evaluated unless it lies on the tap.
    if total <= 0.0 || close < taps.min(2) {
        return None;
    }
    let spread = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    if spread[0].max(spread[1].max(spread[2])) > light_break * hi[0].max(hi[1].max(hi[2])) {
        return None;
    }
    Some(sum.map(|v| v / total))
}

/// The outputs of a family's per-pixel kernel.
#[derive(Clone, Debug)]
pub struct SampledOutput {
    /// The screen-sized output as stored (rgba16float).
    pub output: TexArray,
    /// Pixel evaluations (every pixel for `pixels`; for `lowres` the samples plus the pixels
    /// evaluated themselves).
    pub evaluated: u64,
    /// `lowres`: the pixels evaluated themselves because no sample is close in depth.
    pub depth_refined: u64,
    /// `lowres`: the pixels evaluated themselves because their samples' light differs.
    pub light_refined: u64,
}

/// The family's sampling entry point (`include/sampled_entry.wgsl`): `pixel(x, y)` is the
/// family's per-pixel body (radiance before rounding), `screen` the screen size, `camera`
/// what the epipolar layout is built from (read only by `epipolar`).
/// `pixels`: every pixel (rows in parallel). `lowres`: its three passes in one (every
/// sample, as the family's kernel stores them in `lowres_samples`; every pixel the blend of
/// its taps, as `<kernel>_unwarp` writes it, or its own evaluation, as `<kernel>_fallback`
/// writes it). `epipolar`: its three passes ([`epipolar_samples`], [`epipolar_unwarp`],
/// [`epipolar_fallback`]).
pub fn run_sampled(
    knobs: &SamplingKnobs,
    screen: [u32; 2],
    depth: &Tex,
    camera: &EpipolarCamera,
    pixel: &(dyn Fn(u32, u32) -> [f32; 3] + Sync),
) -> SampledOutput {
    use rayon::prelude::*;
    let [w, h] = screen;
    if knobs.sampling == Sampling::Epipolar {
        let s = epipolar_samples(knobs, screen, depth, camera, pixel);
        let out = epipolar_fallback(epipolar_unwarp(knobs, screen, depth, &s.samples), pixel);
        return SampledOutput {
            output: out.output,
            evaluated: s.evaluated + out.evaluated,
            depth_refined: s.depth_refined + out.depth_refined,
            light_refined: s.light_refined + out.light_refined,
        };
    }
    let store = |c: [f32; 3]| [c[0], c[1], c[2], 1.0].map(|v| quantise(v, Storage::Rgba16float));
    if knobs.sampling == Sampling::Pixels {
        let data = (0..h)
            .into_par_iter()
            .flat_map_iter(|y| (0..w).map(move |x| store(pixel(x, y))))
            .collect();
        return SampledOutput {
            output: TexArray {
                width: w,
                height: h,
                layers: 1,
                data,
            },
            evaluated: u64::from(w) * u64::from(h),
            depth_refined: 0,
            light_refined: 0,
        };
    }
    let scale = knobs.scale;
    let (depth_break, light_break) = (knobs.depth_break_fraction(), knobs.light_break_fraction());
    let grid = lowres_grid(screen, scale);
    // Phase 1: every sample's radiance (rounded to f16) and its pixel's depth.
    let samples: Vec<([f32; 3], f32)> = (0..grid[1])
        .into_par_iter()
        .flat_map_iter(|j| {
            (0..grid[0]).map(move |i| {
                let p = lowres_pixel([i, j], screen, scale);
                (round_f16_rgb(pixel(p[0], p[1])), depth.load(p[0], p[1]))
            })
        })
        .collect();
    // Phase 2: every pixel, blended or evaluated (0 = blended, 1 = no sample close in
    // depth, 2 = the samples' light differs).
    let pixels: Vec<([f32; 4], u8)> = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            let samples = &samples;
            (0..w).map(move |x| {
                let t = lowres_taps([x, y], screen, scale);
                let mut depths = [0.0f32; 4];
                let mut light = [[0.0f32; 3]; 4];
                for j in 0..4 {
                    let (c, d) = samples[(t.rows[j / 2] * grid[0] + t.cols[j % 2]) as usize];
                    depths[j] = d;
                    light[j] = c;
                }
                let d = depth.load(x, y);
                match lowres_blend(t.w, t.w, depths, light, d, depth_break, light_break) {
                    Some(c) => (store(c), 0),
                    None => {
                        let why = if lowres_blend(t.w, t.w, depths, light, d, depth_break, 1.0)
                            .is_none()
                        {
                            1
                        } else {
                            2
                        };
                        (store(pixel(x, y)), why)
                    }
                }
            })
        })
        .collect();
    let depth_refined = pixels.iter().filter(|p| p.1 == 1).count() as u64;
    let light_refined = pixels.iter().filter(|p| p.1 == 2).count() as u64;
    SampledOutput {
        output: TexArray {
            width: w,
            height: h,
            layers: 1,
            data: pixels.into_iter().map(|p| p.0).collect(),
        },
        evaluated: u64::from(grid[0]) * u64::from(grid[1]) + depth_refined + light_refined,
        depth_refined,
        light_refined,
    }
}

// ---- sampling = epipolar (scatter_frame::sampling, "The epipolar passes") ----

/// What an epipolar layout is built from: the camera and the direction towards the light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EpipolarCamera {
    /// Camera forward, right and up.
    pub forward: [f32; 3],
    /// Camera right.
    pub right: [f32; 3],
    /// Camera up.
    pub up: [f32; 3],
    /// tan(fov_y / 2).
    pub tan_half: f32,
    /// Width / height.
    pub aspect: f32,
    /// From the eye towards the light (any length).
    pub toward: [f32; 3],
}

impl EpipolarCamera {
    /// The camera of the epipolar families' `Frame` (`frame.axis` points towards the light).
    pub fn of_frame(f: &scatter_shaderlib::prefiltered::FrameUniforms) -> Self {
        Self::new(
            f.cam_forward,
            f.cam_right,
            f.cam_up,
            [f.axis[0], f.axis[1], f.axis[2]],
        )
    }

    /// The camera of `RaymarchFrame`: towards the light is `-light_dir` (directional) or
    /// `light_pos - eye` (spot).
    pub fn of_raymarch(
        m: &scatter_shaderlib::raymarch::RaymarchUniforms,
        light: scatter_shaderlib::prefiltered::LightKind,
    ) -> Self {
        let toward = match light {
            scatter_shaderlib::prefiltered::LightKind::Directional => {
                [-m.light_dir[0], -m.light_dir[1], -m.light_dir[2]]
            }
            // `Area` is refused by the raymarch variant before any frame is set up.
            scatter_shaderlib::prefiltered::LightKind::Spot
            | scatter_shaderlib::prefiltered::LightKind::Area => [
                m.light_pos[0] - m.eye[0],
                m.light_pos[1] - m.eye[1],
                m.light_pos[2] - m.eye[2],
            ],
        };
        Self::new(m.cam_forward, m.cam_right, m.cam_up, toward)
    }

    /// The camera of `IvsvFrame` (area_ivsv): towards the light is `centre - eye`, the
    /// VPLs' centroid.
    pub fn of_ivsv(m: &scatter_shaderlib::area_ivsv::IvsvUniforms) -> Self {
        Self::new(
            m.cam_forward,
            m.cam_right,
            m.cam_up,
            [
                m.centre[0] - m.eye[0],
                m.centre[1] - m.eye[1],
                m.centre[2] - m.eye[2],
            ],
        )
    }

    /// From a uniform block's `cam_forward` (w = tan(fov_y / 2)), `cam_right` (w = aspect),
    /// `cam_up` and the direction towards the light.
    pub fn new(
        cam_forward: [f32; 4],
        cam_right: [f32; 4],
        cam_up: [f32; 4],
        toward: [f32; 3],
    ) -> Self {
        let xyz = |v: [f32; 4]| [v[0], v[1], v[2]];
        Self {
            forward: xyz(cam_forward),
            right: xyz(cam_right),
            up: xyz(cam_up),
            tan_half: cam_forward[3],
            aspect: cam_right[3],
            toward,
        }
    }
}

/// A frame's slices (WGSL `EpipolarLayout`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EpipolarLayout {
    /// The epipole, pixel coordinates (pixel centres at + 0.5).
    pub origin: [f32; 2],
    /// Unit direction from the origin to the screen centre (angle 0).
    pub axis: [f32; 2],
    /// Slice 0's first angle.
    pub phi_start: f32,
    /// Angle per slice.
    pub dphi: f32,
    /// Whether the origin is on screen (the slices go around it).
    pub wrap: bool,
}

/// The farthest the layout's origin lies from the screen centre, in screens.
pub const EPIPOLE_FAR: f32 = 100.0;
/// WGSL `PI_SAMPLING` (3.14159265358979, which rounds to this f32).
const PI_SAMPLING: f32 = std::f32::consts::PI;

fn dot3(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn length2(v: [f32; 2]) -> f32 {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

/// Angle of `d` from `axis` (counter-clockwise towards (-axis.y, axis.x)).
pub fn epipolar_angle(axis: [f32; 2], d: [f32; 2]) -> f32 {
    (axis[0] * d[1] - axis[1] * d[0]).atan2(axis[0] * d[0] + axis[1] * d[1])
}

/// The layout of `slices` slices for a camera and a screen.
pub fn epipolar_layout(cam: &EpipolarCamera, screen: [u32; 2], slices: u32) -> EpipolarLayout {
    let size = [screen[0] as f32, screen[1] as f32];
    let centre = [0.5 * size[0], 0.5 * size[1]];
    let z = dot3(cam.toward, cam.forward);
    let q = [
        dot3(cam.toward, cam.right) * centre[0] / (cam.tan_half * cam.aspect),
        -dot3(cam.toward, cam.up) * centre[1] / cam.tan_half,
    ];
    let far = EPIPOLE_FAR * size[0].max(size[1]);
    let lq = length2(q);
    let mut origin = centre;
    if lq >= far * z.abs() {
        let k = (far / lq.max(1e-30)) * if z < 0.0 { -1.0 } else { 1.0 };
        origin = [centre[0] + q[0] * k, centre[1] + q[1] * k];
    } else if lq > 0.0 {
        origin = [centre[0] + q[0] / z, centre[1] + q[1] / z];
    }
    let to_centre = [centre[0] - origin[0], centre[1] - origin[1]];
    let lc = length2(to_centre);
    let axis = if lc > 0.0 {
        [to_centre[0] / lc.max(1e-30), to_centre[1] / lc.max(1e-30)]
    } else {
        [1.0, 0.0]
    };
    let lo = [0.5f32, 0.5];
    let hi = [size[0] - 0.5, size[1] - 0.5];
    let inside =
        origin[0] >= lo[0] && origin[0] <= hi[0] && origin[1] >= lo[1] && origin[1] <= hi[1];
    let (phi_start, dphi) = if inside {
        (-PI_SAMPLING, 2.0 * PI_SAMPLING / slices as f32)
    } else {
        let mut a = 0.0f32;
        let mut b = 0.0f32;
        for k in 0..4u32 {
            let corner = [
                if k & 1 != 0 { hi[0] } else { lo[0] },
                if k & 2 != 0 { hi[1] } else { lo[1] },
            ];
            let phi = epipolar_angle(axis, [corner[0] - origin[0], corner[1] - origin[1]]);
            if k == 0 {
                a = phi;
                b = phi;
            } else {
                a = a.min(phi);
                b = b.max(phi);
            }
        }
        (a, (b - a) / slices as f32)
    };
    EpipolarLayout {
        origin,
        axis,
        phi_start,
        dphi,
        wrap: inside,
    }
}

/// Unit direction of slice `s`.
pub fn slice_direction(l: &EpipolarLayout, s: u32) -> [f32; 2] {
    let phi = l.phi_start + (s as f32 + 0.5) * l.dphi;
    let (sn, c) = phi.sin_cos();
    [
        l.axis[0] * c - l.axis[1] * sn,
        l.axis[1] * c + l.axis[0] * sn,
    ]
}

/// Where slice `s` runs inside the rectangle of pixel centres: (first distance from the
/// origin, distance between samples).
pub fn slice_span(l: &EpipolarLayout, s: u32, screen: [u32; 2], samples: u32) -> [f32; 2] {
    let u = slice_direction(l, s);
    let lo = [0.5f32, 0.5];
    let hi = [screen[0] as f32 - 0.5, screen[1] as f32 - 0.5];
    let mut t_in = 0.0f32;
    let mut t_out = 3.4e38f32;
    for a in 0..2 {
        if u[a].abs() > 1e-12 {
            let ta = (lo[a] - l.origin[a]) / u[a];
            let tb = (hi[a] - l.origin[a]) / u[a];
            t_in = t_in.max(ta.min(tb));
            t_out = t_out.min(ta.max(tb));
        }
    }
    t_out = t_out.max(t_in);
    [t_in, (t_out - t_in) / (samples - 1) as f32]
}

/// The pixel sample `k` of a slice (direction `u`, span `span`) stands on.
pub fn slice_sample_pixel(
    l: &EpipolarLayout,
    u: [f32; 2],
    span: [f32; 2],
    k: u32,
    screen: [u32; 2],
) -> [u32; 2] {
    let t = span[0] + k as f32 * span[1];
    [0, 1].map(|a| {
        let p = l.origin[a] + u[a] * t;
        p.floor().clamp(0.0, (screen[a] - 1) as f32) as u32
    })
}

/// The four samples a pixel gathered alone takes, with their weights ([`epipolar_taps_direct`];
/// the GPU gathers blocks of pixels, [`EpipolarBlock`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EpipolarTaps {
    /// The two slices.
    pub slices: [u32; 2],
    /// The first of the two samples on each slice.
    pub k: [u32; 2],
    /// Weights of (slice 0, k0), (slice 0, k0 + 1), (slice 1, k1), (slice 1, k1 + 1) (a
    /// pixel beyond a slice's end takes its end sample: the depth test decides).
    pub w: [f32; 4],
}

/// The four samples a block of pixels is gathered from (WGSL `EpipolarBlock`: slices
/// `slices`, samples (k[0], k[0] + 1) on the first and (k[1], k[1] + 1) on the second) and
/// how a pixel's weights follow from its place in the block: at the block's centre the
/// second slice's fraction `fs` and the fractions `fk` along each slice from sample k,
/// unclamped, and their changes per pixel (`gs`, `gk`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EpipolarBlock {
    /// The two slices.
    pub slices: [u32; 2],
    /// The first of the two samples on each slice.
    pub k: [u32; 2],
    /// The second slice's fraction at the block's centre, unclamped.
    pub fs: f32,
    /// Its change per pixel (x, y).
    pub gs: [f32; 2],
    /// On each slice, the fraction from sample `k` at the block's centre, unclamped.
    pub fk: [f32; 2],
    /// Their changes per pixel (x, y).
    pub gk: [[f32; 2]; 2],
    /// The range a pixel's own slice fraction keeps to (the fan's ends clamp it; unbounded
    /// around a full circle).
    pub fs_range: [f32; 2],
    /// On each slice, the range a pixel's own fraction keeps to (the slice's ends).
    pub fk_range: [[f32; 2]; 2],
}

/// The slices around point `x` (pixel coordinates; a block's centre) as a pixel centre there
/// chooses them, with the slice fraction and its gradient (the angle's, perp(d) / |d|^2, over
/// the angle per slice).
pub fn epipolar_block_slices(l: &EpipolarLayout, x: [f32; 2], slices: u32) -> EpipolarBlock {
    let d = [x[0] - l.origin[0], x[1] - l.origin[1]];
    let f = (epipolar_angle(l.axis, d) - l.phi_start) / l.dphi - 0.5;
    let (s_lo, base) = if l.wrap {
        let fl = f.floor();
        (((fl as i32 + slices as i32) as u32) % slices, fl)
    } else {
        let fc = f.clamp(0.0, (slices - 1) as f32);
        let s_lo = (fc as u32).min(slices - 2);
        (s_lo, s_lo as f32)
    };
    let r = (d[0] * d[0] + d[1] * d[1]).max(1e-20) * l.dphi;
    EpipolarBlock {
        slices: [s_lo, (s_lo + 1) % slices],
        k: [0; 2],
        fs: f - base,
        // (Low 12 mantissa bits cleared, as the WGSL does.)
        gs: [-d[1] / r, d[0] / r].map(|g| f32::from_bits(g.to_bits() & 0xffff_f000)),
        fk: [0.0; 2],
        gk: [[0.0; 2]; 2],
        fs_range: if l.wrap {
            [-3.4e38, 3.4e38]
        } else {
            [-base, (slices - 1) as f32 - base]
        },
        fk_range: [[0.0; 2]; 2],
    }
}

/// The samples around point `x` on the block's slices ([`epipolar_block_slices`]) from their
/// lines (direction, first distance, distance between samples: the samples' last column),
/// with the fractions along the slices and their gradients (each slice's direction over its
/// sample spacing: the distance along a slice is linear).
pub fn epipolar_block_taps(
    l: &EpipolarLayout,
    x: [f32; 2],
    block: EpipolarBlock,
    lines: [[f32; 4]; 2],
    samples: u32,
) -> EpipolarBlock {
    let d = [x[0] - l.origin[0], x[1] - l.origin[1]];
    let mut b = block;
    for (j, line) in lines.iter().enumerate() {
        let sp = line[3].max(1e-20);
        let g = (d[0] * line[0] + d[1] * line[1] - line[2]) / sp;
        let gc = g.clamp(0.0, (samples - 1) as f32);
        b.k[j] = (gc as u32).min(samples - 2);
        b.fk[j] = g - b.k[j] as f32;
        b.fk_range[j] = [-(b.k[j] as f32), (samples - 1) as f32 - b.k[j] as f32];
        b.gk[j] = [line[0] / sp, line[1] / sp];
    }
    b
}

/// The bilinear weights of the block's four samples for the pixel whose centre lies `o` from
/// the block's centre (WGSL `epipolar_block_weights`): the fractions moved by their gradients
/// (kept to the ranges a pixel's own keep to) and clamped to [0, 1]; none where the pixel's own
/// slice fraction lies more than half a slice beyond the block's slices (listed for the
/// fallback).
pub fn epipolar_block_weights(b: &EpipolarBlock, o: [f32; 2]) -> [f32; 4] {
    let own_s = (b.fs + (b.gs[0] * o[0] + b.gs[1] * o[1])).clamp(b.fs_range[0], b.fs_range[1]);
    let own_k = [0, 1].map(|j| {
        (b.fk[j] + (b.gk[j][0] * o[0] + b.gk[j][1] * o[1]))
            .clamp(b.fk_range[j][0], b.fk_range[j][1])
    });
    if !(-0.5..=1.5).contains(&own_s) {
        return [0.0; 4];
    }
    let fs = own_s.clamp(0.0, 1.0);
    let fk = own_k.map(|k| k.clamp(0.0, 1.0));
    [
        (1.0 - fs) * (1.0 - fk[0]),
        (1.0 - fs) * fk[0],
        fs * (1.0 - fk[1]),
        fs * fk[1],
    ]
}

/// The taps of pixel `p` gathered alone (a block of one pixel), its slices' lines computed
/// here (as the samples pass stores them).
pub fn epipolar_taps_direct(
    l: &EpipolarLayout,
    p: [u32; 2],
    screen: [u32; 2],
    slices: u32,
    samples: u32,
) -> EpipolarTaps {
    let x = [p[0] as f32 + 0.5, p[1] as f32 + 0.5];
    let pair = epipolar_block_slices(l, x, slices);
    let lines = pair.slices.map(|s| {
        let u = slice_direction(l, s);
        let span = slice_span(l, s, screen, samples);
        [u[0], u[1], span[0], span[1]]
    });
    let b = epipolar_block_taps(l, x, pair, lines, samples);
    EpipolarTaps {
        slices: b.slices,
        k: b.k,
        w: epipolar_block_weights(&b, [0.0, 0.0]),
    }
}

/// What the epipolar samples pass produced.
#[derive(Clone, Debug)]
pub struct EpipolarSamples {
    /// `(slice_samples + 1) x (slices + 1)`, rgba32float: radiance, the sample pixel's
    /// depth in w; the last column holds each slice's line (direction, first distance,
    /// distance between samples), the last row's first two texels the layout ([`layout_of`]).
    pub samples: TexArray,
    /// Samples evaluated (every slice's marked ones and those the light criterion added).
    pub evaluated: u64,
    /// Of those, the ones marked for a depth break (not on the initial step).
    pub depth_refined: u64,
    /// Of those, the ones the light criterion added.
    pub light_refined: u64,
}

/// Sampling pass 1 of `sampling = epipolar` (`include/sampled_entry.wgsl`): every slice's
/// samples, evaluated with `pixel` where marked (every `step`-th, the last, either side of
/// a depth break, then between evaluated samples whose light differs) and interpolated
/// elsewhere.
pub fn epipolar_samples(
    knobs: &SamplingKnobs,
    screen: [u32; 2],
    depth: &Tex,
    camera: &EpipolarCamera,
    pixel: &(dyn Fn(u32, u32) -> [f32; 3] + Sync),
) -> EpipolarSamples {
    use rayon::prelude::*;
    let (n, m, step) = (knobs.slices, knobs.slice_samples, knobs.step);
    let (depth_break, light_break) = (knobs.depth_break_fraction(), knobs.light_break_fraction());
    let layout = epipolar_layout(camera, screen, n);
    let lines: Vec<(Vec<[f32; 4]>, [u64; 3])> = (0..n)
        .into_par_iter()
        .map(|s| {
            let u = slice_direction(&layout, s);
            let span = slice_span(&layout, s, screen, m);
            let px: Vec<[u32; 2]> = (0..m)
                .map(|k| slice_sample_pixel(&layout, u, span, k, screen))
                .collect();
            let d: Vec<f32> = px.iter().map(|p| depth.load(p[0], p[1])).collect();
            let mut depth_marked = 0u64;
            let flag: Vec<bool> = (0..m as usize)
                .map(|k| {
                    let on_step = (k as u32).is_multiple_of(step) || k as u32 == m - 1;
                    let brk = (k > 0 && !depth_close(d[k - 1], d[k], depth_break))
                        || (k + 1 < m as usize && !depth_close(d[k], d[k + 1], depth_break));
                    if brk && !on_step {
                        depth_marked += 1;
                    }
                    on_step || brk
                })
                .collect();
            let mut light = vec![[0.0f32; 3]; m as usize];
            for k in 0..m as usize {
                if flag[k] {
                    light[k] = round_f16_rgb(pixel(px[k][0], px[k][1]));
                }
            }
            let bracket = |k: usize| {
                let mut a = k;
                while !flag[a] {
                    a -= 1;
                }
                let mut b = k;
                while !flag[b] {
                    b += 1;
                }
                (a, b)
            };
            let spread_over = |light: &[[f32; 3]], (a, b): (usize, usize)| {
                let (la, lb) = (light[a], light[b]);
                let hi = [0, 1, 2].map(|c| la[c].max(lb[c]));
                let spread = [0, 1, 2].map(|c| (la[c] - lb[c]).abs());
                spread[0].max(spread[1].max(spread[2])) > light_break * hi[0].max(hi[1].max(hi[2]))
            };
            let refine: Vec<usize> = (0..m as usize)
                .filter(|&k| !flag[k] && spread_over(&light, bracket(k)))
                .collect();
            for &k in &refine {
                light[k] = round_f16_rgb(pixel(px[k][0], px[k][1]));
            }
            let out = (0..m as usize)
                .map(|k| {
                    let mut c = light[k];
                    if !flag[k] {
                        let ab = bracket(k);
                        if !spread_over(&light, ab) {
                            let t = (k - ab.0) as f32 / (ab.1 - ab.0) as f32;
                            let (la, lb) = (light[ab.0], light[ab.1]);
                            c = [0, 1, 2].map(|i| la[i] * (1.0 - t) + lb[i] * t);
                        }
                    }
                    [c[0], c[1], c[2], d[k]]
                })
                .chain(std::iter::once([u[0], u[1], span[0], span[1]]))
                .collect();
            let marked = flag.iter().filter(|&&f| f).count() as u64;
            (
                out,
                [
                    marked + refine.len() as u64,
                    depth_marked,
                    refine.len() as u64,
                ],
            )
        })
        .collect();
    let mut counts = [0u64; 3];
    let mut data = Vec::with_capacity(((n + 1) * (m + 1)) as usize);
    for (line, c) in lines {
        data.extend(line);
        for i in 0..3 {
            counts[i] += c[i];
        }
    }
    // The last row: the layout, for the unwarp.
    data.push([
        layout.origin[0],
        layout.origin[1],
        layout.axis[0],
        layout.axis[1],
    ]);
    data.push([
        layout.phi_start,
        layout.dphi,
        if layout.wrap { 1.0 } else { 0.0 },
        0.0,
    ]);
    data.resize(((n + 1) * (m + 1)) as usize, [0.0; 4]);
    EpipolarSamples {
        samples: TexArray {
            width: m + 1,
            height: n + 1,
            layers: 1,
            data,
        },
        evaluated: counts[0],
        depth_refined: counts[1],
        light_refined: counts[2],
    }
}

/// The layout the samples pass stored in the last row of `samples` (`slices` slices).
pub fn layout_of(samples: &TexArray, slices: u32) -> EpipolarLayout {
    let head = samples.load(0, slices, 0);
    let angles = samples.load(1, slices, 0);
    EpipolarLayout {
        origin: [head[0], head[1]],
        axis: [head[2], head[3]],
        phi_start: angles[0],
        dphi: angles[1],
        wrap: angles[2] != 0.0,
    }
}

/// What the epipolar unwarp (`<kernel>_unwarp`) produced.
#[derive(Clone, Debug)]
pub struct EpipolarUnwarp {
    /// The screen-sized output as stored (rgba16float); the listed pixels hold 0 (the GPU
    /// pass stores `lowres_blend`'s alpha-0 texel there, which the fallback overwrites).
    pub output: TexArray,
    /// The pixels no sample stands for (`fallback_pixels`), in row-major order (the GPU
    /// lists them in no particular order).
    pub fallback: Vec<[u32; 2]>,
    /// Of those, the ones no sample is close to in depth.
    pub depth_refined: u64,
    /// Of those, the ones whose samples' light differs.
    pub light_refined: u64,
    /// Of those, the ones whose own samples lie more than half a spacing beyond their
    /// block's (slices or samples denser than the block: [`epipolar_block_weights`]).
    pub dense: u64,
}

/// Sampling pass 2 of `sampling = epipolar`, `<kernel>_unwarp`: every pixel gathered from
/// its four samples (`epipolar_taps`, kept as `lowres_blend` keeps taps), or listed for the
/// fallback pass (with why: `depth_refined`, `light_refined`).
pub fn epipolar_unwarp(
    knobs: &SamplingKnobs,
    screen: [u32; 2],
    depth: &Tex,
    samples: &TexArray,
) -> EpipolarUnwarp {
    use rayon::prelude::*;
    let [w, h] = screen;
    let (depth_break, light_break) = (knobs.depth_break_fraction(), knobs.light_break_fraction());
    let layout = layout_of(samples, knobs.slices);
    let store = |c: [f32; 3]| [c[0], c[1], c[2], 1.0].map(|v| quantise(v, Storage::Rgba16float));
    // One block of B x B pixels per GPU invocation, sharing its four samples.
    let bs = scatter_shaderlib::sampling::unwarp_block(knobs);
    let mut pixels: Vec<([f32; 4], u8)> = vec![([0.0; 4], 0); (w * h) as usize];
    pixels
        .par_chunks_mut((w * bs) as usize)
        .enumerate()
        .for_each(|(by, rows)| {
            let y0 = by as u32 * bs;
            for x0 in (0..w).step_by(bs as usize) {
                let centre = [x0 as f32 + 0.5 * bs as f32, y0 as f32 + 0.5 * bs as f32];
                let pair = epipolar_block_slices(&layout, centre, knobs.slices);
                let lines = pair.slices.map(|s| samples.load(knobs.slice_samples, s, 0));
                let b = epipolar_block_taps(&layout, centre, pair, lines, knobs.slice_samples);
                let mut depths = [0.0f32; 4];
                let mut light = [[0.0f32; 3]; 4];
                for j in 0..4 {
                    let v = samples.load(b.k[j / 2] + (j % 2) as u32, b.slices[j / 2], 0);
                    depths[j] = v[3];
                    light[j] = [v[0], v[1], v[2]];
                }
                let support = epipolar_block_weights(&b, [0.0, 0.0]);
                for i in 0..bs * bs {
                    let (x, y) = (x0 + i % bs, y0 + i / bs);
                    if x >= w || y >= h {
                        continue;
                    }
                    let o = [x as f32 + 0.5 - centre[0], y as f32 + 0.5 - centre[1]];
                    let wt = epipolar_block_weights(&b, o);
                    let d = depth.load(x, y);
                    rows[((y - y0) * w + x) as usize] =
                        match lowres_blend(wt, support, depths, light, d, depth_break, light_break)
                        {
                            Some(c) => (store(c), 0),
                            // Beyond the block's samples (no weights).
                            None if wt == [0.0; 4] => ([0.0; 4], 3),
                            None => {
                                let why = if lowres_blend(
                                    wt,
                                    support,
                                    depths,
                                    light,
                                    d,
                                    depth_break,
                                    1.0,
                                )
                                .is_none()
                                {
                                    1
                                } else {
                                    2
                                };
                                ([0.0; 4], why)
                            }
                        };
                }
            }
        });
    let fallback: Vec<[u32; 2]> = pixels
        .iter()
        .enumerate()
        .filter(|(_, p)| p.1 != 0)
        .map(|(i, _)| [i as u32 % w, i as u32 / w])
        .collect();
    let depth_refined = pixels.iter().filter(|p| p.1 == 1).count() as u64;
    let dense = pixels.iter().filter(|p| p.1 == 3).count() as u64;
    EpipolarUnwarp {
        output: TexArray {
            width: w,
            height: h,
            layers: 1,
            data: pixels.into_iter().map(|p| p.0).collect(),
        },
        light_refined: fallback.len() as u64 - depth_refined - dense,
        fallback,
        depth_refined,
        dense,
    }
}

/// Sampling pass 3 of `sampling = epipolar`, `<kernel>_fallback`: the pixels the unwarp
/// listed, evaluated with `pixel` into its output. `evaluated` counts them.
pub fn epipolar_fallback(
    unwarped: EpipolarUnwarp,
    pixel: &(dyn Fn(u32, u32) -> [f32; 3] + Sync),
) -> SampledOutput {
    use rayon::prelude::*;
    let store = |c: [f32; 3]| [c[0], c[1], c[2], 1.0].map(|v| quantise(v, Storage::Rgba16float));
    let EpipolarUnwarp {
        mut output,
        fallback,
        depth_refined,
        light_refined,
        ..
    } = unwarped;
    let values: Vec<[f32; 4]> = fallback
        .par_iter()
        .map(|p| store(pixel(p[0], p[1])))
        .collect();
    let w = output.width;
    for (p, v) in fallback.iter().zip(values) {
        output.data[(p[1] * w + p[0]) as usize] = v;
    }
    SampledOutput {
        output,
        evaluated: fallback.len() as u64,
        depth_refined,
        light_refined,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_stand_in_their_blocks() {
        assert_eq!(lowres_grid([67, 37], 4), [18, 10]);
        assert_eq!(lowres_grid([65, 37], 4), [17, 10]);
        assert_eq!(lowres_pixel([0, 0], [67, 37], 4), [0, 0]);
        assert_eq!(lowres_pixel([17, 9], [67, 37], 4), [66, 36]);
        assert_eq!(lowres_pixel([1, 1], [67, 37], 2), [2, 2]);
    }

    #[test]
    fn f16_rounding_by_bits_matches() {
        // The WGSL rounds by bits; check that scheme against `round_f16` here.
        let by_bits = |v: f32| {
            let a = v.abs().min(65504.0);
            let u = a.to_bits();
            let normal = f32::from_bits((u + 0xfff + ((u >> 13) & 1)) & 0xffff_e000);
            let sub = (a * 16_777_216.0).round_ties_even() / 16_777_216.0;
            v.signum() * if a < 6.103_515_6e-5 { sub } else { normal }
        };
        let mut x = 1.0e-9f32;
        while x < 7.0e4 {
            for v in [x, x * 1.000_03, x * 0.999_97, -x] {
                assert_eq!(by_bits(v), round_f16_rgb([v; 3])[0], "{v:e}");
            }
            x *= 1.013;
        }
        assert_eq!(round_f16_rgb([1e6, 0.0, -1e6]), [65504.0, 0.0, -65504.0]);
    }

    #[test]
    fn taps_and_blends() {
        // A sample pixel is its own tap with weight 1.
        let t = lowres_taps([2, 2], [8, 8], 2);
        assert_eq!(t.w, [1.0, 0.0, 0.0, 0.0]);
        assert_eq!((t.cols, t.rows), ([1, 2], [1, 2]));
        // Between four samples: a quarter each.
        let t = lowres_taps([3, 3], [8, 8], 2);
        assert_eq!(t.w, [0.25; 4]);
        // The last column: between the sample on column 6 and the one on the last pixel.
        let edge = lowres_taps([7, 3], [8, 8], 2);
        assert_eq!((edge.cols, edge.w), ([3, 4], [0.0, 0.5, 0.0, 0.5]));
        let light = [
            [1.0, 1.0, 1.0],
            [1.1, 1.1, 1.1],
            [0.9, 0.9, 0.9],
            [1.0, 1.0, 1.0],
        ];
        let c = lowres_blend(t.w, t.w, [10.0; 4], light, 10.0, 0.05, 0.25).expect("blends");
        assert!((c[0] - 1.0).abs() < 1e-6);
        // A near occluder: no tap is close in depth.
        assert_eq!(
            lowres_blend(t.w, t.w, [10.0; 4], light, 2.0, 0.05, 0.25),
            None
        );
        // A shadow edge between the taps: their spread is over the light break.
        assert_eq!(
            lowres_blend(t.w, t.w, [10.0; 4], light, 10.0, 0.05, 0.1),
            None
        );
        // Only the taps close in depth count, for the blend and for the spread.
        let c = lowres_blend(
            t.w,
            t.w,
            [10.0, 10.0, 2.0, 2.0],
            [[1.0; 3], [1.0; 3], [9.0; 3], [9.0; 3]],
            10.0,
            0.05,
            0.1,
        );
        assert_eq!(c, Some([1.0; 3]));
        // Infinite depths are equal; a light break of 1 never refines.
        let inf = f32::INFINITY;
        assert!(
            lowres_blend(
                t.w,
                t.w,
                [inf; 4],
                [[0.0; 3], [5.0; 3], [0.0; 3], [0.0; 3]],
                inf,
                0.05,
                1.0
            )
            .is_some()
        );
    }

    #[test]
    fn lowres_of_a_smooth_image_is_close_and_exact_at_breaks() {
        let screen = [13, 9];
        let mut depth = Tex::new(13, 9);
        for y in 0..9 {
            for x in 0..13 {
                depth.store(x, y, if x == 5 { 1.0 } else { 10.0 });
            }
        }
        let body = |x: u32, y: u32| [x as f32 * 0.1, y as f32 * 0.1, 1.0];
        let px = run_sampled(
            &SamplingKnobs::default(),
            screen,
            &depth,
            &camera([0.0; 3]),
            &body,
        );
        for scale in [2, 4] {
            let lr = run_sampled(
                &SamplingKnobs::lowres(scale),
                screen,
                &depth,
                &camera([0.0; 3]),
                &body,
            );
            assert!(
                lr.depth_refined > 0,
                "the one-pixel column is evaluated per pixel"
            );
            for (a, b) in px.output.data.iter().zip(&lr.output.data) {
                for c in 0..3 {
                    assert!((a[c] - b[c]).abs() <= 0.1 * scale as f32, "{a:?} {b:?}");
                }
            }
            for y in 0..9 {
                assert_eq!(
                    lr.output.load(5, y, 0),
                    px.output.load(5, y, 0),
                    "the occluder column is exact"
                );
            }
        }
    }

    fn camera(toward: [f32; 3]) -> EpipolarCamera {
        EpipolarCamera {
            forward: [0.0, 0.0, -1.0],
            right: [1.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            tan_half: 0.5,
            aspect: 67.0 / 37.0,
            toward,
        }
    }

    #[test]
    fn epipolar_layouts_cover_the_screen() {
        let screen = [67, 37];
        // On screen (towards the light ahead, a bit right), off screen (far right), behind
        // the camera, and perpendicular to the view (at infinity).
        for toward in [
            [0.2, 0.1, -1.0],
            [3.0, 0.5, -1.0],
            [0.3, -0.2, 1.0],
            [1.0, 0.3, 0.0],
        ] {
            let l = epipolar_layout(&camera(toward), screen, 64);
            assert!(l.dphi > 0.0 && l.dphi.is_finite(), "{toward:?}: {l:?}");
            // Every slice's samples stand on pixels along it, first to last in order.
            for s in 0..64 {
                let u = slice_direction(&l, s);
                let span = slice_span(&l, s, screen, 64);
                assert!(span[1] >= 0.0 && span[0] >= 0.0, "{toward:?} {s}: {span:?}");
                let a = slice_sample_pixel(&l, u, span, 0, screen);
                let b = slice_sample_pixel(&l, u, span, 63, screen);
                assert!(a[0] < 67 && a[1] < 37 && b[0] < 67 && b[1] < 37);
            }
            // Every pixel lies between two slices and two samples with weights summing to 1.
            for y in 0..37 {
                for x in 0..67 {
                    let t = epipolar_taps_direct(&l, [x, y], screen, 64, 64);
                    let sum: f32 = t.w.iter().sum();
                    assert!(
                        t.w.iter().all(|&w| w >= 0.0),
                        "{toward:?} ({x}, {y}): {t:?}"
                    );
                    assert!((sum - 1.0).abs() <= 1e-5, "{toward:?} ({x}, {y}): {t:?}");
                }
            }
            assert_eq!(
                l.wrap,
                toward == [0.2, 0.1, -1.0] || toward == [0.3, -0.2, 1.0]
            );
        }
    }

    #[test]
    fn a_block_s_weights_are_its_pixels_own_where_they_share_its_samples() {
        // The weights a block's pixel takes from the block's centre (the fractions moved by
        // their gradients) against the pixel's own, gathered alone, wherever the pixel's own
        // slices and samples are the block's; and in [0, 1] summing to 1 everywhere.
        let screen = [67, 37];
        let (slices, samples) = (16, 16);
        for toward in [
            [0.2, 0.1, -1.0],
            [3.0, 0.5, -1.0],
            [0.3, -0.2, 1.0],
            [1.0, 0.3, 0.0],
        ] {
            let l = epipolar_layout(&camera(toward), screen, slices);
            let (mut shared, mut worst, mut beyond) = (0, 0.0f32, 0);
            for by in 0..(screen[1] / 2) {
                for bx in 0..(screen[0] / 2) {
                    let centre = [2.0 * bx as f32 + 1.0, 2.0 * by as f32 + 1.0];
                    let pair = epipolar_block_slices(&l, centre, slices);
                    let lines = pair.slices.map(|s| {
                        let u = slice_direction(&l, s);
                        let span = slice_span(&l, s, screen, samples);
                        [u[0], u[1], span[0], span[1]]
                    });
                    let b = epipolar_block_taps(&l, centre, pair, lines, samples);
                    for i in 0..4 {
                        let p = [2 * bx + i % 2, 2 * by + i / 2];
                        let o = [p[0] as f32 + 0.5 - centre[0], p[1] as f32 + 0.5 - centre[1]];
                        let w = epipolar_block_weights(&b, o);
                        let sum: f32 = w.iter().sum();
                        assert!(
                            w.iter().all(|&v| (0.0..=1.0).contains(&v)),
                            "{toward:?} {p:?}: {w:?}"
                        );
                        let own = epipolar_taps_direct(&l, p, screen, slices, samples);
                        if w == [0.0; 4] {
                            // Beyond the block's samples: its own are others.
                            assert!(
                                own.slices != b.slices || own.k != b.k,
                                "{toward:?} {p:?}: no weights, yet its own samples are the block's"
                            );
                            beyond += 1;
                            continue;
                        }
                        assert!((sum - 1.0).abs() <= 1e-5, "{toward:?} {p:?}: {w:?}");
                        if own.slices == b.slices && own.k == b.k {
                            // (Within a few pixels of an on-screen epipole the angle is far
                            // from linear over a block: there the slices are closer than a
                            // pixel and any of them stands for the pixel.)
                            let r = (p[0] as f32 + 0.5 - l.origin[0])
                                .hypot(p[1] as f32 + 0.5 - l.origin[1]);
                            if r >= 8.0 {
                                shared += 1;
                                for (a, b) in own.w.iter().zip(&w) {
                                    worst = worst.max((a - b).abs());
                                }
                            }
                        }
                    }
                }
            }
            // (At 67x37 with 16 slices only the pixels next to an on-screen epipole lie beyond
            // their block's slices.)
            assert!(
                shared > 0 && worst <= 0.02 && beyond * 50 <= screen[0] * screen[1],
                "{toward:?}: {shared} shared, worst {worst}, {beyond} beyond"
            );
        }
    }

    #[test]
    fn epipolar_of_a_smooth_image_is_close_and_exact_at_breaks() {
        let screen = [67, 37];
        let mut depth = Tex::new(67, 37);
        for y in 0..37 {
            for x in 0..67 {
                depth.store(x, y, if x == 20 { 1.0 } else { 10.0 });
            }
        }
        // Smooth on each surface, 5x brighter on the occluder column.
        let body = |x: u32, y: u32| {
            let b = if x == 20 { 5.0 } else { 1.0 };
            [x as f32 * 0.01 + b, y as f32 * 0.01 + b, b]
        };
        let px = run_sampled(
            &SamplingKnobs::default(),
            screen,
            &depth,
            &camera([0.0; 3]),
            &body,
        );
        for toward in [[0.2, 0.1, -1.0], [3.0, 0.5, -1.0]] {
            let knobs = SamplingKnobs {
                slice_samples: 64,
                step: 8,
                ..SamplingKnobs::epipolar(64)
            };
            let e = run_sampled(&knobs, screen, &depth, &camera(toward), &body);
            assert!(
                e.evaluated < 67 * 37,
                "fewer evaluations than pixels: {}",
                e.evaluated
            );
            let mut worst = 0.0f32;
            for (a, b) in px.output.data.iter().zip(&e.output.data) {
                for c in 0..3 {
                    worst = worst.max((a[c] - b[c]).abs());
                }
            }
            // The body changes by 0.01 per pixel; samples stand within a few pixels; no
            // pixel takes light across the depth break (a halo would be off by 4).
            assert!(worst < 0.05, "{toward:?}: worst {worst}");
            assert!(
                e.depth_refined > 0,
                "the occluder column's breaks are refined"
            );
        }
    }
}
