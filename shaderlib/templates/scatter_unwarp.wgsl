{#- scatter_unwarp: the unwarp of the family of `scatter` (`sampling = lowres | epipolar`;
scatter_frame::sampling, "The epipolar passes"): scatter.wgsl rendered with its second
sampling entry point, which gathers every pixel from the samples `scatter` wrote to
`lowres_samples` or `epipolar_samples` (one more binding) and lists in `fallback_pixels` the pixels no sample
stands for, for `scatter_fallback`. Mirrors reference/src/kernels/scatter_unwarp.rs -#}
{% include "scatter.wgsl" %}
