{#- The cookie of a rectified texel, shared by `prefilter` (which folds it into the texel's
weight) and `scatter` with `resume` (which resumes the running means over texels). Needs
`frame`, `cookie`, STRIDE and REGIONS; mirrored by reference/src/kernels/prefilter.rs
(`texel_cookie`). -#}
// The cookie of texel `i` of a row (slice `slice`, slice direction `e`; in a projective frame
// column `i` of region `region`): that of the light ray through the texel's centre, constant
// along it. Epipolar: the ray leaving the lamp at angle psi = (i + 1/2) delta from the
// direction towards the eye, as `rectify` casts it. Projective: the ray of the column
// invariant G at the texel's centre in the row's plane k = slice.delta, along
// e1 + k e2 - G axis (light space: the lamp at D on the axis, G = (D - qz) / qx).
fn texel_cookie(i: u32, slice: SliceParams, e: vec3<f32>, region: u32, proj: bool) -> vec3<f32> {
    let col = (f32(i) + 0.5) * slice.delta;
    var l = -frame.axis.xyz * cos(col) + e * sin(col);
{%- if projective %}
    if proj {
        // The region layout of a map of Wr / STRIDE columns (`proj_texel_weight`).
        let g = proj_region_g(frame, (f32(i) + 0.5) / f32(STRIDE), region, REGIONS, frame.sizes[2] / STRIDE, true);
        l = frame.e1_.xyz + frame.e2_.xyz * slice.delta - frame.axis.xyz * g;
    }
{%- endif %}
    return frame_cookie(frame, cookie, frame.light_pos.xyz + l);
}
