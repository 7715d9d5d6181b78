// scatter::epipolar: what every family built on the epipolar set-up shares and no family owns
// (`prefiltered`, `minmax`, and the coming ones): the `Frame` uniform block, the per-slice
// parameters, the rectified-space depth, the frame's standard shadow map, the pixel's view
// ray, the epipole march and the spot quadrature of a ray span.
//
// Composed into kernels by naga_oil (`#import scatter::epipolar::{...}`); plain WGSL, not an
// askama template. Conventions: `scatter_frame::frame`. Mirrored line by line by
// reference/src/kernels/common_epipolar.rs; functions that read a texture take it as a
// parameter (a shared module cannot see the kernel's bindings).

#define_import_path scatter::epipolar

#import scatter::model::{PI, equiangular, equiangular_sample, phase_hg, spot_integrand, spot_span, transmittance_between}
#import scatter::shadow::{ShadowMapView, shadow_occluder_distance_orthographic, shadow_occluder_distance_perspective, shadow_visibility_for}

// The uniform block (host: `scatter_shaderlib::prefiltered::FrameUniforms`, field by field;
// every member is 16 bytes, 27 * 16 = 432 bytes in all). The host's `e1`, `e2`, `sizes2` and
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
    // Rows aligned with the epipolar sampling's slices (fan_angles.z = 1): the slices'
    // origin on screen (pixels) in xy, the unit screen direction of angle 0 in zw.
    fan_origin: vec4<f32>,
    // Aligned rows: x = screen angle where row 0 starts, y = screen angle per row, z = 1;
    // all zero for rows uniform in the angle around the light axis.
    fan_angles: vec4<f32>,
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

// Slice angle at the centre of row `row`: uniform in the angle around the light axis, or,
// with rows aligned with the epipolar sampling's slices (`f.fan_angles.z`; variants with
// `sampling = epipolar`), that of the plane of the row's screen slice (`fan_phi`), so that a
// sample on slice s reads row s's light rays, not a neighbour's up to half a row away.
// Selected, not branched on (a uniform: `scatter_shaderlib::uniform_branches`).
fn row_phi(f: Frame, row: u32) -> f32 {
    return select(axis_row_phi(f, row), fan_phi(f, row), f.fan_angles[2] > 0.5);
}

// Slice angle at the centre of row `row` of rows uniform in the angle around the light axis:
// `row_phi` of a frame whose rows do not follow the sampling's slices.
fn axis_row_phi(f: Frame, row: u32) -> f32 {
    return f.e1_[3] + (f32(row) + 0.5) * f.e2_[3];
}

// The screen size in pixels.
fn screen_size(f: Frame) -> vec2<f32> {
    return vec2<f32>(f32(f.sizes[0]), f32(f.sizes[1]));
}

// Unit view direction through screen position `p` (pixels from the top-left corner).
fn screen_dir(f: Frame, p: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>(2.0 * p.x / f32(f.sizes[0]) - 1.0, 1.0 - 2.0 * p.y / f32(f.sizes[1]));
    let t = f.cam_forward[3];
    return normalize(f.cam_forward.xyz + f.cam_right.xyz * (ndc.x * t * f.cam_right[3]) + f.cam_up.xyz * (ndc.y * t));
}

// Distance from `o` along `u` of the midpoint of the line's part inside the rectangle of
// pixel centres of a screen of `size` pixels (its nearest point when it misses it). Both axes
// at once, each kept where the line crosses it: the values of a loop over the two axes with
// `o[a]`, `u[a]`, without the loop and its dynamic component index. That loop, inlined into
// `partial_sum_tree`'s fallback (its leaves call `row_phi`) and loaded from the SPIR-V
// target, lost colour channels or whole pixels on lavapipe in one frame of three or four
// (which ones varied between runs; 0 of 60 runs since).
fn fan_line_mid(o: vec2<f32>, u: vec2<f32>, size: vec2<f32>) -> f32 {
    let ta = (vec2<f32>(0.5, 0.5) - o) / u;
    let tb = (size - vec2<f32>(0.5, 0.5) - o) / u;
    let crosses = abs(u) > vec2<f32>(1e-12, 1e-12);
    let enter = select(vec2<f32>(0.0, 0.0), min(ta, tb), crosses);
    let leave = select(vec2<f32>(3.4e38, 3.4e38), max(ta, tb), crosses);
    let t_in = max(0.0, max(enter.x, enter.y));
    let t_out = min(3.4e38, min(leave.x, leave.y));
    return 0.5 * (t_in + max(t_out, t_in));
}

