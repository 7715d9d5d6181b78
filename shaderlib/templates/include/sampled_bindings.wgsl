{%- if sampling.lowres %}

// The low-resolution grid's block side S, and its depth and light breaks (fractions).
const SCALE: u32 = {{ sampling.scale }}u;
const DEPTH_BREAK: f32 = {{ sampling.depth_break }};
const LIGHT_BREAK: f32 = {{ sampling.light_break }};
{%- endif %}
