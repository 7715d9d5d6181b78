//! `scatter-conformance`: the GPU test harness shared by the conformance tests.
//!
//! [`gpu`] hands every test the same [`Context`], or `None` with a loud skip message, as the
//! `SCATTER_GPU` / `CI` policy says (see [`scatter_runtime::GpuPolicy`]): locally a missing
//! adapter skips GPU trials, under CI it fails them. Trials are named
//! `family::kernel::variant::case` (e.g. `common::row_prefix::mean::37x5x2`) in every message.

use std::io::Write as _;
use std::sync::OnceLock;

use scatter_reference::kernels::row_prefix as row_prefix_mirror;
use scatter_runtime::{ArraySize, Context, GpuPolicy};
use scatter_shaderlib::RowPrefixMode;

/// The shared GPU context, or `None` when GPU trials must be skipped.
///
/// # Panics
///
/// When the policy is `required` (explicitly, or because `CI` is set) and no context can be
/// created, or when `SCATTER_GPU` is invalid: the test fails with the reason.
pub fn gpu() -> Option<&'static Context> {
    static GPU: OnceLock<Option<Context>> = OnceLock::new();
    let ctx = GPU.get_or_init(|| {
        let policy = GpuPolicy::from_env().unwrap_or_else(|e| panic!("scatter-conformance: {e}"));
        let reason = match policy {
            GpuPolicy::Off => "GPU work switched off".to_owned(),
            GpuPolicy::Auto | GpuPolicy::Required => match Context::new() {
                Ok(ctx) => {
                    loud(&format!(
                        "scatter-conformance: GPU adapter: {}",
                        ctx.report()
                    ));
                    return Some(ctx);
                }
                Err(e) if policy == GpuPolicy::Required => panic!(
                    "scatter-conformance: SCATTER_GPU=required (explicitly or because CI is \
                     set) but no GPU context: {e} (scripts/test.sh installs lavapipe)"
                ),
                Err(e) => e.to_string(),
            },
        };
        loud(&format!(
            "scatter-conformance: !!! GPU TRIALS SKIPPED (SCATTER_GPU={policy}): {reason}; set \
             SCATTER_GPU=required to fail instead !!!"
        ));
        None
    });
    if ctx.is_none() {
        eprintln!("scatter-conformance: GPU trial skipped (no GPU context)");
    }
    ctx.as_ref()
}

/// Writes a line straight to the process's stderr, past libtest's output capture (which
/// only catches `print!`/`eprint!`), so adapter reports and skips show in every run.
fn loud(line: &str) {
    // Nothing sensible to do if stderr is gone.
    let _ = writeln!(std::io::stderr().lock(), "{line}");
}

/// The mirror's mode for a shaderlib mode. Exhaustive: a new mode needs its mirror.
pub fn row_prefix_mirror_mode(mode: RowPrefixMode) -> row_prefix_mirror::Mode {
    match mode {
        RowPrefixMode::Sum => row_prefix_mirror::Mode::Sum,
        RowPrefixMode::Mean => row_prefix_mirror::Mode::Mean,
    }
}

/// The mirror's dimensions for a runtime array size.
pub fn mirror_dims(size: ArraySize) -> row_prefix_mirror::Dims {
    row_prefix_mirror::Dims {
        width: size.width,
        height: size.height,
        layers: size.layers,
    }
}

/// Deterministic test texels in [-1, 1) (the range of Fourier basis values), from a
/// 64-bit LCG seeded by `seed`: the same inputs on every machine.
pub fn test_texels(count: usize, seed: u64) -> Vec<[f32; 4]> {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        // Top 24 bits: exactly representable in f32.
        ((state >> 40) as f32 / (1u32 << 24) as f32) * 2.0 - 1.0
    };
    (0..count)
        .map(|_| [next(), next(), next(), next()])
        .collect()
}

/// Distance between two f32 in units in the last place (0 for equal values, including
/// +0 and -0; `u32::MAX` when either is NaN).
pub fn ulp_distance(a: f32, b: f32) -> u32 {
    if a.is_nan() || b.is_nan() {
        return u32::MAX;
    }
    // Map the sign-magnitude bit patterns onto a monotonic integer line.
    let key = |x: f32| {
        let bits = x.to_bits() as i32;
        if bits < 0 { i32::MIN - bits } else { bits }
    };
    key(a).abs_diff(key(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ulp_distance_counts_representable_steps() {
        assert_eq!(ulp_distance(1.0, 1.0), 0);
        assert_eq!(ulp_distance(0.0, -0.0), 0);
        assert_eq!(ulp_distance(1.0, 1.0 + f32::EPSILON), 1);
        assert_eq!(
            ulp_distance(-f32::MIN_POSITIVE, f32::MIN_POSITIVE),
            2 * 0x0080_0000
        );
        assert_eq!(ulp_distance(f32::NAN, 1.0), u32::MAX);
    }

    #[test]
    fn test_texels_are_deterministic_and_in_range() {
        let a = test_texels(100, 7);
        assert_eq!(a, test_texels(100, 7));
        assert_ne!(a, test_texels(100, 8));
        assert!(a.iter().flatten().all(|v| (-1.0..1.0).contains(v)));
    }
}
