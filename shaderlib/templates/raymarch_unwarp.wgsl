{#- raymarch_unwarp: the unwarp of the family of `raymarch` (`sampling = lowres | epipolar`;
scatter_frame::sampling, "The epipolar passes"): raymarch.wgsl rendered with its second
sampling entry point, which gathers every pixel from the samples `raymarch` wrote to
`lowres_samples` or `epipolar_samples` (one more binding) and lists in `fallback_pixels` the pixels no sample
stands for, for `raymarch_fallback`. Mirrors reference/src/kernels/raymarch_unwarp.rs -#}
{% include "raymarch.wgsl" %}
