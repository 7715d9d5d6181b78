{#- volume_march_fallback: the fallback of the family of `volume_march` (`sampling = lowres | epipolar`;
scatter_frame::sampling, "The epipolar passes"): volume_march.wgsl rendered with its third
sampling entry point, which evaluates with volume_march's per-pixel body the pixels
`volume_march_unwarp` listed in `fallback_pixels` (no sample stands for them) and writes them to
`output`. Mirrors reference/src/kernels/volume_march_fallback.rs -#}
{% include "volume_march.wgsl" %}
