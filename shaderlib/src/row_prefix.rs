//! The `row_prefix` kernel: per-row running sum or mean over an rgba texture array, one
//! invocation per (row, layer). Template `templates/row_prefix.wgsl`, CPU mirror
//! `reference/src/kernels/row_prefix.rs`.

use askama::Template;

use crate::compose::template_path;
use crate::{Kernel, ShaderError};

/// What the kernel accumulates along a row.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    Hash,
    PartialOrd,
    Ord,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum RowPrefixMode {
    /// Inclusive prefix sum: `out[x] = in[0] + ... + in[x]`.
    Sum,
    /// Running mean blended as in Klehm et al. 2014, Listing 1:
    /// `F = mix(F, in[x], 1 / (x + 1))`, so `out[x]` is the mean of `in[0..=x]`.
    #[default]
    Mean,
}

impl RowPrefixMode {
    /// Both modes, sorted by name.
    pub const ALL: &'static [Self] = &[Self::Mean, Self::Sum];

    /// The mode's name, as used in trial names and serde.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Sum => "sum",
            Self::Mean => "mean",
        }
    }
}

/// Template parameters of `row_prefix`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RowPrefixParams {
    /// Sum or running mean.
    pub mode: RowPrefixMode,
    /// Invocations (rows) per workgroup, 1..=[`Self::MAX_WORKGROUP_SIZE`]. Devices may allow
    /// less (WebGPU's default limit is 256); the runtime checks the device limit.
    pub workgroup_size: u32,
}

impl RowPrefixParams {
    /// Default invocations per workgroup: small enough for any device, a multiple of every
    /// common subgroup size.
    pub const DEFAULT_WORKGROUP_SIZE: u32 = 64;
    /// Largest workgroup size the template accepts (Vulkan/Metal/D3D12 ceiling).
    pub const MAX_WORKGROUP_SIZE: u32 = 1024;

    /// Number of workgroups to dispatch for a `height` x `layers` array: one invocation per
    /// (row, layer), rows rounded up to whole workgroups.
    pub const fn dispatch_size(&self, height: u32, layers: u32) -> [u32; 3] {
        [height.div_ceil(self.workgroup_size), layers, 1]
    }

    /// Checks every parameter against its allowed range.
    ///
    /// # Errors
    ///
    /// [`ShaderError::InvalidParameter`] naming the knob.
    pub fn validate(&self) -> Result<(), ShaderError> {
        if self.workgroup_size == 0 || self.workgroup_size > Self::MAX_WORKGROUP_SIZE {
            return Err(ShaderError::InvalidParameter {
                kernel: Kernel::RowPrefix,
                knob: "workgroup_size",
                value: self.workgroup_size.to_string(),
                allowed: "1..=1024",
            });
        }
        Ok(())
    }
}

impl Default for RowPrefixParams {
    fn default() -> Self {
        Self {
            mode: RowPrefixMode::default(),
            workgroup_size: Self::DEFAULT_WORKGROUP_SIZE,
        }
    }
}

/// The askama view of `templates/row_prefix.wgsl`: plain values computed in Rust.
#[derive(Template)]
#[template(path = "row_prefix.wgsl")]
struct RowPrefixTemplate {
    mode_name: &'static str,
    mean: bool,
    workgroup_size: u32,
}

/// Renders `templates/row_prefix.wgsl` for `params`.
pub(crate) fn render(params: &RowPrefixParams) -> Result<String, ShaderError> {
    params.validate()?;
    RowPrefixTemplate {
        mode_name: params.mode.name(),
        mean: params.mode == RowPrefixMode::Mean,
        workgroup_size: params.workgroup_size,
    }
    .render()
    .map_err(|source| ShaderError::Render {
        kernel: Kernel::RowPrefix,
        template: template_path(Kernel::RowPrefix),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{KernelParams, build};

    #[test]
    fn modes_render_their_own_blend() {
        let mean = render(&RowPrefixParams::default()).expect("renders");
        assert!(mean.contains("mix(acc, texel"), "{mean}");
        let sum = render(&RowPrefixParams {
            mode: RowPrefixMode::Sum,
            ..RowPrefixParams::default()
        })
        .expect("renders");
        assert!(sum.contains("acc = acc + texel"), "{sum}");
        assert!(!sum.contains("mix("), "{sum}");
    }

    #[test]
    fn workgroup_size_is_read_back_from_the_ir() {
        for size in [1, 37, 256, 1024] {
            let built = build(&KernelParams::RowPrefix(RowPrefixParams {
                workgroup_size: size,
                ..RowPrefixParams::default()
            }))
            .expect("builds");
            assert_eq!(built.workgroup_size, [size, 1, 1]);
        }
    }

    #[test]
    fn bad_workgroup_size_is_an_error_naming_the_knob() {
        for size in [0, 1025, u32::MAX] {
            let err = build(&KernelParams::RowPrefix(RowPrefixParams {
                workgroup_size: size,
                ..RowPrefixParams::default()
            }))
            .expect_err("rejected");
            let text = err.to_string();
            assert!(
                text.contains("row_prefix") && text.contains("workgroup_size"),
                "{text}"
            );
        }
    }

    #[test]
    fn dispatch_covers_every_row() {
        let p = RowPrefixParams::default();
        assert_eq!(p.dispatch_size(1, 1), [1, 1, 1]);
        assert_eq!(p.dispatch_size(64, 3), [1, 3, 1]);
        assert_eq!(p.dispatch_size(65, 3), [2, 3, 1]);
    }
}
