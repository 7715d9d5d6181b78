{#- ivsv_gather_unwarp: the unwarp of the family of `ivsv_gather` (`sampling =
lowres | epipolar`; scatter_frame::sampling, "The epipolar passes"): ivsv_gather.wgsl rendered with
its second sampling entry point, which gathers every pixel from the samples `ivsv_gather`
wrote to `lowres_samples` or `epipolar_samples` (one more binding) and lists in `fallback_pixels` the pixels no
sample stands for, for `ivsv_gather_fallback`.
Mirrors reference/src/kernels/ivsv_gather_unwarp.rs -#}
{% include "ivsv_gather.wgsl" %}
