{#- scatter_unwarp: the epipolar unwarp of the family of `scatter` (`sampling = epipolar`;
scatter_frame::sampling, "The epipolar passes"): scatter.wgsl rendered with its second
sampling entry point, which gathers every pixel from the samples `scatter` wrote to
`epipolar_samples` (one more binding) and lists in `fallback_pixels` the pixels no sample
stands for, for `scatter_fallback`. Mirrors reference/src/kernels/scatter_unwarp.rs -#}
{% include "scatter.wgsl" %}
