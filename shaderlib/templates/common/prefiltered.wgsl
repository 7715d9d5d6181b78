// scatter::prefiltered: what the three kernels of the prefiltered family (Klehm et al. 2014)
// share: the `Frame` uniform block, the per-slice parameters, the rectified-space mapping
// (Sec. 4.1), the Fourier basis and its coefficients (Sec. 3, Eq. 8), the prefilter's
// reference-ray weights (Eq. 11/12), region bounds (Table 1) and the frame's standard
// shadow map (`scatter::shadow`) for `rectify` and the epipole ray march of `scatter` (Sec. 5).
//
// Composed into kernels by naga_oil (`#import scatter::prefiltered::{...}`); plain WGSL, not
// an askama template. Conventions: `scatter_shaderlib::prefiltered::frame`. Mirrored line by
// line by reference/src/kernels/common_prefiltered.rs; functions that read a texture take it
// as a parameter (a shared module cannot see the kernel's bindings), the texture operations
// themselves (`Tex::load`, `TexArray::store`, `sample_bilinear`) are textureLoad,
// textureStore and textureSampleLevel in the kernels. `region_start` is mirrored by
// reference/src/kernels/prefilter.rs.

#define_import_path scatter::prefiltered

#import scatter::model::{PI, cone_falloff, transmittance_between}
#import scatter::shadow::{ShadowMapView, shadow_occluder_distance, shadow_visibility}

// The uniform block (host: `scatter_shaderlib::prefiltered::FrameUniforms`, field by field;
// every member is 16 bytes, 25 * 16 = 400 bytes in all). The host's `e1`, `e2`, `sizes2` and
// `proj_g0..2` are spelled `e1_`, `e2_`, `sizes2_` and `proj_g0_..2_`: naga's back-ends append
// `_` to identifiers that end in a digit, and naga_oil requires shared modules to use the
// written-back spelling.
struct Frame {
    // Eye position; w unused.
    eye: vec4<f32>,
    // Axis A (towards the light); w = eye-light distance D (spot), 0 (directional).
    axis: vec4<f32>,
    // Slice basis e1 (perpendicular to A); w = phi0.
    e1_: vec4<f32>,
    // Slice basis e2 = A x e1; w = dphi (radians per row).
    e2_: vec4<f32>,
    // Camera forward; w = tan(fov_y / 2).
    cam_forward: vec4<f32>,
    // Camera right; w = aspect (width / height).
    cam_right: vec4<f32>,
    // Camera up; w = near.
    cam_up: vec4<f32>,
    // x = theta_lo, y = theta_hi, z = far, w = 1 / (theta_hi - theta_lo).
    theta: vec4<f32>,
    // x = sigma_t, y = sigma_s, z = g, w unused.
    medium: vec4<f32>,
    // Light colour (E or I); w unused.
    light_color: vec4<f32>,
    // Spot position; w = cos(inner angle).
    light_pos: vec4<f32>,
    // Direction the light travels (spot axis); w = cos(outer angle).
    light_dir: vec4<f32>,
    // Shadow-map right; w = shadow-map near.
    sm_right: vec4<f32>,
    // Shadow-map up; w = shadow-map far.
    sm_up: vec4<f32>,
    // Shadow-map forward; w = bias in texel footprints.
    sm_forward: vec4<f32>,
    // Shadow-map origin; w = 0 orthographic, 1 perspective.
    sm_origin: vec4<f32>,
    // Orthographic: x0, x1, y0, y1. Perspective: tan_half, 0, 0, 0.
    sm_proj: vec4<f32>,
    // Epipole pixel position x, y; z = 1 if it is on screen; w = march radius (pixels).
    epipole: vec4<f32>,
    // Anti-epipole pixel position x, y; z = 1 if on screen; w = 1 if the slices wrap around.
    anti_epipole: vec4<f32>,
    // Screen width, height, rectified width, rectified height.
    sizes: vec4<u32>,
    // Shadow-map size, march steps, spot quadrature nodes, unused.
    sizes2_: vec4<u32>,
    // x = 1 projective frame, 0 epipolar; y = kh (rows span k = qy / qx in [-kh, kh]);
    // z = m_hi; w = 1 / (m_hi - m_lo) (ray depths m = qz / qx).
    proj: vec4<f32>,
    // Projective column invariants G_0..G_3 at the region boundaries.
    proj_g0_: vec4<f32>,
    // G_4..G_7.
    proj_g1_: vec4<f32>,
    // G_8; yzw unused.
    proj_g2_: vec4<f32>,
}

