//! Hand-checked unit tests of every metric in `scatter_reference::metrics`.
//!
//! Pixel values are chosen to be exactly representable (mostly dyadic fractions) so that the
//! expected answers can be computed by hand and compared with tight tolerances.

use scatter_reference::image::Image;
use scatter_reference::metrics::{
    ErrorReport, MetricError, compare, flicker, non_finite_count, p99_over_max, rel_l1, rel_rmse,
};

/// `a` equals `b` to within `rel` relative error (exact when `b` is 0).
fn close(a: f64, b: f64, rel: f64) -> bool {
    if b == 0.0 {
        a == 0.0
    } else {
        ((a - b) / b).abs() <= rel
    }
}

#[track_caller]
fn assert_close(a: f64, b: f64) {
    assert!(close(a, b, 1e-12), "got {a:e}, expected {b:e}");
}

fn uniform(w: u32, h: u32, v: f32) -> Image {
    Image::from_pixels(w, h, vec![[v; 3]; (w * h) as usize])
}

// ---------------------------------------------------------------------------------------------
// rel_l1

#[test]
fn rel_l1_uniform_ten_percent() {
    // Exactly representable: 2.0 vs 2.5 is 25 %.
    let r = uniform(4, 3, 2.0);
    assert_eq!(rel_l1(&uniform(4, 3, 2.5), &r).unwrap(), 0.25);
    // 2.2 is not representable in f32, so the answer is 0.1 up to f32 rounding of 2.2 and
    // exactly (f64(2.2f32) - 2) / 2 when computed from the stored value.
    let got = rel_l1(&uniform(4, 3, 2.2), &r).unwrap();
    assert!(close(got, 0.1, 1e-6), "{got}");
    assert_close(got, (f64::from(2.2f32) - 2.0) / 2.0);
    // An image below the reference counts the same as one above it.
    assert_eq!(rel_l1(&uniform(4, 3, 1.5), &r).unwrap(), 0.25);
}

#[test]
fn rel_l1_mixed_pixels() {
    let r = Image::from_pixels(2, 1, vec![[1.0, 2.0, 3.0], [4.0, 0.0, 0.0]]);
    let l = Image::from_pixels(2, 1, vec![[1.5, 2.0, 2.0], [4.0, 1.0, 0.0]]);
    // |diff| = 0.5 + 0 + 1 + 0 + 1 + 0 = 2.5; sum |R| = 10.
    assert_close(rel_l1(&l, &r).unwrap(), 0.25);
}

#[test]
fn rel_l1_uses_absolute_reference_values() {
    // A negative reference channel contributes |R| to the denominator.
    let r = Image::from_pixels(1, 1, vec![[-2.0, 2.0, 0.0]]);
    let l = Image::from_pixels(1, 1, vec![[-1.0, 2.0, 0.0]]);
    assert_close(rel_l1(&l, &r).unwrap(), 0.25);
}

#[test]
fn identical_images_score_zero() {
    let r = Image::from_pixels(
        3,
        1,
        vec![[0.1, 0.2, 0.3], [1.0, 5.0, 0.0], [7.0, 0.0, 0.25]],
    );
    assert_eq!(rel_l1(&r, &r).unwrap(), 0.0);
    assert_eq!(rel_rmse(&r, &r).unwrap(), 0.0);
    assert_eq!(p99_over_max(&r, &r).unwrap(), 0.0);
    assert_eq!(non_finite_count(&r), 0);
}

// ---------------------------------------------------------------------------------------------
// rel_rmse

#[test]
fn rel_rmse_hand_computed() {
    let r = Image::from_pixels(2, 1, vec![[1.0, 2.0, 3.0], [4.0, 0.0, 0.0]]);
    let l = Image::from_pixels(2, 1, vec![[1.5, 2.0, 2.0], [4.0, 1.0, 0.0]]);
    // sqrt(0.25 + 1 + 1) / sqrt(1 + 4 + 9 + 16) = 1.5 / sqrt(30).
    assert_close(rel_rmse(&l, &r).unwrap(), 1.5 / 30f64.sqrt());
}

