//! Float RGB images: PFM input/output (lossless float), tone-mapped PNG, side-by-side strips.
//!
//! PNGs are tone-mapped with an exposure that maps the 99.5th percentile of luminance to 1,
//! the curve `1 - exp(-x)` and the sRGB transfer function, unless an exposure is given (use
//! the same exposure for images that are to be compared).

use std::io::{BufRead, Read, Write};
use std::path::Path;

/// A float RGB image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels.
    pub data: Vec<[f32; 3]>,
}

/// Why an image could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// File system error.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Malformed file.
    #[error("{path}: not a valid PFM file ({reason})")]
    Format {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// PNG encoder error.
    #[error("{path}: PNG encoding failed: {reason}")]
    Png {
        /// The file.
        path: String,
        /// Encoder message.
        reason: String,
    },
    /// Images to combine differ in size.
    #[error("image sizes differ: {0}x{1} vs {2}x{3}")]
    SizeMismatch(u32, u32, u32, u32),
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ImageError + '_ {
    move |source| ImageError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Writes `bytes` to `path` atomically (temporary file in the same directory + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
    let name = path
        .file_name()
        .map_or("out".into(), |n| n.to_string_lossy().into_owned());
    let tmp = match dir {
        Some(d) => d.join(format!(".{name}.tmp{}", std::process::id())),
        None => format!(".{name}.tmp{}", std::process::id()).into(),
    };
    let res = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if res.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    res
}

/// Writes 8-bit RGB pixels (already display-encoded, row-major) as a PNG, atomically.
pub fn write_png_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[u8],
) -> Result<(), ImageError> {
    let mut buf = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut buf, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let png_err = |e: png::EncodingError| ImageError::Png {
            path: path.display().to_string(),
            reason: e.to_string(),
        };
        let mut w = enc.write_header().map_err(png_err)?;
        w.write_image_data(pixels).map_err(png_err)?;
    }
    write_atomic(path, &buf).map_err(io_err(path))
}

/// Rec. 709 luminance.
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

