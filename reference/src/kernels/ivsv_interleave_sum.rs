//! CPU mirror of `shaderlib/templates/ivsv_interleave_sum.wgsl`: every pixel adds the
//! partial sums of the `M x M` window around it (centred, clamped inside the screen).

use scatter_shaderlib::area_ivsv::IvsvUniforms;

/// First of the `m` consecutive pixels of the window of pixel `pos` in a line of `len >= m`.
pub fn window_first(pos: u32, m: u32, len: u32) -> u32 {
    (pos as i32 - (m / 2) as i32).clamp(0, len as i32 - m as i32) as u32
}

/// The whole pass: the window sums of `partial` (row-major), not yet rounded to
/// `rgba16float`.
pub fn ivsv_interleave_sum(
    m: &IvsvUniforms,
    partial: &[[f32; 3]],
    interleave: u32,
) -> Vec<[f32; 3]> {
    let (w, h) = (m.sizes[0], m.sizes[1]);
    let mut out = Vec::with_capacity(partial.len());
    for y in 0..h {
        for x in 0..w {
            let x0 = window_first(x, interleave, w);
            let y0 = window_first(y, interleave, h);
            let mut sum = [0.0f32; 3];
            for j in 0..interleave {
                for i in 0..interleave {
                    let p = partial[((y0 + j) * w + x0 + i) as usize];
                    for k in 0..3 {
                        sum[k] += p[k];
                    }
                }
            }
            out.push(sum);
        }
    }
    out
}