#[test]
fn rel_rmse_uniform_offset() {
    // Every channel off by 25 %: RMSE relative is 25 % too.
    let r = uniform(5, 2, 4.0);
    assert_close(rel_rmse(&uniform(5, 2, 5.0), &r).unwrap(), 0.25);
}

#[test]
fn rel_rmse_weights_large_errors_more_than_rel_l1() {
    // One big error among many exact pixels: same L1 budget spent in one place.
    let r = uniform(4, 1, 1.0);
    let mut l = r.clone();
    l.data[0] = [3.0, 1.0, 1.0];
    // L1: 2 / 12; RMSE: sqrt(4) / sqrt(12).
    assert_close(rel_l1(&l, &r).unwrap(), 2.0 / 12.0);
    assert_close(rel_rmse(&l, &r).unwrap(), 2.0 / 12f64.sqrt());
}

// ---------------------------------------------------------------------------------------------
// p99_over_max

/// An image of `n` pixels whose per-pixel errors against `reference` are `errs[k]`, each put in
/// a different channel (the max over channels is what counts), with smaller errors elsewhere.
fn with_errors(reference: &Image, errs: &[f32]) -> Image {
    assert_eq!(reference.data.len(), errs.len());
    let mut l = reference.clone();
    for (k, (p, &e)) in l.data.iter_mut().zip(errs).enumerate() {
        let c = k % 3;
        p[c] += e;
        // A smaller error of the opposite sign in another channel must not matter.
        p[(c + 1) % 3] -= e * 0.5;
    }
    l
}

/// `0..n` in a scrambled order (a permutation since `step` is coprime with `n`).
fn scrambled(n: usize, step: usize) -> Vec<usize> {
    (0..n).map(|k| (k * step + 3) % n).collect()
}

#[test]
fn p99_over_max_hundred_pixels() {
    // Errors 0.25 * {1..=100}, scrambled; nearest rank: ceil(0.99 * 100) = 99th smallest,
    // 24.75. The reference's largest channel is 16 (one pixel), the rest are 1.
    let n = 100;
    let mut r = Image::from_pixels(10, 10, vec![[1.0; 3]; n]);
    r.data[37][1] = 16.0;
    let errs: Vec<f32> = scrambled(n, 37)
        .into_iter()
        .map(|k| 0.25 * (k + 1) as f32)
        .collect();
    let l = with_errors(&r, &errs);
    assert_close(p99_over_max(&l, &r).unwrap(), 24.75 / 16.0);
}

#[test]
fn p99_over_max_thousand_pixels() {
    // Errors 1/8 * {1..=1000}; nearest rank: the 990th smallest, 123.75; max channel 64.
    let n = 1000;
    let mut r = Image::from_pixels(40, 25, vec![[2.0, 1.0, 0.5]; n]);
    r.data[999][2] = 64.0;
    let errs: Vec<f32> = scrambled(n, 333)
        .into_iter()
        .map(|k| 0.125 * (k + 1) as f32)
        .collect();
    let l = with_errors(&r, &errs);
    assert_close(p99_over_max(&l, &r).unwrap(), 123.75 / 64.0);
}

#[test]
fn p99_over_max_nearest_rank_edges() {
    // n = 101: ceil(99.99) = 100, so the 100th smallest (not the largest) is reported.
    let n = 101;
    let r = Image::from_pixels(101, 1, vec![[1.0; 3]; n]);
    let errs: Vec<f32> = scrambled(n, 10)
        .into_iter()
        .map(|k| (k + 1) as f32)
        .collect();
    assert_close(p99_over_max(&with_errors(&r, &errs), &r).unwrap(), 100.0);

    // n = 10: ceil(9.9) = 10, the largest error.
    let r = Image::from_pixels(5, 2, vec![[1.0; 3]; 10]);
    let errs: Vec<f32> = scrambled(10, 3).into_iter().map(|k| k as f32).collect();
    assert_close(p99_over_max(&with_errors(&r, &errs), &r).unwrap(), 9.0);

    // n = 1: the only error.
    let r = Image::from_pixels(1, 1, vec![[4.0, 2.0, 1.0]]);
    let l = Image::from_pixels(1, 1, vec![[4.0, 3.0, 1.0]]);
    assert_close(p99_over_max(&l, &r).unwrap(), 0.25);
}

