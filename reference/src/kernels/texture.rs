//! The texture operations of the CPU mirrors (no WGSL module: in the kernels they are
//! `textureLoad`, `textureStore` and `textureSampleLevel`): r32float and rgba texture arrays,
//! what a storage texture of each format keeps of a value, and the bilinear fetch with the
//! samplers' address modes. Every family's mirrors use them.

use glam::Vec3;
use scatter_shaderlib::prefiltered::Storage;

/// An r32float texture (row-major from the top-left texel).
#[derive(Clone, Debug, PartialEq)]
pub struct Tex {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Texels.
    pub data: Vec<f32>,
}

impl Tex {
    /// A zeroed texture.
    pub fn new(width: u32, height: u32) -> Tex {
        Tex {
            width,
            height,
            data: vec![0.0; width as usize * height as usize],
        }
    }
    /// WGSL `textureLoad` (coordinates must be in range).
    pub fn load(&self, x: u32, y: u32) -> f32 {
        self.data[(y * self.width + x) as usize]
    }
    /// WGSL `textureStore`.
    pub fn store(&mut self, x: u32, y: u32, v: f32) {
        self.data[(y * self.width + x) as usize] = v;
    }
}

/// An rgba texture array (layer-major, then row-major).
#[derive(Clone, Debug, PartialEq)]
pub struct TexArray {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Layers.
    pub layers: u32,
    /// Texels, index `(layer * height + y) * width + x`.
    pub data: Vec<[f32; 4]>,
}

impl TexArray {
    /// A zeroed array.
    pub fn new(width: u32, height: u32, layers: u32) -> TexArray {
        TexArray {
            width,
            height,
            layers,
            data: vec![[0.0; 4]; width as usize * height as usize * layers as usize],
        }
    }
    fn index(&self, x: u32, y: u32, layer: u32) -> usize {
        ((layer * self.height + y) * self.width + x) as usize
    }
    /// WGSL `textureLoad`.
    pub fn load(&self, x: u32, y: u32, layer: u32) -> [f32; 4] {
        self.data[self.index(x, y, layer)]
    }
    /// WGSL `textureStore` into a storage texture of format `storage` (quantised as the
    /// format stores it).
    pub fn store(&mut self, x: u32, y: u32, layer: u32, v: [f32; 4], storage: Storage) {
        let i = self.index(x, y, layer);
        self.data[i] = v.map(|c| quantise(c, storage));
    }
}

/// The value a storage texture of `storage` format keeps for `v`.
pub fn quantise(v: f32, storage: Storage) -> f32 {
    match storage {
        Storage::Rgba8unorm => (v.clamp(0.0, 1.0) * 255.0).round() / 255.0,
        Storage::Rgba16float => round_f16(v),
        Storage::Rgba32float => v,
    }
}

/// Rounds an f32 to the nearest f16 value (ties to even), returned as f32.
pub fn round_f16(v: f32) -> f32 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let e = v.abs().log2().floor() as i32;
    // Spacing of f16 values around v: 2^(e - 10) for normals, 2^-24 for subnormals.
    let q = if e < -14 {
        2f32.powi(-24)
    } else {
        2f32.powi(e - 10)
    };
    let r = (v / q).round_ties_even() * q;
    if r.abs() > 65504.0 {
        v.signum() * f32::INFINITY
    } else {
        r
    }
}

/// Bilinear sample of layer `layer` at texel-space position (`x`, `y`) (texel `i`'s centre at
/// `i + 0.5`), clamp-to-edge in x, wrap-around in y when `wrap_y`, else clamp-to-edge.
pub fn sample_bilinear(t: &TexArray, layer: u32, x: f32, y: f32, wrap_y: bool) -> [f32; 4] {
    let (x0, fx) = split(x - 0.5);
    let (y0, fy) = split(y - 0.5);
    let cx = |i: i64| i.clamp(0, i64::from(t.width) - 1) as u32;
    let h = i64::from(t.height);
    let cy = |j: i64| {
        if wrap_y {
            j.rem_euclid(h) as u32
        } else {
            j.clamp(0, h - 1) as u32
        }
    };
    let a = t.load(cx(x0), cy(y0), layer);
    let b = t.load(cx(x0 + 1), cy(y0), layer);
    let c = t.load(cx(x0), cy(y0 + 1), layer);
    let d = t.load(cx(x0 + 1), cy(y0 + 1), layer);
    let mut out = [0.0; 4];
    for k in 0..4 {
        let top = a[k] * (1.0 - fx) + b[k] * fx;
        let bottom = c[k] * (1.0 - fx) + d[k] * fx;
        out[k] = top * (1.0 - fy) + bottom * fy;
    }
    out
}

fn split(x: f32) -> (i64, f32) {
    let f = x.floor();
    (f as i64, x - f)
}

/// `.xyz` of a vec4.
pub fn xyz(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}