// One rectified row's parameters (host: `SliceParams`), unpacked from the kernels'
// `slices: array<vec4<f32>>` binding by `slice_params`. In a projective frame the fields hold
// the row's k (delta), its reference ray's depth m_ref (theta_ref) and its depth range
// m_lo, m_hi (theta_lo, theta_hi).
struct SliceParams {
    // Column spacing: `v` per column (directional) or `psi` per column (spot).
    delta: f32,
    // View angle of the slice's reference ray.
    theta_ref: f32,
    // Smallest view angle of the slice inside the frustum.
    theta_lo: f32,
    // Largest view angle of the slice inside the frustum.
    theta_hi: f32,
}

// Unpacks one entry of the `slices` binding (x = delta, y = theta_ref, z = theta_lo,
// w = theta_hi). No mirror: the CPU reads `SliceParams` directly.
fn slice_params(v: vec4<f32>) -> SliceParams {
    return SliceParams(v.x, v.y, v.z, v.w);
}

// Unit vector of slice angle `phi` (perpendicular to the axis).
fn slice_e(f: Frame, phi: f32) -> vec3<f32> {
    return f.e1_.xyz * cos(phi) + f.e2_.xyz * sin(phi);
}

// Slice angle at the centre of row `row`.
fn row_phi(f: Frame, row: u32) -> f32 {
    return f.e1_[3] + (f32(row) + 0.5) * f.e2_[3];
}

// Normalised rectified depth of view angle `theta`, the frame's view angles spanning
// [`lo`, `hi`] (`Frame::theta`).
fn normalised_depth(theta: f32, lo: f32, hi: f32) -> f32 {
    return DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp((theta - lo) / max(hi - lo, 1e-6), 0.0, 1.0);
}

// Rectified depths use [DEPTH_MARGIN, 1 - DEPTH_MARGIN]: the Fourier series of the step
// is 2-periodic, so depth differences near +-1 (a ray at the very start of the range
// against an empty light ray) would fall on the periodic copy's discontinuity.
const DEPTH_MARGIN: f32 = 0.1f;

// Smallest cone factor of a spot texel weight: where a region of the reference ray lies
// outside the cone, its texels still average (nearly uniformly) instead of leaving the
// region's mean undefined (all-zero weights store F = 0, i.e. visibility 0.5), because a
// pixel's own ray may cross the cone where the reference ray does not.
const CONE_FLOOR: f32 = 1e-3f;

// Fourier frequency `c_k = pi (2k - 1)`.
fn freq(k: u32) -> f32 {
    return PI * f32(2u * k - 1u);
}

// Basis values of layer `layer` at depth `d`: `(sin c1 d, cos c1 d, sin c2 d, cos c2 d)`
// with `k1 = 2 layer + 1`, `k2 = 2 layer + 2` (Klehm Eq. 8: B_{2k-1} = sin, B_{2k} = cos).
fn basis4(d: f32, layer: u32) -> vec4<f32> {
    let c1 = freq(2u * layer + 1u);
    let c2 = freq(2u * layer + 2u);
    return vec4<f32>(sin(c1 * d), cos(c1 * d), sin(c2 * d), cos(c2 * d));
}

// Coefficients of layer `layer` for a ray of depth `d`:
// `(2/c1 cos c1 d, -2/c1 sin c1 d, 2/c2 cos c2 d, -2/c2 sin c2 d)`, so that
// `V = 0.5 + sum a . B` approximates the step `H(d_i - d)`.
fn coeff4(d: f32, layer: u32) -> vec4<f32> {
    let c1 = freq(2u * layer + 1u);
    let c2 = freq(2u * layer + 2u);
    return vec4<f32>(
        2.0 / c1 * cos(c1 * d),
        -2.0 / c1 * sin(c1 * d),
        2.0 / c2 * cos(c2 * d),
        -2.0 / c2 * sin(c2 * d),
    );
}

