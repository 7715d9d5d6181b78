//! The [`Kernel`] enum: one variant per WGSL template, named like its template file, its CPU
//! mirror (`reference/src/kernels/<name>.rs`) and its conformance trials.

use std::fmt;

/// Every kernel the library ships. Matches on it must stay exhaustive, so that a new kernel
/// cannot be added without its template, CPU mirror and tests.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum Kernel {
    /// Separable sum filter of interleaved sampling over the `raymarch` partial sums (Tóth &
    /// Umenhoffer 2009).
    InterleaveSum,
    /// The 1D min-max tree of every rectified row (Chen et al. 2011).
    MinmaxBuild,
    /// Per pixel: the rectified row marched through its min-max tree, skipping nodes wholly
    /// lit or shadowed; pixels near the epipole ray-marched (Chen et al. 2011).
    MinmaxTraverse,
    /// Fourier basis transform fused with the weighted running mean along each rectified
    /// row, per region (Klehm et al. 2014, Listings 1-3, Table 1).
    Prefilter,
    /// Brute-force ray marching through the standard shadow map, optionally interleaved
    /// (Tóth & Umenhoffer 2009).
    Raymarch,
    /// Epipolar resampling of a standard shadow map into the rectified shadow map (Klehm et
    /// al. 2014, Sec. 4.1, after Baran et al. 2010).
    Rectify,
    /// Per-row running prefix (sum or mean) over an rgba texture array; the filtering step
    /// of the prefiltered method (Klehm et al. 2014, Listing 1).
    RowPrefix,
    /// Per pixel: prefiltered visibility times the unshadowed integral, one dot product per
    /// region; pixels near the epipole ray-marched (Klehm et al. 2014, Listing 4, Sec. 5).
    Scatter,
}

impl Kernel {
    /// All kernels, sorted by name.
    pub const ALL: &'static [Self] = &[
        Self::InterleaveSum,
        Self::MinmaxBuild,
        Self::MinmaxTraverse,
        Self::Prefilter,
        Self::Raymarch,
        Self::Rectify,
        Self::RowPrefix,
        Self::Scatter,
    ];

    /// The kernel's name: template file stem, entry point, mirror module and trial name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::InterleaveSum => "interleave_sum",
            Self::MinmaxBuild => "minmax_build",
            Self::MinmaxTraverse => "minmax_traverse",
            Self::Prefilter => "prefilter",
            Self::Raymarch => "raymarch",
            Self::Rectify => "rectify",
            Self::RowPrefix => "row_prefix",
            Self::Scatter => "scatter",
        }
    }
}

impl fmt::Display for Kernel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
