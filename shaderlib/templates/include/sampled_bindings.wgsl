{%- if sampling.lowres %}
@group(0) @binding({{ sampling.samples_binding }}) var samples: texture_storage_2d<rgba16float, write>;

// The low-resolution grid's block side S and depth break (a fraction of the nearer depth).
const SCALE: u32 = {{ sampling.scale }}u;
const DEPTH_BREAK: f32 = {{ sampling.depth_break }};
{%- endif %}
