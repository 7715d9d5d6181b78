//! Image I/O and composition: PFM round trips, PNG output and tone mapping, atomic writes,
//! stacking, exposure and per-pixel arithmetic.

use scatter_reference::image::{Image, ImageError, luminance, write_atomic};
use std::path::PathBuf;

/// A fresh directory under the system temp dir, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> TempDir {
        let dir =
            std::env::temp_dir().join(format!("scatter-image-io-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Names of the entries in the directory, sorted.
    fn entries(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A 7x3 test image with distinct values in every channel, negatives, signed zeros,
/// subnormals, extremes and non-finite values.
fn odd_image() -> Image {
    let (w, h) = (7u32, 3u32);
    let mut data: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            let i = i as f32;
            [i * 0.37 - 3.0, -(i * 1.5e-3), i * i * 123.456]
        })
        .collect();
    data[0] = [-0.0, 0.0, f32::MIN_POSITIVE / 8.0];
    data[1] = [f32::MAX, f32::MIN, f32::EPSILON];
    data[2] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY];
    data[20] = [1.0 / 3.0, -2.0 / 7.0, 1e-30];
    Image::from_pixels(w, h, data)
}

/// Bitwise equality of two images (NaN-safe).
#[track_caller]
fn assert_bits_eq(a: &Image, b: &Image) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    for (k, (p, q)) in a.data.iter().zip(&b.data).enumerate() {
        for c in 0..3 {
            assert_eq!(
                p[c].to_bits(),
                q[c].to_bits(),
                "pixel {k} channel {c}: {} vs {}",
                p[c],
                q[c]
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// PFM

#[test]
fn pfm_round_trip_is_bit_exact() {
    let dir = TempDir::new("pfm_round_trip_is_bit_exact");
    let img = odd_image();
    let path = dir.path("odd.pfm");
    img.write_pfm(&path).unwrap();
    let back = Image::read_pfm(&path).unwrap();
    assert_bits_eq(&img, &back);
    // And the same for a 1-pixel-wide, tall image.
    let tall = Image::from_pixels(1, 5, (0..5).map(|i| [i as f32, -(i as f32), 0.5]).collect());
    tall.write_pfm(dir.path("tall.pfm")).unwrap();
    assert_eq!(Image::read_pfm(dir.path("tall.pfm")).unwrap(), tall);
}

#[test]
fn pfm_layout_is_little_endian_bottom_to_top() {
    let dir = TempDir::new("pfm_layout_is_little_endian_bottom_to_top");
    let img = odd_image();
    let path = dir.path("odd.pfm");
    img.write_pfm(&path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let header = b"PF\n7 3\n-1.0\n";
    assert!(bytes.starts_with(header));
    assert_eq!(bytes.len(), header.len() + 7 * 3 * 12);
    // The first stored pixel is the bottom-left one, (0, 2).
    let body = &bytes[header.len()..];
    let first = f32::from_le_bytes(body[0..4].try_into().unwrap());
    assert_eq!(first.to_bits(), img.get(0, 2)[0].to_bits());
    // The last stored pixel is the top-right one, (6, 0).
    let n = body.len();
    let last = f32::from_le_bytes(body[n - 4..].try_into().unwrap());
    assert_eq!(last.to_bits(), img.get(6, 0)[2].to_bits());
}

#[test]
fn pfm_reads_big_endian() {
    let dir = TempDir::new("pfm_reads_big_endian");
    // 2x1, positive scale: big-endian.
    let mut bytes = b"PF\n2 1\n1.0\n".to_vec();
    for v in [1.0f32, -2.5, 3.25, 0.0, 1e-3, -7.0] {
        bytes.extend_from_slice(&v.to_be_bytes());
    }
    let path = dir.path("be.pfm");
    std::fs::write(&path, bytes).unwrap();
    let img = Image::read_pfm(&path).unwrap();
    assert_eq!(
        img,
        Image::from_pixels(2, 1, vec![[1.0, -2.5, 3.25], [0.0, 1e-3, -7.0]])
    );
}

#[test]
fn pfm_rejects_malformed_files() {
    let dir = TempDir::new("pfm_rejects_malformed_files");
    let cases: [(&str, &[u8]); 5] = [
        ("gray.pfm", b"Pf\n1 1\n-1.0\n\0\0\0\0"),
        ("truncated_header.pfm", b"PF\n1 1\n"),
        ("bad_size.pfm", b"PF\nx 1\n-1.0\n"),
        ("short_data.pfm", b"PF\n2 1\n-1.0\n\0\0\0\0\0\0\0\0\0\0\0\0"),
        ("bad_scale.pfm", b"PF\n1 1\nscale\n\0\0\0\0\0\0\0\0\0\0\0\0"),
    ];
    for (name, bytes) in cases {
        let path = dir.path(name);
        std::fs::write(&path, bytes).unwrap();
        match Image::read_pfm(&path) {
            Err(ImageError::Format { path: p, reason }) => {
                assert_eq!(p, path.display().to_string(), "{name}");
                assert!(!reason.is_empty(), "{name}");
            }
            other => panic!("{name}: expected a format error, got {other:?}"),
        }
    }
    // A missing file is an I/O error naming the path.
    let missing = dir.path("missing.pfm");
    let err = Image::read_pfm(&missing).unwrap_err();
    assert!(matches!(err, ImageError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("missing.pfm"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// PNG and tone mapping

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

#[test]
fn png_has_signature_and_decodes_to_the_tonemap() {
    let dir = TempDir::new("png_has_signature_and_decodes_to_the_tonemap");
    let img = odd_image();
    let path = dir.path("odd.png");
    let e = img.write_png(&path, Some(0.5)).unwrap();
    assert_eq!(e, 0.5);
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.starts_with(&PNG_SIGNATURE));

    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (7, 3));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    assert_eq!(&buf[..info.buffer_size()], img.tonemap(0.5).as_slice());
    assert_eq!(dir.entries(), vec!["odd.png".to_string()]);
}

#[test]
fn png_default_exposure_is_auto() {
    let dir = TempDir::new("png_default_exposure_is_auto");
    let img = Image::from_pixels(4, 1, vec![[0.5; 3], [1.0; 3], [2.0; 3], [4.0; 3]]);
    let e = img.write_png(dir.path("auto.png"), None).unwrap();
    assert_eq!(e, img.auto_exposure());
}

#[test]
fn tonemap_values() {
    let img = Image::from_pixels(
        3,
        2,
        vec![
            [f32::NAN, 0.0, 0.0],
            [0.0, f32::INFINITY, 1.0],
            [0.0, 0.0, 0.0],
            [-5.0, 1e9, std::f32::consts::LN_2],
            [f32::NEG_INFINITY, 0.0, 0.0],
            [0.0, 0.0, 1e-3],
        ],
    );
    let t = img.tonemap(1.0);
    assert_eq!(t.len(), 6 * 3);
    // Non-finite pixels are magenta, whichever channel is bad.
    assert_eq!(&t[0..3], &[255, 0, 255]);
    assert_eq!(&t[3..6], &[255, 0, 255]);
    assert_eq!(&t[12..15], &[255, 0, 255]);
    // Black stays black; negatives clamp to black; huge values saturate.
    assert_eq!(&t[6..9], &[0, 0, 0]);
    assert_eq!(t[9], 0);
    assert_eq!(t[10], 255);
    // ln 2 -> 1 - exp(-ln 2) = 0.5 -> sRGB 0.7354 -> 188.
    assert_eq!(t[11], 188);
    // 1e-3 -> ~0.0009995, in the linear segment: 12.92 * 0.0009995 * 255 + 0.5 -> 3.
    assert_eq!(t[17], 3);
    // Exposure scales before the curve: 0.5 * ln 4 = ln 2.
    let x = Image::from_pixels(1, 1, vec![[std::f32::consts::LN_2 * 2.0; 3]]);
    assert_eq!(x.tonemap(0.5), vec![188; 3]);
}

// ---------------------------------------------------------------------------------------------
// write_atomic

#[test]
fn write_atomic_writes_and_leaves_no_temp_file() {
    let dir = TempDir::new("write_atomic_writes_and_leaves_no_temp_file");
    let path = dir.path("data.bin");
    write_atomic(&path, b"first").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"first");
    // Overwriting replaces the contents.
    write_atomic(&path, b"second, longer").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"second, longer");
    write_atomic(&path, b"").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"");
    assert_eq!(dir.entries(), vec!["data.bin".to_string()]);
    // Image writers go through it too.
    odd_image().write_pfm(dir.path("x.pfm")).unwrap();
    assert_eq!(
        dir.entries(),
        vec!["data.bin".to_string(), "x.pfm".to_string()]
    );
}

#[test]
fn write_atomic_fails_cleanly_in_missing_directory() {
    let dir = TempDir::new("write_atomic_fails_cleanly_in_missing_directory");
    let missing = dir.path("no/such/dir");
    let path = missing.join("data.bin");
    let err = write_atomic(&path, b"x").unwrap_err();
    assert_eq!(err.kind(), std::io::ErrorKind::NotFound);
    assert!(!missing.exists());
    assert!(dir.entries().is_empty());

    // The image writers report an I/O error naming the path.
    let img = odd_image();
    for (res, name) in [
        (img.write_pfm(missing.join("a.pfm")), "a.pfm"),
        (
            img.write_png(missing.join("a.png"), Some(1.0)).map(|_| ()),
            "a.png",
        ),
    ] {
        match res {
            Err(ImageError::Io { path, source }) => {
                assert!(path.ends_with(name), "{path}");
                assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
            }
            other => panic!("{name}: expected an I/O error, got {other:?}"),
        }
    }
    assert!(dir.entries().is_empty());
}

#[test]
fn write_atomic_fails_cleanly_when_target_is_a_directory() {
    let dir = TempDir::new("write_atomic_fails_cleanly_when_target_is_a_directory");
    let target = dir.path("occupied");
    std::fs::create_dir(&target).unwrap();
    assert!(write_atomic(&target, b"x").is_err());
    // The temporary file was removed again; only the directory remains.
    assert_eq!(dir.entries(), vec!["occupied".to_string()]);
    assert!(target.is_dir());
}

// ---------------------------------------------------------------------------------------------
// composition

fn filled(w: u32, h: u32, tag: f32) -> Image {
    // Pixel (x, y) = [tag, x, y], so placement can be checked.
    let mut img = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            img.data[(y * w + x) as usize] = [tag, x as f32, y as f32];
        }
    }
    img
}

#[test]
fn hstack_places_left_to_right() {
    let (a, b, c) = (filled(2, 3, 1.0), filled(3, 3, 2.0), filled(1, 3, 3.0));
    let s = Image::hstack(&[&a, &b, &c]).unwrap();
    assert_eq!((s.width, s.height), (6, 3));
    for y in 0..3 {
        assert_eq!(s.get(0, y), [1.0, 0.0, y as f32]);
        assert_eq!(s.get(1, y), [1.0, 1.0, y as f32]);
        assert_eq!(s.get(2, y), [2.0, 0.0, y as f32]);
        assert_eq!(s.get(4, y), [2.0, 2.0, y as f32]);
        assert_eq!(s.get(5, y), [3.0, 0.0, y as f32]);
    }
    // A single image is itself; no images is an empty image.
    assert_eq!(Image::hstack(&[&a]).unwrap(), a);
    let empty = Image::hstack(&[]).unwrap();
    assert_eq!((empty.width, empty.height), (0, 0));
}

#[test]
fn hstack_rejects_height_mismatch() {
    let (a, b) = (filled(2, 3, 1.0), filled(2, 4, 2.0));
    match Image::hstack(&[&a, &b]) {
        Err(ImageError::SizeMismatch(2, 4, 2, 3)) => {}
        other => panic!("expected SizeMismatch(2, 4, 2, 3), got {other:?}"),
    }
}

#[test]
fn vstack_places_top_to_bottom_left_aligned() {
    let (a, b) = (filled(2, 1, 1.0), filled(3, 2, 2.0));
    let s = Image::vstack(&[&a, &b]);
    assert_eq!((s.width, s.height), (3, 3));
    assert_eq!(s.get(0, 0), [1.0, 0.0, 0.0]);
    assert_eq!(s.get(1, 0), [1.0, 1.0, 0.0]);
    // The narrower image is padded with black on the right.
    assert_eq!(s.get(2, 0), [0.0, 0.0, 0.0]);
    for x in 0..3 {
        assert_eq!(s.get(x, 1), [2.0, x as f32, 0.0]);
        assert_eq!(s.get(x, 2), [2.0, x as f32, 1.0]);
    }
    let empty = Image::vstack(&[]);
    assert_eq!((empty.width, empty.height), (0, 0));
}

#[test]
fn add_and_abs_diff() {
    let a = Image::from_pixels(2, 1, vec![[1.0, 2.0, 3.0], [-1.0, 0.5, 0.0]]);
    let b = Image::from_pixels(2, 1, vec![[0.5, 4.0, 3.0], [1.0, 0.25, -2.0]]);
    assert_eq!(
        a.add(&b).unwrap(),
        Image::from_pixels(2, 1, vec![[1.5, 6.0, 6.0], [0.0, 0.75, -2.0]])
    );
    assert_eq!(
        a.abs_diff(&b, 4.0).unwrap(),
        Image::from_pixels(2, 1, vec![[2.0, 8.0, 0.0], [8.0, 1.0, 8.0]])
    );
    // Symmetric.
    assert_eq!(a.abs_diff(&b, 1.0).unwrap(), b.abs_diff(&a, 1.0).unwrap());
}

#[test]
fn add_and_abs_diff_reject_size_mismatch() {
    let a = Image::new(4, 3);
    let b = Image::new(3, 4);
    match a.add(&b) {
        Err(ImageError::SizeMismatch(4, 3, 3, 4)) => {}
        other => panic!("add: expected SizeMismatch(4, 3, 3, 4), got {other:?}"),
    }
    match b.abs_diff(&a, 1.0) {
        Err(e @ ImageError::SizeMismatch(3, 4, 4, 3)) => {
            assert!(e.to_string().contains("3x4 vs 4x3"), "{e}");
        }
        other => panic!("abs_diff: expected SizeMismatch(3, 4, 4, 3), got {other:?}"),
    }
}

#[test]
#[should_panic(expected = "pixel count")]
fn from_pixels_checks_the_pixel_count() {
    let _ = Image::from_pixels(2, 2, vec![[0.0; 3]; 3]);
}

// ---------------------------------------------------------------------------------------------
// exposure

#[test]
fn auto_exposure_maps_the_995th_percentile_to_one() {
    // Gray pixels 1..=200 (scrambled): index floor(199 * 0.995) = 198 of the sorted
    // luminances, i.e. the pixel of value 199.
    let data: Vec<[f32; 3]> = (0..200).map(|k| [((k * 7) % 200 + 1) as f32; 3]).collect();
    let img = Image::from_pixels(20, 10, data);
    let e = img.auto_exposure();
    assert_eq!(e, 1.0 / luminance([199.0; 3]));
    assert!((e - 1.0 / 199.0).abs() < 1e-6 / 199.0, "{e}");
}

#[test]
fn auto_exposure_ignores_non_finite_and_handles_black() {
    assert_eq!(Image::new(5, 5).auto_exposure(), 1.0);
    assert_eq!(Image::new(0, 0).auto_exposure(), 1.0);
    let nan = Image::from_pixels(2, 1, vec![[f32::NAN; 3], [f32::INFINITY; 3]]);
    assert_eq!(nan.auto_exposure(), 1.0);
    // A single finite pixel among non-finite ones sets the exposure.
    let mixed = Image::from_pixels(
        3,
        1,
        vec![[f32::NAN; 3], [4.0; 3], [f32::INFINITY, 0.0, 0.0]],
    );
    assert_eq!(mixed.auto_exposure(), 1.0 / luminance([4.0; 3]));
    // A few bright pixels (under 0.5 %) in a black image: the percentile is black, exposure 1.
    let mut sparse = Image::new(100, 10);
    sparse.data[17] = [50.0; 3];
    assert_eq!(sparse.auto_exposure(), 1.0);
}

#[test]
fn luminance_weights() {
    assert_eq!(luminance([1.0, 0.0, 0.0]), 0.2126);
    assert_eq!(luminance([0.0, 1.0, 0.0]), 0.7152);
    assert_eq!(luminance([0.0, 0.0, 1.0]), 0.0722);
    assert!((luminance([1.0; 3]) - 1.0).abs() < 1e-6);
}

#[test]
fn temp_dir_is_cleaned_up() {
    let p: PathBuf;
    {
        let dir = TempDir::new("temp_dir_is_cleaned_up");
        p = dir.0.clone();
        write_atomic(&dir.path("f"), b"1").unwrap();
        assert!(p.is_dir());
    }
    assert!(!p.exists());
}
