//! A spot light's cookie ("gobo", stained glass): an RGB texture projected along the cone
//! that multiplies the light's intensity. Every family that supports it (a `cookie` knob)
//! takes the same texture and the same projection; the truths (`scatter_reference::truth`)
//! evaluate it the same way in f64.
//!
//! # The projection
//!
//! A point `x` lit by the spot at `p` is seen from the lamp along `d = x - p`. In the light's
//! frame (the spot's standard shadow map: `right`, `up`, `forward` of its
//! [`crate::frame::ShadowMapDesc`], `forward` the cone's axis) with `tan_outer` the tangent of
//! the outer half-angle,
//!
//! ```text
//! a = dot(d, right) / (dot(d, forward) tan_outer),   b = dot(d, up) / (dot(d, forward) tan_outer)
//! u = (a + 1) / 2,   v = (1 - b) / 2
//! ```
//!
//! so the texture's square circumscribes the outer cone (its corners are outside the cone,
//! where the falloff is 0) and row 0 is the top, as in the shadow map. The texture is read
//! with bilinear filtering between texel centres (`u W - 1/2`, `v H - 1/2`), clamped to the
//! edge; a point behind the lamp (`dot(d, forward) <= 0`) gets black. The filtering is done
//! in the kernel from four texel loads (no sampler binding), so any float format binds:
//! `rgba16float` is what the plans declare (linear RGB; alpha is ignored).
//!
//! A cookie is constant along each light ray, so it commutes with the shadow test: per
//! sample (`raymarch`) it multiplies the shadow-free integrand, which becomes RGB.

use crate::variant::{LightKind, VariantError};

/// The format the plans declare for the engine's cookie texture.
pub const COOKIE_FORMAT: &str = "rgba16float";

/// Checks the `cookie` knob against the light: a cookie needs a spot light.
///
/// # Errors
///
/// A [`VariantError`] naming `cookie` for a cookie on a directional light.
pub fn validate_cookie(cookie: bool, light: LightKind) -> Result<(), VariantError> {
    if cookie && light != LightKind::Spot {
        return Err(VariantError {
            knob: "cookie",
            value: "true".into(),
            allowed: format!(
                "false with light = {light} (a cookie is projected along a spot light's cone)"
            ),
        });
    }
    Ok(())
}

/// The variant-id suffix of the knob: `-cookie`, or nothing.
pub fn id_suffix(cookie: bool) -> &'static str {
    if cookie { "-cookie" } else { "" }
}

/// The texture coordinates `(u, v)` of the light-space direction `(x, y, z)` (components
/// along the frame's right, up and forward) for a cone of outer half-angle tangent
/// `tan_outer`, or `None` behind the lamp (`z <= 0`).
pub fn cookie_uv(x: f64, y: f64, z: f64, tan_outer: f64) -> Option<(f64, f64)> {
    if z <= 0.0 {
        return None;
    }
    let a = x / (z * tan_outer);
    let b = y / (z * tan_outer);
    Some((0.5 * (a + 1.0), 0.5 * (1.0 - b)))
}

/// Bilinear weights of texture coordinate `c` (0..1) over `n` texels: the two texel indices
/// (clamped to the edge) and the weight of the second.
pub fn bilinear_axis(c: f64, n: u32) -> (u32, u32, f64) {
    let x = c * f64::from(n) - 0.5;
    let x0 = x.floor();
    let f = x - x0;
    let last = i64::from(n) - 1;
    let i0 = (x0 as i64).clamp(0, last) as u32;
    let i1 = (x0 as i64 + 1).clamp(0, last) as u32;
    (i0, i1, f)
}