#[test]
fn p99_over_max_divides_by_largest_reference_channel() {
    // Same errors, reference max doubled: the metric halves.
    let n = 100;
    let errs: Vec<f32> = (0..n).map(|k| k as f32 * 0.5).collect();
    let mut r1 = Image::from_pixels(100, 1, vec![[1.0; 3]; n]);
    r1.data[5][0] = 10.0;
    let mut r2 = r1.clone();
    r2.data[77][2] = 20.0;
    let a = p99_over_max(&with_errors(&r1, &errs), &r1).unwrap();
    let b = p99_over_max(&with_errors(&r2, &errs), &r2).unwrap();
    // 99th smallest of 0, 0.5, ..., 49.5 is 49.0.
    assert_close(a, 49.0 / 10.0);
    assert_close(b, 49.0 / 20.0);
}

#[test]
fn p99_over_max_ignores_non_finite_pixels() {
    // A NaN pixel in the image is skipped (and does not count towards the rank), and an
    // infinite reference pixel neither contributes an error nor the max.
    let mut r = Image::from_pixels(4, 1, vec![[1.0; 3]; 4]);
    let mut l = Image::from_pixels(4, 1, vec![[1.5, 1.0, 1.0]; 4]);
    l.data[0] = [f32::NAN, 1.0, 1.0];
    r.data[3] = [f32::INFINITY, 1.0, 1.0];
    l.data[3] = [1.0, 1.0, 1.0];
    assert_close(p99_over_max(&l, &r).unwrap(), 0.5);
}

// ---------------------------------------------------------------------------------------------
// non_finite_count and exclusion from the sums

#[test]
fn non_finite_count_counts_pixels_not_channels() {
    let img = Image::from_pixels(
        3,
        2,
        vec![
            [f32::NAN, 0.0, 0.0],
            [0.0, f32::INFINITY, 0.0],
            [0.0, 0.0, f32::NEG_INFINITY],
            [f32::NAN, f32::NAN, f32::INFINITY], // one pixel, however many bad channels
            [f32::MAX, -f32::MAX, f32::MIN_POSITIVE], // extreme but finite
            [1.0, 2.0, 3.0],
        ],
    );
    assert_eq!(non_finite_count(&img), 4);
    assert_eq!(non_finite_count(&uniform(3, 3, 1.0)), 0);
    assert_eq!(non_finite_count(&Image::new(0, 0)), 0);
}

#[test]
fn non_finite_pixels_are_excluded_from_sums() {
    let r = uniform(2, 1, 2.0);
    let l = Image::from_pixels(2, 1, vec![[2.5, 2.0, 2.0], [f32::NAN, 0.0, 0.0]]);
    // Only the first pixel counts, numerator and denominator alike: 0.5 / 6.
    assert_close(rel_l1(&l, &r).unwrap(), 0.5 / 6.0);
    assert_close(rel_rmse(&l, &r).unwrap(), 0.5 / 12f64.sqrt());
    assert!(rel_l1(&l, &r).unwrap().is_finite());

    // Same with infinities of both signs in the image.
    let l = Image::from_pixels(
        3,
        1,
        vec![
            [2.5, 2.0, 2.0],
            [f32::INFINITY, 2.0, 2.0],
            [2.0, f32::NEG_INFINITY, 2.0],
        ],
    );
    let r = uniform(3, 1, 2.0);
    assert_close(rel_l1(&l, &r).unwrap(), 0.5 / 6.0);

    // And a non-finite reference pixel excludes that pixel too.
    let r = Image::from_pixels(2, 1, vec![[2.0; 3], [f32::NAN, 2.0, 2.0]]);
    let l = Image::from_pixels(2, 1, vec![[2.5, 2.0, 2.0], [1.0, 100.0, 1.0]]);
    assert_close(rel_l1(&l, &r).unwrap(), 0.5 / 6.0);
}

