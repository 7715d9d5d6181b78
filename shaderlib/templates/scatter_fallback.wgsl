{#- scatter_fallback: the fallback of the family of `scatter` (`sampling = lowres | epipolar`;
scatter_frame::sampling, "The epipolar passes"): scatter.wgsl rendered with its third
sampling entry point, which evaluates with scatter's per-pixel body the pixels
`scatter_unwarp` listed in `fallback_pixels` (no sample stands for them) and writes them to
`output`. Mirrors reference/src/kernels/scatter_fallback.rs -#}
{% include "scatter.wgsl" %}
