{#- minmax_traverse_unwarp: the epipolar unwarp of the family of `minmax_traverse` (`sampling = epipolar`;
scatter_frame::sampling, "The epipolar passes"): minmax_traverse.wgsl rendered with its second
sampling entry point, which gathers every pixel from the samples `minmax_traverse` wrote to
`epipolar_samples` (one more binding) and evaluates with minmax_traverse's per-pixel body the pixels no
sample stands for. Mirrors reference/src/kernels/minmax_traverse_unwarp.rs -#}
{% include "minmax_traverse.wgsl" %}