// First column of region `r` of `regions` in a row of `width` columns. Directional lights
// split rows quadratically (`width r^2 / regions^2`): transmittance concentrates the
// integrand near the eye (column 0), and finer regions there cut the reference-ray
// weighting error. Spot lights split uniformly (`width r / regions`), as in the paper.
fn region_start(r: u32, regions: u32, width: u32, spot: bool) -> u32 {
    if spot {
        return r * width / regions;
    }
    return r * r * width / (regions * regions);
}

// Distance from the eye, along the slice's reference ray, of column edge `x` (continuous,
// in columns), capped at four far-plane distances.
fn ref_t(f: Frame, s: SliceParams, x: f32, spot: bool) -> f32 {
    let cap = 4.0 * f.theta[2];
    if spot {
        let psi = x * s.delta;
        let den = sin(s.theta_ref + psi);
        if den <= 1e-4 || s.theta_ref + psi >= PI {
            return cap;
        }
        return min(f.axis[3] * sin(psi) / den, cap);
    } else {
        return min(x * s.delta / max(sin(s.theta_ref), 1e-4), cap);
    }
}

// Prefilter weight of column `i` of row `row`: the length of the reference ray it covers
// (average), or the transmittance integral over that span (weighted), times the cone
// falloff and `exp(-sigma_t r) / r^2` at the span's middle for a spot light.
fn texel_weight(f: Frame, s: SliceParams, row: u32, i: u32, weighted: bool, spot: bool) -> f32 {
    let t0 = ref_t(f, s, f32(i), spot);
    let t1 = ref_t(f, s, f32(i + 1u), spot);
    if !weighted {
        return t1 - t0;
    }
    var w = transmittance_between(f.medium[0], t0, t1);
    if spot {
        let psi = (f32(i) + 0.5) * s.delta;
        let e = slice_e(f, row_phi(f, row));
        let l = -f.axis.xyz * cos(psi) + e * sin(psi);
        let den = max(sin(s.theta_ref + psi), 1e-4);
        let r = max(f.axis[3] * sin(s.theta_ref) / den, 1e-4);
        let cone = max(cone_falloff(dot(l, f.light_dir.xyz), f.light_pos[3], f.light_dir[3]), CONE_FLOOR);
        w *= cone * exp(-f.medium[0] * r) / (r * r);
    }
    return w;
}

// The frame's standard shadow map (`scatter::shadow`).
fn sm_view(f: Frame) -> ShadowMapView {
    return ShadowMapView(f.sm_right, f.sm_up, f.sm_forward, f.sm_origin, f.sm_proj, vec4<u32>(f.sizes2_[0], 0u, 0u, 0u));
}

// Standard shadow-map visibility of world point `p` (1 lit, 0 shadowed), as the `shadow_map`
// ground truth tests it. `sm`: the kernel's r32float `shadow_map` binding.
fn sm_visibility(f: Frame, sm: texture_2d<f32>, p: vec3<f32>) -> f32 {
    return shadow_visibility(sm_view(f), sm, p);
}

// Travel distance from `o` along the light ray `o + s l` to its first occluder, or
// NO_OCCLUDER (`scatter::shadow::shadow_occluder_distance`).
fn sm_occluder_distance(f: Frame, sm: texture_2d<f32>, o: vec3<f32>, l: vec3<f32>) -> f32 {
    return shadow_occluder_distance(sm_view(f), sm, o, l);
}

// ---- Projective rectification (Sec. 4.2; conventions: `ProjectiveMaps` and
// `projective_frame` in scatter_shaderlib::prefiltered::frame). Light space: eye at the
// origin, x = e1 (the fan's bisectrix), y = e2, z = axis. Row k = qy / qx, ray depth
// m = qz / qx, column invariant G = 1 / qx (sun) or (D - qz) / qx (spot); region r maps G
// linearly from G_r to G_(r+1) onto its columns.

