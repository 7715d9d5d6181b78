{#- volume_march_unwarp: the unwarp of the family of `volume_march` (`sampling = lowres | epipolar`;
scatter_frame::sampling, "The epipolar passes"): volume_march.wgsl rendered with its second
sampling entry point, which gathers every pixel from the samples `volume_march` wrote to
`lowres_samples` or `epipolar_samples` (one more binding) and lists in `fallback_pixels` the pixels no sample
stands for, for `volume_march_fallback`. Mirrors reference/src/kernels/volume_march_unwarp.rs -#}
{% include "volume_march.wgsl" %}
