//! A spot light's cookie: an RGB texture projected along the cone that multiplies the
//! light's intensity (convention: [`scatter_frame::cookie`]). In a scene file it is the
//! spot's `cookie` field, a PNG file or a built-in pattern:
//!
//! ```json
//! "cookie": { "file": "rose.png" }
//! "cookie": { "pattern": "stained_glass", "size": 64 }
//! ```
//!
//! A PNG's 8-bit sRGB values are decoded to linear RGB (alpha ignored; 16-bit files are
//! reduced to 8 bits); relative paths are relative to the scene file's directory.

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use scatter_shaderlib::cookie::{bilinear_axis, cookie_uv};

/// Where a cookie's texels come from, as written in a scene file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CookieSource {
    /// A PNG file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// A built-in pattern: `stained_glass`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pattern: Option<String>,
    /// A pattern's side in texels (4..=4096).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<u32>,
}

/// Built-in patterns.
pub const PATTERNS: &[&str] = &["stained_glass"];

/// Default side of a built-in pattern.
pub const DEFAULT_PATTERN_SIZE: u32 = 64;

/// A cookie's texels: linear RGB, row 0 at the top.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CookieSource", into = "CookieSource")]
pub struct Cookie {
    source: CookieSource,
    width: u32,
    height: u32,
    texels: Arc<[[f32; 3]]>,
}

impl From<Cookie> for CookieSource {
    fn from(c: Cookie) -> CookieSource {
        c.source
    }
}

impl TryFrom<CookieSource> for Cookie {
    type Error = String;

    /// Loads the file (relative to the working directory; scene files resolve theirs first)
    /// or draws the pattern.
    fn try_from(source: CookieSource) -> Result<Cookie, String> {
        match (&source.file, &source.pattern) {
            (Some(file), None) => {
                if source.size.is_some() {
                    return Err("size applies to a pattern, not to a file".into());
                }
                let (width, height, texels) = read_png(Path::new(file))?;
                Ok(Cookie {
                    source,
                    width,
                    height,
                    texels: texels.into(),
                })
            }
            (None, Some(pattern)) => {
                let size = source.size.unwrap_or(DEFAULT_PATTERN_SIZE);
                if !(4..=4096).contains(&size) {
                    return Err(format!("size must be in 4..=4096 texels, got {size}"));
                }
                let texels = match pattern.as_str() {
                    "stained_glass" => stained_glass(size),
                    other => {
                        return Err(format!(
                            "unknown pattern {other:?} (known: {})",
                            PATTERNS.join(", ")
                        ));
                    }
                };
                Ok(Cookie {
                    source,
                    width: size,
                    height: size,
                    texels: texels.into(),
                })
            }
            _ => Err("give exactly one of file (a PNG) or pattern (stained_glass)".into()),
        }
    }
}

fn srgb_to_linear(c: u8) -> f32 {
    let x = f32::from(c) / 255.0;
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads an 8- or 16-bit PNG (gray, gray-alpha, RGB, RGBA, palette) as linear RGB.
fn read_png(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>), String> {
    let what = || path.display().to_string();
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read {}: {e}", what()))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("{} is not a readable PNG: {e}", what()))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| format!("{}: image too large", what()))?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("{} is not a readable PNG: {e}", what()))?;
    let (w, h) = (info.width, info.height);
    if w == 0 || h == 0 || w > 4096 || h > 4096 {
        return Err(format!("{}: {w}x{h}, sides must be in 1..=4096", what()));
    }
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => {
            return Err(format!("{}: palette not expanded", what()));
        }
    };
    let texels = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .map(|p| {
            if channels < 3 {
                [srgb_to_linear(p[0]); 3]
            } else {
                [
                    srgb_to_linear(p[0]),
                    srgb_to_linear(p[1]),
                    srgb_to_linear(p[2]),
                ]
            }
        })
        .collect();
    Ok((w, h, texels))
}