#[test]
fn compare_reports_every_metric() {
    let r = Image::from_pixels(2, 1, vec![[1.0, 2.0, 3.0], [4.0, 0.0, 0.0]]);
    let mut l = Image::from_pixels(
        3,
        1,
        vec![[1.5, 2.0, 2.0], [4.0, 1.0, 0.0], [0.0, 0.0, 0.0]],
    );
    assert_eq!(compare(&l, &r), Err(MetricError::SizeMismatch(3, 1, 2, 1)));
    l = Image::from_pixels(2, 1, vec![[1.5, 2.0, 2.0], [4.0, 1.0, 0.0]]);
    let rep = compare(&l, &r).unwrap();
    assert_eq!(
        rep,
        ErrorReport {
            rel_l1: rel_l1(&l, &r).unwrap(),
            rel_rmse: rel_rmse(&l, &r).unwrap(),
            p99_over_max: p99_over_max(&l, &r).unwrap(),
            non_finite: 0,
        }
    );
    assert_close(rep.rel_l1, 0.25);
    // Errors per pixel: 1, 1; p99 of two = the larger; over max 4.
    assert_close(rep.p99_over_max, 0.25);
    let text = rep.to_string();
    assert!(text.contains("rel L1 25.0000 %"), "{text}");
    assert!(text.contains("p99/max 25.0000 %"), "{text}");
    assert!(text.contains("NaN/Inf 0"), "{text}");

    l.data[1] = [f32::NAN; 3];
    let rep = compare(&l, &r).unwrap();
    assert_eq!(rep.non_finite, 1);
    // Pixel 1 excluded: |diff| 1.5 over 6.
    assert_close(rep.rel_l1, 0.25);
}

// ---------------------------------------------------------------------------------------------
// black images

#[test]
fn both_black_scores_zero() {
    let b = Image::new(6, 4);
    assert_eq!(rel_l1(&b, &b).unwrap(), 0.0);
    assert_eq!(rel_rmse(&b, &b).unwrap(), 0.0);
    assert_eq!(p99_over_max(&b, &b).unwrap(), 0.0);
    assert_eq!(
        flicker(&[b.clone(), b.clone()], &[b.clone(), b]).unwrap(),
        0.0
    );
}

#[test]
fn black_reference_nonzero_image_is_infinite() {
    let b = Image::new(3, 2);
    let mut l = b.clone();
    l.data[4] = [0.0, 0.5, 0.0];
    assert_eq!(rel_l1(&l, &b).unwrap(), f64::INFINITY);
    assert_eq!(rel_rmse(&l, &b).unwrap(), f64::INFINITY);
    // 6 errors, nearest rank 6 (the largest, 0.5), over a max of 0.
    assert_eq!(p99_over_max(&l, &b).unwrap(), f64::INFINITY);
}

#[test]
fn empty_images_score_zero() {
    let e = Image::new(0, 0);
    assert_eq!(rel_l1(&e, &e).unwrap(), 0.0);
    assert_eq!(rel_rmse(&e, &e).unwrap(), 0.0);
    assert_eq!(p99_over_max(&e, &e).unwrap(), 0.0);
}

// ---------------------------------------------------------------------------------------------
// size mismatches

#[test]
fn size_mismatch_is_an_error() {
    let a = uniform(4, 3, 1.0);
    let b = uniform(3, 4, 1.0); // same pixel count, different shape
    let c = uniform(4, 2, 1.0);
    let e = || Err(MetricError::SizeMismatch(4, 3, 3, 4));
    assert_eq!(rel_l1(&a, &b), e());
    assert_eq!(rel_rmse(&a, &b), e());
    assert_eq!(p99_over_max(&a, &b), e());
    assert_eq!(rel_l1(&c, &a), Err(MetricError::SizeMismatch(4, 2, 4, 3)));
    let msg = rel_l1(&a, &c).unwrap_err().to_string();
    assert!(msg.contains("4x3 vs 4x2"), "{msg}");
}

// ---------------------------------------------------------------------------------------------
// flicker

/// A sequence of `t` references, frame `k` uniformly `1 + k / 2` (exact in f32).
fn ramp_refs(t: usize, w: u32, h: u32) -> Vec<Image> {
    (0..t)
        .map(|k| uniform(w, h, 1.0 + 0.5 * k as f32))
        .collect()
}

