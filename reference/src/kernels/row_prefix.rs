//! CPU mirror of `shaderlib/templates/row_prefix.wgsl` (and of the helpers it imports from
//! `shaderlib/templates/common/indexing.wgsl`): per-row running sum or mean over an rgba
//! texture array, in f32, with the same loop and the same `mix` as the WGSL.
//!
//! Texels are `[f32; 4]` in a flat slice, index `(layer * height + row) * width + x`.

/// What the kernel accumulates along a row (the template's `mode` parameter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Inclusive prefix sum.
    Sum,
    /// Running mean, `F = mix(F, B, 1 / (i + 1))` (Klehm et al. 2014, Listing 1).
    Mean,
}

/// Size of the texture array: `width` texels per row, `height` rows, `layers` layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Dims {
    /// Texels per row (`textureDimensions(input).x`).
    pub width: u32,
    /// Rows per layer (`textureDimensions(input).y`).
    pub height: u32,
    /// Layers (`textureNumLayers(input)`).
    pub layers: u32,
}

impl Dims {
    /// Flat index of texel (x, row, layer).
    pub fn index(&self, x: u32, row: u32, layer: u32) -> usize {
        ((layer as usize * self.height as usize) + row as usize) * self.width as usize + x as usize
    }

    /// Number of texels.
    pub fn texel_count(&self) -> usize {
        self.width as usize * self.height as usize * self.layers as usize
    }
}

// --- scatter::indexing (shaderlib/templates/common/indexing.wgsl) ---

/// `row_in_range` of `scatter::indexing`.
pub fn row_in_range(row: u32, layer: u32, height: u32, layers: u32) -> bool {
    row < height && layer < layers
}

/// `running_mean_weight` of `scatter::indexing`: `1.0 / f32(i + 1u)`.
pub fn running_mean_weight(i: u32) -> f32 {
    1.0 / (i + 1) as f32
}

/// WGSL `mix(e1, e2, e3)` on `vec4<f32>`, as the WGSL spec defines it:
/// `e1 * (1 - e3) + e2 * e3`, component-wise.
pub fn mix(e1: [f32; 4], e2: [f32; 4], e3: [f32; 4]) -> [f32; 4] {
    let mut r = [0.0; 4];
    for c in 0..4 {
        r[c] = e1[c] * (1.0 - e3[c]) + e2[c] * e3[c];
    }
    r
}

fn add(a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]]
}

// --- row_prefix.wgsl ---

/// The body of entry point `row_prefix` for one invocation `id` (x = row, y = layer).
pub fn row_prefix_main(
    id: [u32; 3],
    mode: Mode,
    dims: Dims,
    input: &[[f32; 4]],
    output: &mut [[f32; 4]],
) {
    let size = [dims.width, dims.height];
    let layers = dims.layers;
    let row = id[0];
    let layer = id[1];
    if !row_in_range(row, layer, size[1], layers) {
        return;
    }
    let mut acc = [0.0f32; 4];
    for x in 0..size[0] {
        let texel = input[dims.index(x, row, layer)];
        acc = match mode {
            Mode::Mean => mix(acc, texel, [running_mean_weight(x); 4]),
            Mode::Sum => add(acc, texel),
        };
        output[dims.index(x, row, layer)] = acc;
    }
}

/// Runs `row_prefix` over a whole array: one invocation per (row, layer), as dispatched.
///
/// # Panics
///
/// When `input.len()` is not `dims.texel_count()` (a caller bug, not user input).
pub fn row_prefix(mode: Mode, dims: Dims, input: &[[f32; 4]]) -> Vec<[f32; 4]> {
    assert_eq!(
        input.len(),
        dims.texel_count(),
        "row_prefix mirror: input length does not match {dims:?}"
    );
    let mut output = vec![[0.0f32; 4]; input.len()];
    for layer in 0..dims.layers {
        for row in 0..dims.height {
            row_prefix_main([row, layer, 0], mode, dims, input, &mut output);
        }
    }
    output
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_of_a_row_is_the_running_mean() {
        let dims = Dims {
            width: 4,
            height: 1,
            layers: 1,
        };
        let input = [
            [1.0, 0.0, 2.0, 4.0],
            [3.0, 0.0, 2.0, 0.0],
            [5.0, 3.0, 2.0, 0.0],
            [7.0, 1.0, 2.0, 0.0],
        ];
        let out = row_prefix(Mode::Mean, dims, &input);
        let close = |a: [f32; 4], b: [f32; 4]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= 1e-6);
        assert_eq!(out[0], input[0], "weight 1 copies the first texel exactly");
        assert!(close(out[1], [2.0, 0.0, 2.0, 2.0]), "{:?}", out[1]);
        assert!(close(out[3], [4.0, 1.0, 2.0, 1.0]), "{:?}", out[3]);
    }

    #[test]
    fn sum_is_inclusive_and_rows_are_independent() {
        let dims = Dims {
            width: 3,
            height: 2,
            layers: 2,
        };
        let input: Vec<[f32; 4]> = (0..12).map(|i| [i as f32, 1.0, 0.0, -1.0]).collect();
        let out = row_prefix(Mode::Sum, dims, &input);
        assert_eq!(out[dims.index(2, 0, 0)], [3.0, 3.0, 0.0, -3.0]);
        assert_eq!(out[dims.index(0, 1, 1)], [9.0, 1.0, 0.0, -1.0]);
        assert_eq!(out[dims.index(2, 1, 1)], [30.0, 3.0, 0.0, -3.0]);
    }
}
