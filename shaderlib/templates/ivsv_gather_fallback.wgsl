{#- ivsv_gather_fallback: the fallback of the family of `ivsv_gather` (`sampling =
lowres | epipolar`; scatter_frame::sampling, "The epipolar passes"): ivsv_gather.wgsl rendered with
its third sampling entry point, which evaluates with ivsv_gather's per-pixel body the pixels
`ivsv_gather_unwarp` listed in `fallback_pixels` (no sample stands for them) and writes them
to `output`.
Mirrors reference/src/kernels/ivsv_gather_fallback.rs -#}
{% include "ivsv_gather.wgsl" %}
