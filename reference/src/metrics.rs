//! Error metrics between a method's image and a reference image, and over image sequences.
//!
//! All sums run over every pixel and all three channels, in f64:
//! - relative L1: `sum |L - R| / sum |R|`;
//! - relative RMSE: `sqrt(sum (L - R)^2) / sqrt(sum R^2)`;
//! - p99 over max: the 99th percentile (nearest rank) of the per-pixel error
//!   `max_c |L_c - R_c|`, divided by the reference's largest channel value;
//! - non-finite count: pixels of `L` with a NaN or infinite channel;
//! - flicker: mean absolute frame-to-frame change of the error image `e_t = L_t - R_t`,
//!   `sum_{t>=1} sum |e_t - e_{t-1}| / sum_{t>=1} sum |R_t|` (0 for an error that is steady
//!   over time, however large; a method whose error jumps between frames scores high).
//!
//! Non-finite pixels are excluded from the sums (they are counted separately), so one NaN
//! does not hide every other number.

use crate::image::Image;

/// Why two images cannot be compared.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MetricError {
    /// Sizes differ.
    #[error("image sizes differ: {0}x{1} vs {2}x{3}")]
    SizeMismatch(u32, u32, u32, u32),
    /// Sequences differ in length, or are too short.
    #[error("flicker needs two equally long sequences of >= 2 frames, got {0} and {1}")]
    Sequence(usize, usize),
}

/// Every per-image metric at once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorReport {
    /// Relative L1.
    pub rel_l1: f64,
    /// Relative RMSE.
    pub rel_rmse: f64,
    /// 99th-percentile per-pixel error over the reference's max radiance.
    pub p99_over_max: f64,
    /// Pixels with a NaN or infinite channel.
    pub non_finite: usize,
}

impl std::fmt::Display for ErrorReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "rel L1 {:.4} %, rel RMSE {:.4} %, p99/max {:.4} %, NaN/Inf {}",
            100.0 * self.rel_l1,
            100.0 * self.rel_rmse,
            100.0 * self.p99_over_max,
            self.non_finite
        )
    }
}

fn same_size(a: &Image, b: &Image) -> Result<(), MetricError> {
    if (a.width, a.height) == (b.width, b.height) {
        Ok(())
    } else {
        Err(MetricError::SizeMismatch(
            a.width, a.height, b.width, b.height,
        ))
    }
}

fn finite(c: &[f32; 3]) -> bool {
    c.iter().all(|x| x.is_finite())
}

/// Pixels of `img` with a NaN or infinite channel.
pub fn non_finite_count(img: &Image) -> usize {
    img.data.iter().filter(|c| !finite(c)).count()
}

/// Relative L1 error of `img` against `reference` (0 if both are black).
pub fn rel_l1(img: &Image, reference: &Image) -> Result<f64, MetricError> {
    same_size(img, reference)?;
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (a, r) in img.data.iter().zip(&reference.data) {
        if !finite(a) || !finite(r) {
            continue;
        }
        for c in 0..3 {
            num += (f64::from(a[c]) - f64::from(r[c])).abs();
            den += f64::from(r[c]).abs();
        }
    }
    Ok(ratio(num, den))
}

fn ratio(num: f64, den: f64) -> f64 {
    if den > 0.0 {
        num / den
    } else if num > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// Relative RMSE of `img` against `reference`.
pub fn rel_rmse(img: &Image, reference: &Image) -> Result<f64, MetricError> {
    same_size(img, reference)?;
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (a, r) in img.data.iter().zip(&reference.data) {
        if !finite(a) || !finite(r) {
            continue;
        }
        for c in 0..3 {
            let d = f64::from(a[c]) - f64::from(r[c]);
            num += d * d;
            den += f64::from(r[c]) * f64::from(r[c]);
        }
    }
    Ok(ratio(num.sqrt(), den.sqrt()))
}

/// 99th-percentile (nearest rank) per-pixel error over the reference's max channel value.
pub fn p99_over_max(img: &Image, reference: &Image) -> Result<f64, MetricError> {
    same_size(img, reference)?;
    let mut errs: Vec<f64> = img
        .data
        .iter()
        .zip(&reference.data)
        .filter(|(a, r)| finite(a) && finite(r))
        .map(|(a, r)| {
            (0..3)
                .map(|c| (f64::from(a[c]) - f64::from(r[c])).abs())
                .fold(0.0, f64::max)
        })
        .collect();
    let max = reference
        .data
        .iter()
        .filter(|r| finite(r))
        .flat_map(|r| r.iter().map(|&x| f64::from(x)))
        .fold(0.0, f64::max);
    if errs.is_empty() {
        return Ok(0.0);
    }
    // Nearest rank: the smallest value with at least 99 % of the errors at or below it.
    let rank = ((0.99 * errs.len() as f64).ceil() as usize).clamp(1, errs.len()) - 1;
    let (_, p, _) = errs.select_nth_unstable_by(rank, f64::total_cmp);
    Ok(ratio(*p, max))
}

/// All per-image metrics.
pub fn compare(img: &Image, reference: &Image) -> Result<ErrorReport, MetricError> {
    Ok(ErrorReport {
        rel_l1: rel_l1(img, reference)?,
        rel_rmse: rel_rmse(img, reference)?,
        p99_over_max: p99_over_max(img, reference)?,
        non_finite: non_finite_count(img),
    })
}

/// Flicker of a sequence against its reference sequence (see the module docs).
pub fn flicker(frames: &[Image], references: &[Image]) -> Result<f64, MetricError> {
    if frames.len() != references.len() || frames.len() < 2 {
        return Err(MetricError::Sequence(frames.len(), references.len()));
    }
    for (f, r) in frames.iter().zip(references) {
        same_size(f, r)?;
        same_size(f, &frames[0])?;
    }
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for t in 1..frames.len() {
        let pix = frames[t]
            .data
            .iter()
            .zip(&references[t].data)
            .zip(frames[t - 1].data.iter().zip(&references[t - 1].data));
        for ((a, r), (pa, pr)) in pix {
            if !(finite(a) && finite(r) && finite(pa) && finite(pr)) {
                continue;
            }
            for c in 0..3 {
                let e1 = f64::from(a[c]) - f64::from(r[c]);
                let e0 = f64::from(pa[c]) - f64::from(pr[c]);
                num += (e1 - e0).abs();
                den += f64::from(r[c]).abs();
            }
        }
    }
    Ok(ratio(num, den))
}
