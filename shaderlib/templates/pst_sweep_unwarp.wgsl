{#- pst_sweep_unwarp: the epipolar unwarp of the `partial_sum_tree` family (`sampling = epipolar`;
scatter_frame::sampling, "The epipolar passes"): pst_sweep.wgsl rendered with the second
sampling entry point, which gathers every pixel from the samples `pst_sweep` wrote to
`epipolar_samples` (one more binding) and lists in `fallback_pixels` the pixels no sample
stands for, for `pst_sweep_fallback`. Mirrors reference/src/kernels/pst_sweep_unwarp.rs -#}
{% include "pst_sweep.wgsl" %}
