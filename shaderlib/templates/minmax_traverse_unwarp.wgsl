{#- minmax_traverse_unwarp: the unwarp of the family of `minmax_traverse` (`sampling = lowres | epipolar`;
scatter_frame::sampling, "The epipolar passes"): minmax_traverse.wgsl rendered with its second
sampling entry point, which gathers every pixel from the samples `minmax_traverse` wrote to
`lowres_samples` or `epipolar_samples` (one more binding) and lists in `fallback_pixels` the pixels no sample
stands for, for `minmax_traverse_fallback`. Mirrors reference/src/kernels/minmax_traverse_unwarp.rs -#}
{% include "minmax_traverse.wgsl" %}
