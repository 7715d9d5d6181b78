//! The texture operations of the CPU mirrors (no WGSL module: in the kernels they are
//! `textureLoad` and `textureStore`): r32float and rgba texture arrays, what a storage
//! texture of each format keeps of a value, and WGSL's `mix` of two texels. Every family's
//! mirrors use them.

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
    /// A 1 x 1 white texel: the cookie a `cookie` variant's mirror reads when it is given none.
    pub fn white() -> TexArray {
        TexArray {
            width: 1,
            height: 1,
            layers: 1,
            data: vec![[1.0; 4]],
        }
    }

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

/// WGSL `mix` of two vec4 with a scalar weight: `a (1 - t) + b t`.
pub fn mix4(a: [f32; 4], b: [f32; 4], t: f32) -> [f32; 4] {
    [0, 1, 2, 3].map(|k| a[k] * (1.0 - t) + b[k] * t)
}

/// `.xyz` of a vec4.
pub fn xyz(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}