// The slice angle (around the light axis) of aligned row `row`: that of the view ray through
// the midpoint of its screen slice, the line from `f.fan_origin.xy` at screen angle
// `fan_angles.x + (row + 1/2) fan_angles.y` (every point of the line lies on one plane
// through the axis when the origin is the epipole; the midpoint keeps a near-infinite
// epipole, whose origin the layout clamps, on the slice's own plane).
fn fan_phi(f: Frame, row: u32) -> f32 {
    let a = f.fan_angles[0] + (f32(row) + 0.5) * f.fan_angles[1];
    let ax = f.fan_origin.zw;
    let u = vec2<f32>(ax.x * cos(a) - ax.y * sin(a), ax.y * cos(a) + ax.x * sin(a));
    let d = screen_dir(f, f.fan_origin.xy + u * fan_line_mid(f.fan_origin.xy, u, screen_size(f)));
    return atan2(dot(d, f.e2_.xyz), dot(d, f.e1_.xyz));
}

// Normalised rectified depth of view angle `theta`, the frame's view angles spanning
// [`lo`, `hi`] (`Frame::theta`).
fn normalised_depth(theta: f32, lo: f32, hi: f32) -> f32 {
    return DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * clamp((theta - lo) / max(hi - lo, 1e-6), 0.0, 1.0);
}

// Normalised rectified depth of the first occluder of a light ray at view angle `theta`: the
// same map as `normalised_depth`, clamped to [0, 1] instead of the view rays'
// [DEPTH_MARGIN, 1 - DEPTH_MARGIN]. An occluder before every view ray of the frame (or none)
// then lies up to DEPTH_MARGIN away from the nearest ray depth, not on it, so the Fourier
// step does not blur it into half a light (a sun below the horizon lit 6 % of a lit frame's
// maximum at the frame's low-angle border, issue 12).
fn occluder_depth(theta: f32, lo: f32, hi: f32) -> f32 {
    return clamp(DEPTH_MARGIN + (1.0 - 2.0 * DEPTH_MARGIN) * ((theta - lo) / max(hi - lo, 1e-6)), 0.0, 1.0);
}

// View-ray depths use [DEPTH_MARGIN, 1 - DEPTH_MARGIN], occluder depths [0, 1]: the Fourier
// series of the step is 2-periodic, so depth differences near +-1 would fall on the
// periodic copy's discontinuity; the largest difference is 0.9.
const DEPTH_MARGIN: f32 = 0.1f;

// The frame's standard shadow map (`scatter::shadow`).
fn sm_view(f: Frame) -> ShadowMapView {
    return ShadowMapView(f.sm_right, f.sm_up, f.sm_forward, f.sm_origin, f.sm_proj, vec4<u32>(f.sizes2_[0], 0u, 0u, 0u));
}

// Standard shadow-map visibility of world point `p` (1 lit, 0 shadowed), as the `shadow_map`
// ground truth tests it. `sm`: the kernel's r32float `shadow_map` binding.
// `spot`: the kernel's light switch (a template constant: the other light's test is
// compiled out, `scatter::shadow::shadow_visibility_for`).
fn sm_visibility(f: Frame, sm: texture_2d<f32>, p: vec3<f32>, spot: bool) -> f32 {
    return shadow_visibility_for(sm_view(f), sm, p, spot);
}

// Travel distance along a light ray to its first occluder, or
// NO_OCCLUDER (`scatter::shadow::shadow_occluder_distance`); the sun's light ray from `o`
// along the light's direction, a spot's from the light along `l`, for kernels generated for
// one light kind.
fn sm_occluder_distance_sun(f: Frame, sm: texture_2d<f32>, o: vec3<f32>) -> f32 {
    return shadow_occluder_distance_orthographic(sm_view(f), sm, o);
}

fn sm_occluder_distance_spot(f: Frame, sm: texture_2d<f32>, l: vec3<f32>) -> f32 {
    return shadow_occluder_distance_perspective(sm_view(f), sm, l);
}


// Unit view direction through the centre of pixel (x, y).
fn pixel_dir(f: Frame, x: u32, y: u32) -> vec3<f32> {
    let ndc_x = 2.0 * (f32(x) + 0.5) / f32(f.sizes[0]) - 1.0;
    let ndc_y = 1.0 - 2.0 * (f32(y) + 0.5) / f32(f.sizes[1]);
    let t = f.cam_forward[3];
    return normalize(f.cam_forward.xyz + f.cam_right.xyz * (ndc_x * t * f.cam_right[3]) + f.cam_up.xyz * (ndc_y * t));
}