// Column invariant G_r of region boundary `r` (0..=8).
fn proj_boundary(f: Frame, r: u32) -> f32 {
    var v = f.proj_g2_;
    if r < 4u {
        v = f.proj_g0_;
    } else if r < 8u {
        v = f.proj_g1_;
    }
    return v[r % 4u];
}

// Column invariant at continuous column `x` of region `r`.
fn proj_region_g(f: Frame, x: f32, r: u32, regions: u32, width: u32, spot: bool) -> f32 {
    let b0 = f32(region_start(r, regions, width, spot));
    let b1 = f32(region_start(r + 1u, regions, width, spot));
    return mix(proj_boundary(f, r), proj_boundary(f, r + 1u), (x - b0) / (b1 - b0));
}

// Continuous column of column invariant `g` (outside the map: extrapolated from the first
// or last region).
fn proj_column(f: Frame, g: f32, regions: u32, width: u32, spot: bool) -> f32 {
    var r = 0u;
    for (; r + 1u < regions; r++) {
        if g > proj_boundary(f, r + 1u) {
            break;
        }
    }
    let g0 = proj_boundary(f, r);
    let g1 = proj_boundary(f, r + 1u);
    let b0 = f32(region_start(r, regions, width, spot));
    let b1 = f32(region_start(r + 1u, regions, width, spot));
    return b0 + (b1 - b0) * (g0 - g) / (g0 - g1);
}

// qx where a view ray of depth `m` meets the light rays of invariant `g`: 1 / g (sun),
// D / (g + m) (spot); `cap` when it never does or lies beyond `cap`.
fn proj_reach(f: Frame, g: f32, m: f32, spot: bool, cap: f32) -> f32 {
    var num = 1.0;
    var den = g;
    if spot {
        num = f.axis[3];
        den = g + m;
    }
    if den * cap <= num {
        return cap;
    }
    return num / den;
}

// Normalised rectified depth of a view ray of depth `m` (lit iff it is <= the stored depth).
fn proj_ray_depth(f: Frame, m: f32) -> f32 {
    return DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp((f.proj[2] - m) * f.proj[3], 0.0, 1.0);
}

// Normalised rectified depth of a rasterised texel (clip z / w in [0, 1]).
fn proj_stored_depth(raw: f32) -> f32 {
    return DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp(raw, 0.0, 1.0);
}

// Projective counterpart of `texel_weight` for column `i` of region `r`: the exact span of
// the row's reference ray (direction e1 + k e2 + m_ref axis) that the texel covers, from the
// projective map itself (Klehm's Eq. 12 assumes a constant growth factor per texel; the
// spans of a perspective map grow hyperbolically, so the exact spans are used instead).
// Column 0 also covers the ray from the eye to the map's first light ray.
fn proj_texel_weight(f: Frame, s: SliceParams, i: u32, r: u32, regions: u32, weighted: bool, spot: bool) -> f32 {
    let width = f.sizes[2];
    let k = s.delta;
    let m = s.theta_ref;
    let len = sqrt(1.0 + k * k + m * m);
    let cap = 4.0 * f.theta[2];
    var t0 = 0.0;
    if i > 0u {
        t0 = proj_reach(f, proj_region_g(f, f32(i), r, regions, width, spot), m, spot, cap / len) * len;
    }
    let t1 = proj_reach(f, proj_region_g(f, f32(i + 1u), r, regions, width, spot), m, spot, cap / len) * len;
    if !weighted {
        return t1 - t0;
    }
    var w = transmittance_between(f.medium[0], t0, t1);
    if spot {
        let dir = (f.e1_.xyz + f.e2_.xyz * k + f.axis.xyz * m) / len;
        let to = f.eye.xyz + dir * (0.5 * (t0 + t1)) - f.light_pos.xyz;
        let dl = max(length(to), 1e-4);
        let cone = max(cone_falloff(dot(to / dl, f.light_dir.xyz), f.light_pos[3], f.light_dir[3]), CONE_FLOOR);
        w *= cone * exp(-f.medium[0] * dl) / (dl * dl);
    }
    return w;
}
