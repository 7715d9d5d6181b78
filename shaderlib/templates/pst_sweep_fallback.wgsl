{#- pst_sweep_fallback: the epipolar fallback of the `partial_sum_tree` family (`sampling = epipolar`;
scatter_frame::sampling, "The epipolar passes"): pst_sweep.wgsl rendered with the third
sampling entry point, which evaluates with `pst_sweep_pixel` (the pixel's own nearest row, its
lit whole columns' leaves summed without the tree) the pixels `pst_sweep_unwarp` listed in
`fallback_pixels` and writes them to `output`. Mirrors reference/src/kernels/pst_sweep_fallback.rs -#}
{% include "pst_sweep.wgsl" %}