// The spot integrand at ray parameter `t` with the light and medium of the frame.
fn frame_spot_integrand(f: Frame, eye: vec3<f32>, dir: vec3<f32>, t: f32) -> f32 {
    return spot_integrand(eye, dir, t, f.light_pos.xyz, f.light_dir.xyz, f.light_pos[3], f.light_dir[3], f.medium);
}

// In-scattering along `[a, b]` of the pixel's ray by marching `steps` samples against the
// standard shadow map `sm`, without `sigma_s p E` for the sun (as `lit_span`). The sun: cell
// midpoints uniform in `t`, each with the exact transmittance integral of its cell. A spot:
// the midpoints of `steps` equiangular strata of `[a, b]` (`scatter::model::equiangular`),
// each weighted by `1 / (steps pdf)`, so the 1/d^2 peak of a ray passing next to the lamp is
// sampled by its angle (uniform midpoints in `t` overshot the truth 5.6x next to a lamp on
// screen); its integrand carries `sigma_s p`. The epipole discs march `[0, s]`
// (`epipole_march`); `volume_march` marches the span its shadow-volume bounds leave open.
fn span_march(f: Frame, sm: texture_2d<f32>, eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32, steps: u32, spot: bool) -> f32 {
    let h = (b - a) / f32(steps);
    let strata = equiangular(eye, dir, f.light_pos.xyz, a, b, steps);
    var sum = 0.0;
    // `k + 1u <= steps`, not `k < steps`: lavapipe re-specialises a shader at every dispatch
    // when a loop compares its counter with a uniform count (`scatter_shaderlib::uniform_branches`).
    for (var k = 0u; k + 1u <= steps; k++) {
        var t = a + (f32(k) + 0.5) * h;
        var w = h;
        if spot {
            let tw = equiangular_sample(strata, f32(k) + 0.5);
            t = tw.x;
            w = tw.y;
        }
        let v = sm_visibility(f, sm, eye + dir * t, spot);
        if spot {
            sum += v * w * frame_spot_integrand(f, eye, dir, t);
        } else {
            sum += v * transmittance_between(f.medium[0], a + f32(k) * h, a + f32(k + 1u) * h);
        }
    }
    return sum;
}

// In-scattering along `[0, s]` of the pixel's ray by marching `f.sizes2_[1]` samples against
// the standard shadow map (`span_march`): the epipole and anti-epipole discs of every
// epipolar family, where the rectification degenerates (Klehm Sec. 5); without the light
// colour.
fn epipole_march(f: Frame, sm: texture_2d<f32>, eye: vec3<f32>, dir: vec3<f32>, s: f32, spot: bool) -> f32 {
    let sum = span_march(f, sm, eye, dir, 0.0, s, f.sizes2_[1], spot);
    if spot {
        return sum;
    } else {
        return f.medium[1] * phase_hg(f.medium[2], -dot(f.light_dir.xyz, dir)) * sum;
    }
}

// Whether the pixel centred at `pc` lies in the epipole's or the anti-epipole's disc (radius
// `epipole.w`, where the rectification degenerates and the families march instead; mirrors
// `in_epipole_disc` of reference/src/kernels/common_epipolar.rs). `&`, not `&&`: naga writes a
// short-circuit as a branch, here on a uniform, and lavapipe re-specialises a shader branching
// on uniforms at every dispatch (`scatter_shaderlib::uniform_branches`).
fn in_epipole_disc(f: Frame, pc: vec2<f32>) -> bool {
    let radius = f.epipole[3];
    let near_epi = (f.epipole[2] > 0.5) & (length(pc - f.epipole.xy) < radius);
    let near_anti = (f.anti_epipole[2] > 0.5) & (length(pc - f.anti_epipole.xy) < radius);
    return near_epi | near_anti;
}

// Row of the `slices` table for row coordinate `j` (a whole number): wrapped around when
// the slices cover the full circle, else clamped.
fn row_index(j: f32, rows: u32, wrap: bool) -> u32 {
    let ji = i32(j);
    // Selected, not branched on (`wrap` is a uniform's: `scatter_shaderlib::uniform_branches`).
    return select(u32(clamp(ji, 0, i32(rows) - 1)), u32(((ji % i32(rows)) + i32(rows)) % i32(rows)), wrap);
}

// Distance along the pixel's own ray (angle `theta` to the axis) of column edge `x`, capped
// at the surface distance `s`.
fn ray_t(f: Frame, x: f32, delta: f32, theta: f32, s: f32, spot: bool) -> f32 {
    if spot {
        let psi = x * delta;
        let den = sin(theta + psi);
        if den <= 1e-6 || theta + psi >= PI {
            return s;
        }
        return min(f.axis[3] * sin(psi) / den, s);
    } else {
        return min(x * delta / max(sin(theta), 1e-6), s);
    }
}