/// A rose window: a 4 x 4 grid of coloured panes and a ring, leaded (black lines 1/32 of the
/// side wide), clear glass in the centre. Sharp colour edges on purpose: they are what the
/// methods must carry through.
pub fn stained_glass(size: u32) -> Vec<[f32; 3]> {
    const GLASS: [[f32; 3]; 6] = [
        [0.85, 0.12, 0.08],
        [0.10, 0.30, 0.90],
        [0.95, 0.75, 0.10],
        [0.12, 0.65, 0.20],
        [0.55, 0.12, 0.75],
        [0.90, 0.45, 0.10],
    ];
    let n = size as f64;
    let lead = 1.0 / 32.0;
    let mut out = Vec::with_capacity((size * size) as usize);
    for y in 0..size {
        for x in 0..size {
            // Texel centre in [-1, 1]^2, y up.
            let a = 2.0 * (f64::from(x) + 0.5) / n - 1.0;
            let b = 1.0 - 2.0 * (f64::from(y) + 0.5) / n;
            let r = (a * a + b * b).sqrt();
            let cell = |c: f64| ((c + 1.0) * 2.0).floor().clamp(0.0, 3.0) as usize;
            let line = |c: f64| {
                let f = (c + 1.0) * 2.0;
                (f - f.round()).abs() < lead * 2.0
            };
            let texel = if (r - 0.42).abs() < lead || (r > 0.42 && (line(a) || line(b))) {
                [0.0; 3]
            } else if r < 0.42 {
                if r < 0.16 {
                    [0.95, 0.95, 0.9]
                } else {
                    GLASS[(cell(a) + 2 * cell(b)) % GLASS.len()]
                }
            } else {
                GLASS[(cell(a) * 5 + cell(b) * 3) % GLASS.len()]
            };
            out.push(texel);
        }
    }
    out
}

impl Cookie {
    /// A cookie from texels (linear RGB, row-major from the top-left), e.g. for tests.
    ///
    /// # Errors
    ///
    /// When the sides are 0 or over 4096 or `texels` does not hold `width * height` values.
    pub fn from_texels(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Result<Cookie, String> {
        if width == 0 || height == 0 || width > 4096 || height > 4096 {
            return Err(format!("{width}x{height}: sides must be in 1..=4096"));
        }
        if texels.len() != (width * height) as usize {
            return Err(format!("{} texels for {width}x{height}", texels.len()));
        }
        Ok(Cookie {
            source: CookieSource {
                file: None,
                pattern: Some("texels".into()),
                size: None,
            },
            width,
            height,
            texels: texels.into(),
        })
    }

    /// The built-in pattern `name` at `size` texels a side.
    ///
    /// # Errors
    ///
    /// An unknown name or a size outside 4..=4096.
    pub fn pattern(name: &str, size: u32) -> Result<Cookie, String> {
        Cookie::try_from(CookieSource {
            file: None,
            pattern: Some(name.into()),
            size: Some(size),
        })
    }

    /// Where the texels came from.
    pub fn source(&self) -> &CookieSource {
        &self.source
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texels, linear RGB, row-major from the top-left.
    pub fn texels(&self) -> &[[f32; 3]] {
        &self.texels
    }

    /// The texels as RGBA (alpha 1), as the GPU texture holds them.
    pub fn rgba(&self) -> Vec<[f32; 4]> {
        self.texels
            .iter()
            .map(|t| [t[0], t[1], t[2], 1.0])
            .collect()
    }

    /// Bilinear sample at texture coordinates `(u, v)` (clamped to the edge).
    pub fn sample_uv(&self, u: f64, v: f64) -> [f64; 3] {
        let (x0, x1, fx) = bilinear_axis(u, self.width);
        let (y0, y1, fy) = bilinear_axis(v, self.height);
        let t = |x: u32, y: u32| self.texels[(y * self.width + x) as usize];
        let mut out = [0.0; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let top = f64::from(t(x0, y0)[c]) * (1.0 - fx) + f64::from(t(x1, y0)[c]) * fx;
            let bottom = f64::from(t(x0, y1)[c]) * (1.0 - fx) + f64::from(t(x1, y1)[c]) * fx;
            *o = top * (1.0 - fy) + bottom * fy;
        }
        out
    }

    /// The cookie's value for the light-travel direction `travel` (from the lamp) in the
    /// light frame `basis` (right, up, forward) of a cone with `tan_outer`: black behind the
    /// lamp.
    pub fn sample_dir(&self, travel: DVec3, basis: &[DVec3; 3], tan_outer: f64) -> [f64; 3] {
        match cookie_uv(
            travel.dot(basis[0]),
            travel.dot(basis[1]),
            travel.dot(basis[2]),
            tan_outer,
        ) {
            Some((u, v)) => self.sample_uv(u, v),
            None => [0.0; 3],
        }
    }
}