#[test]
fn flicker_steady_error_is_zero() {
    let refs = ramp_refs(5, 3, 2);
    // A large but constant error (+0.75 everywhere, -2 in one channel of one pixel).
    let frames: Vec<Image> = refs
        .iter()
        .map(|r| {
            let mut l = r.clone();
            for p in &mut l.data {
                p.iter_mut().for_each(|x| *x += 0.75);
            }
            l.data[3][1] -= 2.75;
            l
        })
        .collect();
    assert_eq!(flicker(&frames, &refs).unwrap(), 0.0);
    // The per-frame error is far from zero, though.
    assert!(rel_l1(&frames[2], &refs[2]).unwrap() > 0.2);
}

#[test]
fn flicker_alternating_error() {
    // e_t = +e, -e, +e, ...: |e_t - e_{t-1}| = 2e for every channel of every frame t >= 1.
    // References: frame 0 is 100 (excluded from the denominator), frames t >= 1 are 1.
    let (w, h, t, e) = (4u32, 3u32, 6usize, 0.25f32);
    let refs: Vec<Image> = (0..t)
        .map(|k| uniform(w, h, if k == 0 { 100.0 } else { 1.0 }))
        .collect();
    let frames: Vec<Image> = refs
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let s = if k % 2 == 0 { e } else { -e };
            let mut l = r.clone();
            for p in &mut l.data {
                p.iter_mut().for_each(|x| *x += s);
            }
            l
        })
        .collect();
    // sum_t sum |e_t - e_{t-1}| = (t-1) * n * 3 * 2e; denominator (t-1) * n * 3 * 1.
    assert_close(flicker(&frames, &refs).unwrap(), 2.0 * f64::from(e));
}

#[test]
fn flicker_single_jump_hand_computed() {
    // Three frames of a 2-pixel image against a constant reference 2; the error is 0, then
    // +1 in one channel of pixel 0, then that error stays: only one change of size 1.
    let refs = vec![uniform(2, 1, 2.0); 3];
    let mut f1 = refs[0].clone();
    f1.data[0][2] = 3.0;
    let frames = vec![refs[0].clone(), f1.clone(), f1];
    // num = 1 (t = 1) + 0 (t = 2); den = 2 frames * 6 channels * 2 = 24.
    assert_close(flicker(&frames, &refs).unwrap(), 1.0 / 24.0);
}

#[test]
fn flicker_skips_non_finite_pixels() {
    let refs = vec![uniform(2, 1, 1.0); 2];
    let mut f0 = refs[0].clone();
    f0.data[1] = [f32::NAN; 3];
    let mut f1 = refs[1].clone();
    f1.data[0][0] = 1.5;
    // Pixel 1 is excluded at t = 1 (its previous frame is NaN): num 0.5, den 3.
    assert_close(flicker(&[f0, f1], &refs).unwrap(), 0.5 / 3.0);
}

#[test]
fn flicker_sequence_errors() {
    let refs = ramp_refs(3, 2, 2);
    assert_eq!(flicker(&refs, &refs[..2]), Err(MetricError::Sequence(3, 2)));
    assert_eq!(
        flicker(&refs[..1], &refs[..1]),
        Err(MetricError::Sequence(1, 1))
    );
    assert_eq!(flicker(&[], &[]), Err(MetricError::Sequence(0, 0)));
    let msg = flicker(&refs[..1], &refs[..2]).unwrap_err().to_string();
    assert!(msg.contains(">= 2 frames"), "{msg}");
    assert!(msg.contains("got 1 and 2"), "{msg}");
}

#[test]
fn flicker_size_errors() {
    let refs = ramp_refs(3, 2, 2);
    // A frame whose size differs from its reference.
    let mut frames = refs.clone();
    frames[1] = uniform(3, 2, 1.0);
    assert_eq!(
        flicker(&frames, &refs),
        Err(MetricError::SizeMismatch(3, 2, 2, 2))
    );
    // Frames that match their references but change size over the sequence.
    let seq = vec![uniform(2, 2, 1.0), uniform(2, 3, 1.0)];
    assert!(matches!(
        flicker(&seq, &seq),
        Err(MetricError::SizeMismatch(..))
    ));
}
