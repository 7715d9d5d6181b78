{#- raymarch_fallback: the fallback of the family of `raymarch` (`sampling = lowres | epipolar`;
scatter_frame::sampling, "The epipolar passes"): raymarch.wgsl rendered with its third
sampling entry point, which evaluates with raymarch's per-pixel body the pixels
`raymarch_unwarp` listed in `fallback_pixels` (no sample stands for them) and writes them to
`output`. Mirrors reference/src/kernels/raymarch_fallback.rs -#}
{% include "raymarch.wgsl" %}
