{#- minmax_traverse_fallback: the fallback of the family of `minmax_traverse` (`sampling = lowres | epipolar`;
scatter_frame::sampling, "The epipolar passes"): minmax_traverse.wgsl rendered with its third
sampling entry point, which evaluates with minmax_traverse's per-pixel body the pixels
`minmax_traverse_unwarp` listed in `fallback_pixels` (no sample stands for them) and writes them to
`output`. Mirrors reference/src/kernels/minmax_traverse_fallback.rs -#}
{% include "minmax_traverse.wgsl" %}