fn srgb_encode(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let y = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (y * 255.0 + 0.5) as u8
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            data: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    /// Wraps pixels (`width * height` of them).
    pub fn from_pixels(width: u32, height: u32, data: Vec<[f32; 3]>) -> Image {
        assert_eq!(data.len(), width as usize * height as usize, "pixel count");
        Image {
            width,
            height,
            data,
        }
    }

    /// Pixel at (x, y).
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.data[(y * self.width + x) as usize]
    }

    /// Per-pixel sum; errors if sizes differ.
    pub fn add(&self, o: &Image) -> Result<Image, ImageError> {
        self.zip(o, |a, b| a + b)
    }

    fn zip(&self, o: &Image, f: impl Fn(f32, f32) -> f32) -> Result<Image, ImageError> {
        if (self.width, self.height) != (o.width, o.height) {
            return Err(ImageError::SizeMismatch(
                self.width,
                self.height,
                o.width,
                o.height,
            ));
        }
        Ok(Image::from_pixels(
            self.width,
            self.height,
            self.data
                .iter()
                .zip(&o.data)
                .map(|(a, b)| [f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2])])
                .collect(),
        ))
    }

    /// `scale * |self - o|` per channel (difference images).
    pub fn abs_diff(&self, o: &Image, scale: f32) -> Result<Image, ImageError> {
        self.zip(o, |a, b| scale * (a - b).abs())
    }

    /// Images placed left to right (all the same height).
    pub fn hstack(images: &[&Image]) -> Result<Image, ImageError> {
        let h = images.first().map_or(0, |i| i.height);
        if let Some(bad) = images.iter().find(|i| i.height != h) {
            return Err(ImageError::SizeMismatch(
                bad.width, bad.height, bad.width, h,
            ));
        }
        let w: u32 = images.iter().map(|i| i.width).sum();
        let mut out = Image::new(w, h);
        for y in 0..h {
            let mut x0 = 0;
            for img in images {
                for x in 0..img.width {
                    out.data[(y * w + x0 + x) as usize] = img.get(x, y);
                }
                x0 += img.width;
            }
        }
        Ok(out)
    }

    /// Images placed top to bottom, left-aligned (narrower ones padded with black).
    pub fn vstack(images: &[&Image]) -> Image {
        let w = images.iter().map(|i| i.width).max().unwrap_or(0);
        let h: u32 = images.iter().map(|i| i.height).sum();
        let mut out = Image::new(w, h);
        let mut y0 = 0;
        for img in images {
            for y in 0..img.height {
                for x in 0..img.width {
                    out.data[((y0 + y) * w + x) as usize] = img.get(x, y);
                }
            }
            y0 += img.height;
        }
        out
    }

    /// Exposure that maps the 99.5th percentile of luminance to 1 (1 for a black image).
    pub fn auto_exposure(&self) -> f32 {
        let mut l: Vec<f32> = self
            .data
            .iter()
            .map(|&c| luminance(c))
            .filter(|x| x.is_finite())
            .collect();
        if l.is_empty() {
            return 1.0;
        }
        let k = ((l.len() - 1) as f64 * 0.995) as usize;
        let (_, v, _) = l.select_nth_unstable_by(k, f32::total_cmp);
        if *v > 0.0 { 1.0 / *v } else { 1.0 }
    }

    /// 8-bit sRGB pixels after exposure and the `1 - exp(-x)` curve (NaN shows as magenta).
    pub fn tonemap(&self, exposure: f32) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.data.len() * 3);
        for c in &self.data {
            if c.iter().any(|x| !x.is_finite()) {
                out.extend_from_slice(&[255, 0, 255]);
                continue;
            }
            for x in c {
                out.push(srgb_encode(1.0 - (-x.max(0.0) * exposure).exp()));
            }
        }
        out
    }

    /// Writes a tone-mapped 8-bit PNG (`exposure` None: [`Image::auto_exposure`]); returns
    /// the exposure used.
    pub fn write_png(
        &self,
        path: impl AsRef<Path>,
        exposure: Option<f32>,
    ) -> Result<f32, ImageError> {
        let path = path.as_ref();
        let e = exposure.unwrap_or_else(|| self.auto_exposure());
        let mut buf = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut buf, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let png_err = |e: png::EncodingError| ImageError::Png {
                path: path.display().to_string(),
                reason: e.to_string(),
            };
            let mut w = enc.write_header().map_err(png_err)?;
            w.write_image_data(&self.tonemap(e)).map_err(png_err)?;
        }
        write_atomic(path, &buf).map_err(io_err(path))?;
        Ok(e)
    }

    /// Writes a little-endian RGB PFM file (lossless float radiance).
    pub fn write_pfm(&self, path: impl AsRef<Path>) -> Result<(), ImageError> {
        let path = path.as_ref();
        let mut buf = format!("PF\n{} {}\n-1.0\n", self.width, self.height).into_bytes();
        // PFM rows run bottom to top.
        for y in (0..self.height).rev() {
            for x in 0..self.width {
                for c in self.get(x, y) {
                    buf.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        write_atomic(path, &buf).map_err(io_err(path))
    }

    /// Reads an RGB PFM file (either byte order).
    pub fn read_pfm(path: impl AsRef<Path>) -> Result<Image, ImageError> {
        let path = path.as_ref();
        let fmt = |reason: &str| ImageError::Format {
            path: path.display().to_string(),
            reason: reason.into(),
        };
        let file = std::fs::File::open(path).map_err(io_err(path))?;
        let mut r = std::io::BufReader::new(file);
        let mut header = Vec::new();
        while header.len() < 4 {
            let mut line = String::new();
            if r.read_line(&mut line).map_err(io_err(path))? == 0 {
                return Err(fmt("truncated header"));
            }
            header.extend(line.split_whitespace().map(str::to_owned));
        }
        if header[0] != "PF" {
            return Err(fmt("only RGB 'PF' files are supported"));
        }
        let dims: Vec<u32> = header[1..]
            .iter()
            .take(2)
            .map(|s| s.parse().map_err(|_| fmt("bad size")))
            .collect::<Result<_, _>>()?;
        let (w, h) = (dims[0], *dims.get(1).ok_or_else(|| fmt("bad size"))?);
        let scale: f32 = header
            .get(3)
            .ok_or_else(|| fmt("missing scale"))?
            .parse()
            .map_err(|_| fmt("bad scale"))?;
        let mut bytes = Vec::new();
        r.read_to_end(&mut bytes).map_err(io_err(path))?;
        let n = w as usize * h as usize;
        if bytes.len() != n * 12 {
            return Err(fmt("pixel data size does not match the header"));
        }
        let mut img = Image::new(w, h);
        for (k, ch) in bytes.chunks_exact(4).enumerate() {
            let b = [ch[0], ch[1], ch[2], ch[3]];
            let v = if scale < 0.0 {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            };
            let (p, c) = (k / 3, k % 3);
            let (x, yb) = (p % w as usize, p / w as usize);
            let y = h as usize - 1 - yb;
            img.data[y * w as usize + x][c] = v;
        }
        Ok(img)
    }
}