// View angle of direction `dir` to the axis (atan2: accurate near the axis, where acos loses
// digits).
fn ray_theta(f: Frame, dir: vec3<f32>) -> f32 {
    let axis = f.axis.xyz;
    return atan2(length(cross(dir, axis)), dot(dir, axis));
}

// Continuous row coordinate of the slice holding direction `dir`: its slice angle in rows
// from the first row's start (with aligned rows, `row_phi`, its screen angle around the
// fan's origin in rows), wrapped into [0, rows) when the slices cover the full circle,
// else clamped to [0, rows]. Row `floor(yc)` is the nearest (`row_index`).
fn ray_row_coord(f: Frame, dir: vec3<f32>) -> f32 {
    let rows = f.sizes[3];
    let phi = atan2(dot(dir, f.e2_.xyz), dot(dir, f.e1_.xyz));
    // Aligned rows (`row_phi`): the screen angle of the ray's screen point around the fan's
    // origin, in rows.
    let z = dot(dir, f.cam_forward.xyz);
    let t = f.cam_forward[3];
    let ndc = vec2<f32>(dot(dir, f.cam_right.xyz) / (z * t * f.cam_right[3]), dot(dir, f.cam_up.xyz) / (z * t));
    let p = vec2<f32>((ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5) * screen_size(f);
    let d = p - f.fan_origin.xy;
    let ax = f.fan_origin.zw;
    let fan = (atan2(ax.x * d.y - ax.y * d.x, ax.x * d.x + ax.y * d.y) - f.fan_angles[0]) / f.fan_angles[1];
    let yc = select((phi - f.e1_[3]) / f.e2_[3], fan, f.fan_angles[2] > 0.5);
    // Selected, not branched on (a uniform: `scatter_shaderlib::uniform_branches`).
    return select(clamp(yc, 0.0, f32(rows)), yc - floor(yc / f32(rows)) * f32(rows), f.anti_epipole[3] > 0.5);
}

// Column coordinate, before division by a row's spacing, of the point at distance `s` along
// the view ray `dir` (view angle `theta`): the sun's distance from the axis, the spot's angle
// at the lamp from the direction towards the eye (atan2, not acos of the normalised cosine:
// acos loses digits near 0, where a point near the eye-lamp line lies, off by up to 5 % of
// its distance in the round-trip test). The inverse of `ray_t`.
fn ray_column(f: Frame, eye: vec3<f32>, dir: vec3<f32>, s: f32, theta: f32, spot: bool) -> f32 {
    if spot {
        let q = eye + dir * s - f.light_pos.xyz;
        let to_eye = -f.axis.xyz;
        return atan2(length(cross(q, to_eye)), dot(q, to_eye));
    }
    return s * sin(theta);
}

// View angle (to the axis) of the point at distance `s` along the light ray of column
// coordinate `col` in its slice: the sun's ray at distance `v = col` from the axis, leaving
// `eye + e v` along -axis; the spot's ray leaving the lamp at angle `psi = col` from the
// direction towards the eye. `ray_t` maps it back to a distance along the view ray.
fn light_point_theta(f: Frame, col: f32, s: f32, spot: bool) -> f32 {
    if spot {
        return atan2(s * sin(col), f.axis[3] - s * cos(col));
    } else {
        return atan2(col, -s);
    }
}

// Unshadowed spot in-scattering over `[a, b]` of the ray (`scatter::model::spot_span`).
fn spot_segment(f: Frame, eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32, panels: u32) -> f32 {
    return spot_span(eye, dir, a, b, panels, f.light_pos.xyz, f.light_dir.xyz, f.light_pos[3], f.light_dir[3], f.medium);
}

// Ray distance of column edge `x` of a ray that crosses texels 0 .. n: the last texel's
// span ends at the surface `s` (the texel walks of `minmax_traverse` and `pst_sweep`).
fn edge_t(f: Frame, x: u32, n: u32, delta: f32, theta: f32, s: f32, spot: bool) -> f32 {
    if x >= n {
        return s;
    }
    return ray_t(f, f32(x), delta, theta, s, spot);
}

// Unshadowed in-scattering over `[a, b]` of the ray, without `sigma_s p E` for the sun.
fn lit_span(f: Frame, eye: vec3<f32>, dir: vec3<f32>, a: f32, b: f32, spot: bool) -> f32 {
    if spot {
        return spot_segment(f, eye, dir, a, b, max(f.sizes2_[2] / 4u, 1u));
    }
    return transmittance_between(f.medium[0], a, b);
}
