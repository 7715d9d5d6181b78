//! The small engine's frame (issue 18): rasterised inputs ([`crate::raster`]), any kernel
//! family's passes on them through `scatter-runtime`, a forward-shaded scene and a composite,
//! all on the GPU until the final readback of the 8-bit image.
//!
//! One frame, in order (each stage submitted and waited for, so that it can be timed; no
//! texture leaves the GPU between stages):
//! 1. `raster`: the camera's linear view depth and the light's shadow map ([`Rasteriser::render`]);
//! 2. `rectified`: in a projective frame, the rectified map with the frame's matrices and
//!    viewports ([`Rasteriser::rectified`]), as the README tells an engine to;
//! 3. the family's passes ([`FamilyPasses`]), reading those render targets as they are;
//! 4. `shade`: the tessellated scene drawn again with a forward shading pipeline into an
//!    `Rgba16Float` target: Lambert with the light's shadow map (nearest texel, the
//!    `shadow_map` truth's bias), the spot's cone and `1/d^2` and its extinction
//!    `exp(-sigma_t d)`, an ambient term `albedo * sky`, all attenuated by the view ray's
//!    transmittance `exp(-sigma_t s)`; pixels that see no surface get `sky * exp(-sigma_t s)`
//!    to the far plane. It mirrors `scatter_reference::truth::surface_radiance` term by term
//!    (which casts an exact shadow ray where this reads the map);
//! 5. `exposure` (unless fixed): one over the 99.5th percentile of the luminance of shaded +
//!    shafts, as `scatter_reference::image` exposes its PNGs, from a 256-bin log histogram
//!    (1/8 stop per bin) built by one workgroup, into a one-float buffer;
//! 6. `composite`: shaded + shafts, times the exposure, the ACES filmic fit (Narkowicz 2015),
//!    sRGB-encoded into an `Rgba8Unorm` storage texture ([`tonemap`] is its CPU twin).

use std::time::{Duration, Instant};

use scatter_reference::buffers::{ShadowMap, ShadowProjection};
use scatter_reference::bvh::Bvh;
use scatter_reference::desc::SHADOW_BIAS_TEXELS;
use scatter_reference::scene::{Light, Scene};
use scatter_runtime::shaderlib::Kernel;
use scatter_runtime::shaderlib::family::FamilyVariant;
use scatter_runtime::shaderlib::prefiltered::{FrameReport, FrameSettings, Resolutions};
use scatter_runtime::textures::read_rgba16float;
use scatter_runtime::wgpu;
use scatter_runtime::{Context, FamilyPasses, FrameInput, Inputs};

use crate::raster::{RasterError, RasterFrame, Rasteriser, Triangles, cleared_depth, read_texture};

/// What to render a frame with.
#[derive(Clone, Copy, Debug)]
pub struct EngineSettings {
    /// The family and its knobs (the light must match the scene's).
    pub variant: FamilyVariant,
    /// Shadow map size (square).
    pub shadow_map: u32,
    /// Rectified map size of a family that has one.
    pub rectified: [u32; 2],
    /// A fixed exposure, or `None` for one from the frame's luminance histogram on the GPU.
    pub exposure: Option<f32>,
}

/// One rendered frame: every texture still on the GPU, the image read back.
#[derive(Debug)]
pub struct EngineFrame {
    /// The rasterised depth buffer and shadow map (and the triangles).
    pub raster: RasterFrame,
    /// The projective frame's rasterised rectified map (`None`: not projective).
    pub rectified: Option<wgpu::Texture>,
    /// The family's passes; `output_texture()` is the in-scattered radiance (the shafts).
    pub family: FamilyPasses,
    /// The frame report of an epipolar family.
    pub report: Option<FrameReport>,
    /// The shaded scene, attenuated by the medium (`Rgba16Float`, linear radiance).
    pub shaded: wgpu::Texture,
    /// The exposure the composite used (one f32; `STORAGE | COPY_SRC`).
    pub exposure: wgpu::Buffer,
    /// The tone-mapped sRGB composite (`Rgba8Unorm`).
    pub composite: wgpu::Texture,
    /// The composite read back: RGB, 8 bits, row-major from the top-left pixel.
    pub image: Vec<u8>,
    /// Wall time of each stage, submitted and waited for, in order.
    pub times: Vec<(String, Duration)>,
}

impl EngineFrame {
    /// The exposure read back.
    ///
    /// # Errors
    ///
    /// The readback fails.
    pub fn exposure(&self, ctx: &Context) -> Result<f32, RasterError> {
        let bytes = read_buffer(ctx, &self.exposure)?;
        Ok(f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]))
    }

    /// The shaded scene read back (linear RGB).
    ///
    /// # Errors
    ///
    /// The readback fails.
    pub fn read_shaded(&self, ctx: &Context) -> Result<Vec<[f32; 4]>, RasterError> {
        read_rgba16float(ctx, Kernel::Scatter, &self.shaded).map_err(|e| format!("shaded: {e}"))
    }

    /// The family's output (the shafts) read back (linear RGB).
    ///
    /// # Errors
    ///
    /// The readback fails.
    pub fn read_shafts(&self, ctx: &Context) -> Result<Vec<[f32; 4]>, RasterError> {
        read_rgba16float(ctx, Kernel::Scatter, self.family.output_texture())
            .map_err(|e| format!("shafts: {e}"))
    }
}

/// The ACES filmic fit of Narkowicz 2015 (`x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`).
fn aces(x: f32) -> f32 {
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// The sRGB transfer function.
fn srgb(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The composite's tone map on the CPU, the twin of `composite` in [`COMPOSITE_SHADER`]:
/// linear radiance times `exposure`, ACES fit, sRGB, 8 bits (NaN or Inf: magenta).
pub fn tonemap(c: [f32; 3], exposure: f32) -> [u8; 3] {
    if c.iter().any(|x| !x.is_finite()) {
        return [255, 0, 255];
    }
    c.map(|x| (srgb(aces(x.max(0.0) * exposure)) * 255.0 + 0.5) as u8)
}

/// The shading pass: sky, then the scene. Mirrors `truth::surface_radiance`.
const SHADE_SHADER: &str = r"
struct Shade {
    // xyz, sigma_t
    cam_pos: vec4<f32>,
    // xyz, 1 / (t a)
    cam_right: vec4<f32>,
    // xyz, 1 / t
    cam_up: vec4<f32>,
    // xyz, near
    cam_forward: vec4<f32>,
    // far, width, height, -
    cam_extra: vec4<f32>,
    // rgb, -
    sky: vec4<f32>,
    // rgb, 0 directional / 1 spot
    light_color: vec4<f32>,
    // spot position, cos(outer)
    light_pos: vec4<f32>,
    // direction light travels (the spot's axis), cos(inner)
    light_dir: vec4<f32>,
    // cone: 0 none, 1 step at cos(outer), 2 smoothstep; shadow map size; bias texels;
    // 1 = the spot has a cookie
    light_extra: vec4<f32>,
    // map origin, 1 = perspective
    sm_origin: vec4<f32>,
    // map basis, near / far / -
    sm_right: vec4<f32>,
    sm_up: vec4<f32>,
    sm_forward: vec4<f32>,
    // orthographic x0, x1, y0, y1; perspective tan_half, -, -, -
    sm_window: vec4<f32>,
}

@group(0) @binding(0) var<uniform> u: Shade;
@group(0) @binding(1) var shadow_map: texture_2d<f32>;
// The spot's cookie (white 1 x 1 without one), the texture the family's passes read.
@group(0) @binding(2) var cookie: texture_2d<f32>;

const PI: f32 = 3.14159265358979;

struct Surface {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) albedo: vec3<f32>,
}

// The camera depth pass's projection (raster.rs), so that both cover the same pixels.
@vertex
fn vs(@location(0) p: vec3<f32>, @location(1) n: vec3<f32>, @location(2) albedo: vec3<f32>) -> Surface {
    let q = p - u.cam_pos.xyz;
    let x = dot(q, u.cam_right.xyz);
    let y = dot(q, u.cam_up.xyz);
    let z = dot(q, u.cam_forward.xyz);
    let near = u.cam_forward.w;
    let far = u.cam_extra.x;
    var out: Surface;
    out.clip = vec4<f32>(x * u.cam_right.w, y * u.cam_up.w, far * (z - near) / (far - near), z);
    out.world = p;
    out.normal = n;
    out.albedo = albedo;
    return out;
}

// ShadowMap::visibility: 1 lit, 0 shadowed; lit outside the map and behind a spot.
fn visibility(p: vec3<f32>) -> f32 {
    let q = p - u.sm_origin.xyz;
    let x = dot(q, u.sm_right.xyz);
    let y = dot(q, u.sm_up.xyz);
    let z = dot(q, u.sm_forward.xyz);
    let near = u.sm_right.w;
    let far = u.sm_up.w;
    let size = u.light_extra.y;
    let w = u.sm_window;
    var uv: vec2<f32>;
    var footprint: f32;
    if u.sm_origin.w > 0.5 {
        if z <= near {
            return 1.0;
        }
        uv = vec2<f32>(0.5 + 0.5 * x / (z * w.x), 0.5 - 0.5 * y / (z * w.x));
        footprint = 2.0 * max(z, 0.0) * w.x;
    } else {
        uv = vec2<f32>((x - w.x) / (w.y - w.x), (w.w - y) / (w.w - w.z));
        footprint = max(w.y - w.x, w.w - w.z);
    }
    if any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0)) {
        return 1.0;
    }
    let n = i32(size);
    let texel = min(vec2<i32>(uv * size), vec2<i32>(n - 1));
    let stored = textureLoad(shadow_map, texel, 0).r;
    let bias = u.light_extra.z * footprint / size / (far - near);
    return select(0.0, 1.0, (z - near) / (far - near) <= stored + bias);
}

// model::cone_falloff.
fn cone(cos_angle: f32) -> f32 {
    let mode = u.light_extra.x;
    let co = u.light_pos.w;
    let ci = u.light_dir.w;
    if mode < 0.5 {
        return 1.0;
    }
    if mode < 1.5 {
        return select(0.0, 1.0, cos_angle >= co);
    }
    let x = clamp((cos_angle - co) / (ci - co), 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

// scatter_frame::cookie for a point `from_lamp` away from the spot lamp: the cookie in the
// spot's shadow-map basis (its square circumscribing the outer cone), bilinear between texel
// centres from four loads, clamped to the edge; black behind the lamp; white without a
// cookie. The kernels' `scatter::cookie::spot_cookie`.
fn cookie_tint(from_lamp: vec3<f32>) -> vec3<f32> {
    if u.light_extra.w < 0.5 {
        return vec3<f32>(1.0);
    }
    let z = dot(from_lamp, u.sm_forward.xyz);
    if z <= 0.0 {
        return vec3<f32>(0.0);
    }
    let co = u.light_pos.w;
    let tan_outer = sqrt(max(1.0 - co * co, 0.0)) / co;
    let a = dot(from_lamp, u.sm_right.xyz) / (z * tan_outer);
    let b = dot(from_lamp, u.sm_up.xyz) / (z * tan_outer);
    let size = vec2<i32>(textureDimensions(cookie));
    let q = vec2<f32>(0.5 * (a + 1.0), 0.5 * (1.0 - b)) * vec2<f32>(size) - 0.5;
    let q0 = floor(q);
    let t = q - q0;
    let i0 = clamp(vec2<i32>(q0), vec2<i32>(0), size - 1);
    let i1 = clamp(vec2<i32>(q0) + 1, vec2<i32>(0), size - 1);
    let top = mix(textureLoad(cookie, i0, 0).rgb, textureLoad(cookie, vec2<i32>(i1.x, i0.y), 0).rgb, t.x);
    let bottom = mix(textureLoad(cookie, vec2<i32>(i0.x, i1.y), 0).rgb, textureLoad(cookie, i1, 0).rgb, t.x);
    return mix(top, bottom, t.y);
}

@fragment
fn fs(in: Surface) -> @location(0) vec4<f32> {
    let sigma_t = u.cam_pos.w;
    let to_eye = u.cam_pos.xyz - in.world;
    let s = length(to_eye);
    // Two-sided: the normal facing the camera (zero for a degenerate triangle).
    var n = in.normal;
    if dot(n, n) > 0.0 {
        n = normalize(n);
    }
    if dot(n, to_eye) < 0.0 {
        n = -n;
    }
    let p = in.world + n * 1e-4;
    var to_light: vec3<f32>;
    var l_in: f32;
    var tint = vec3<f32>(1.0);
    if u.light_color.w < 0.5 {
        to_light = -u.light_dir.xyz;
        l_in = 1.0;
    } else {
        let d = u.light_pos.xyz - p;
        let dist = max(length(d), 1e-9);
        to_light = d / dist;
        l_in = cone(dot(-to_light, u.light_dir.xyz)) * exp(-sigma_t * dist) / (dist * dist);
        tint = cookie_tint(-d);
    }
    let cos_n = max(dot(n, to_light), 0.0);
    var lit = 0.0;
    if cos_n > 0.0 {
        lit = visibility(p);
    }
    let direct = in.albedo / PI * u.light_color.rgb * tint * (l_in * cos_n * lit);
    let ambient = in.albedo * u.sky.rgb;
    return vec4<f32>((direct + ambient) * exp(-sigma_t * s), 1.0);
}

// A full-screen triangle behind everything: the sky seen through the medium to the far plane.
@vertex
fn vs_sky(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    return vec4<f32>(xy, 0.5, 1.0);
}

@fragment
fn fs_sky(@builtin(position) at: vec4<f32>) -> @location(0) vec4<f32> {
    let ndc = vec2<f32>(2.0 * at.x / u.cam_extra.y - 1.0, 1.0 - 2.0 * at.y / u.cam_extra.z);
    let f = u.cam_forward.xyz;
    let dir = normalize(f + u.cam_right.xyz * (ndc.x / u.cam_right.w) + u.cam_up.xyz * (ndc.y / u.cam_up.w));
    let s = u.cam_extra.x / dot(dir, f);
    return vec4<f32>(u.sky.rgb * exp(-u.cam_pos.w * s), 1.0);
}
";

/// The exposure (one workgroup) and composite passes. `tonemap` is the CPU twin of
/// `composite`.
const COMPOSITE_SHADER: &str = r"
@group(0) @binding(0) var shaded: texture_2d<f32>;
@group(0) @binding(1) var shafts: texture_2d<f32>;
@group(0) @binding(2) var<storage, read_write> exposure: array<f32>;
@group(0) @binding(3) var image: texture_storage_2d<rgba8unorm, write>;

var<workgroup> bins: array<atomic<u32>, 256>;

fn radiance(p: vec2<i32>) -> vec3<f32> {
    return textureLoad(shaded, p, 0).rgb + textureLoad(shafts, p, 0).rgb;
}

// Histogram bin of a luminance: 8 per stop over 2^-16..2^16, bin 0 at or below 2^-16.
fn bin(l: f32) -> u32 {
    if l <= 1.52587890625e-5 {
        return 0u;
    }
    return u32(clamp((log2(l) + 16.0) * 8.0, 0.0, 255.0));
}

// exposure[0] = 1 / the 99.5th percentile of luminance (the middle of its bin; 1 when that
// is in bin 0), the non-finite pixels left out: scatter_reference::image's auto exposure
// from a histogram instead of a sort.
@compute @workgroup_size(256)
fn log_histogram(@builtin(local_invocation_index) lid: u32) {
    let size = textureDimensions(shaded);
    let count = size.x * size.y;
    atomicStore(&bins[lid], 0u);
    workgroupBarrier();
    for (var i = lid; i < count; i += 256u) {
        let c = radiance(vec2<i32>(vec2<u32>(i % size.x, i / size.x)));
        let l = dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
        // NaN fails both comparisons; Inf the second.
        if l >= -3e38 && l <= 3e38 {
            atomicAdd(&bins[bin(l)], 1u);
        }
    }
    workgroupBarrier();
    if lid == 0u {
        var finite = 0u;
        for (var b = 0u; b < 256u; b++) {
            finite += atomicLoad(&bins[b]);
        }
        let k = u32(f32(max(finite, 1u) - 1u) * 0.995);
        var below = 0u;
        var at = 0u;
        for (var b = 0u; b < 256u; b++) {
            below += atomicLoad(&bins[b]);
            if below > k {
                at = b;
                break;
            }
        }
        exposure[0] = select(1.0 / exp2((f32(at) + 0.5) / 8.0 - 16.0), 1.0, at == 0u);
    }
}

fn aces(x: vec3<f32>) -> vec3<f32> {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
}

fn srgb(x: vec3<f32>) -> vec3<f32> {
    return select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055, 12.92 * x, x <= vec3<f32>(0.0031308));
}

@compute @workgroup_size(8, 8)
fn composite(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(image);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let p = vec2<i32>(id.xy);
    let c = radiance(p);
    // NaN or Inf: magenta, as scatter_reference::image does.
    var out = vec3<f32>(1.0, 0.0, 1.0);
    if all(c >= vec3<f32>(-3e38)) && all(c <= vec3<f32>(3e38)) {
        out = srgb(aces(max(c, vec3<f32>(0.0)) * exposure[0]));
    }
    textureStore(image, p, vec4<f32>(out, 1.0));
}
";

/// The uniform block of [`SHADE_SHADER`]: fifteen vec4.
const SHADE_UNIFORM_SIZE: u64 = 15 * 16;

/// The shading uniform's contents for `scene` and its fitted map.
fn shade_uniform(scene: &Scene, map: &ShadowMap) -> Vec<u8> {
    let cam = &scene.camera;
    let f = cam.frame();
    let t = cam.tan_half_fov();
    let v = |d: glam::DVec3, w: f64| [d.x as f32, d.y as f32, d.z as f32, w as f32];
    let sky = scene.sky;
    // An area light shades as its point limit (the kernels' passes are per point light).
    let light = scene
        .light
        .area()
        .map_or_else(|| scene.light.clone(), |a| a.point_limit());
    let color = light.color();
    let (kind, pos, dir, cos_outer, cos_inner, mode) = match &light {
        Light::Directional { direction, .. } => {
            (0.0, glam::DVec3::ZERO, direction.normalize(), 0.0, 0.0, 0.0)
        }
        Light::Spot {
            position,
            direction,
            inner_angle_deg,
            outer_angle_deg,
            ..
        } => {
            let (ci, co) = (
                inner_angle_deg.to_radians().cos(),
                outer_angle_deg.to_radians().cos(),
            );
            // model::cone_falloff's three cases.
            let mode = if *outer_angle_deg >= 180.0 && *inner_angle_deg >= 180.0 {
                0.0
            } else if ci - co <= 1e-12 {
                1.0
            } else {
                2.0
            };
            (1.0, *position, direction.normalize(), co, ci, mode)
        }
        Light::Area(_) => unreachable!("replaced by its point limit above"),
    };
    let (perspective, window) = match map.projection {
        ShadowProjection::Orthographic { x0, x1, y0, y1 } => (0.0, [x0, x1, y0, y1]),
        ShadowProjection::Perspective { tan_half } => (1.0, [tan_half, 0.0, 0.0, 0.0]),
    };
    let rows: [[f32; 4]; 15] = [
        v(cam.position, scene.medium.sigma_t),
        v(f.right, 1.0 / (t * cam.aspect())),
        v(f.up, 1.0 / t),
        v(f.forward, cam.near),
        [cam.far as f32, cam.width as f32, cam.height as f32, 0.0],
        [sky[0] as f32, sky[1] as f32, sky[2] as f32, 0.0],
        [color[0] as f32, color[1] as f32, color[2] as f32, kind],
        v(pos, cos_outer),
        v(dir, cos_inner),
        [
            mode,
            map.size as f32,
            SHADOW_BIAS_TEXELS as f32,
            if scene.light.cookie().is_some() {
                1.0
            } else {
                0.0
            },
        ],
        v(map.origin, perspective),
        v(map.basis[0], map.near),
        v(map.basis[1], map.far),
        v(map.basis[2], 0.0),
        window.map(|w| w as f32),
    ];
    rows.iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect()
}

/// The shading vertices: position, normal, albedo (nine f32 each).
fn shade_vertices(scene: &Scene, soup: &Triangles) -> Vec<u8> {
    let mut out = Vec::with_capacity(soup.positions.len() * 36);
    for ((p, n), s) in soup.positions.iter().zip(&soup.normals).zip(&soup.shapes) {
        let a = scene.geometry[*s as usize].albedo().map(|x| x as f32);
        for x in p.iter().chain(n).chain(&a) {
            out.extend(x.to_le_bytes());
        }
    }
    out
}

/// The engine's pipelines (built once, used for every frame).
#[derive(Debug)]
pub struct Engine {
    rasteriser: Rasteriser,
    shade_layout: wgpu::BindGroupLayout,
    shade: wgpu::RenderPipeline,
    sky: wgpu::RenderPipeline,
    log_histogram: wgpu::ComputePipeline,
    composite: wgpu::ComputePipeline,
}

impl Engine {
    /// Compiles the pipelines.
    pub fn new(ctx: &Context) -> Self {
        let device = ctx.device();
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("engine shade"),
            source: wgpu::ShaderSource::Wgsl(SHADE_SHADER.into()),
        });
        // The fragment shader's textures (shadow map, cookie): loaded, not sampled.
        let texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let shade_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("engine shade"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                texture(1),
                texture(2),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("engine shade"),
            bind_group_layouts: &[Some(&shade_layout)],
            immediate_size: 0,
        });
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];
        let buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: 36,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attributes,
        })];
        let pipeline =
            |vs: &str, fs: &str, buffers: &[Option<wgpu::VertexBufferLayout<'_>>], sky: bool| {
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(if sky { "engine sky" } else { "engine shade" }),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(vs),
                        compilation_options: Default::default(),
                        buffers,
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleList,
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: wgpu::TextureFormat::Depth32Float,
                        depth_write_enabled: Some(!sky),
                        depth_compare: Some(if sky {
                            wgpu::CompareFunction::Always
                        } else {
                            wgpu::CompareFunction::Less
                        }),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(fs),
                        compilation_options: Default::default(),
                        targets: &[Some(wgpu::ColorTargetState {
                            format: wgpu::TextureFormat::Rgba16Float,
                            blend: None,
                            write_mask: wgpu::ColorWrites::ALL,
                        })],
                    }),
                    multiview_mask: None,
                    cache: None,
                })
            };
        let shade = pipeline("vs", "fs", &buffers, false);
        let sky = pipeline("vs_sky", "fs_sky", &[], true);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("engine composite"),
            source: wgpu::ShaderSource::Wgsl(COMPOSITE_SHADER.into()),
        });
        let compute = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        Engine {
            rasteriser: Rasteriser::new(ctx),
            shade_layout,
            shade,
            sky,
            log_histogram: compute("log_histogram"),
            composite: compute("composite"),
        }
    }

    /// Renders `scene` (its camera's size) with `settings`: see the module docs.
    ///
    /// # Errors
    ///
    /// One line naming the stage: the shadow map cannot be fitted, the family refuses the
    /// variant or the sizes, the device cannot rasterise a projective frame's map, a
    /// readback fails.
    pub fn render(
        &self,
        ctx: &Context,
        scene: &Scene,
        bvh: &Bvh,
        settings: &EngineSettings,
    ) -> Result<EngineFrame, RasterError> {
        let device = ctx.device();
        let wait = || {
            device
                .poll(wgpu::PollType::wait_indefinitely())
                .map(|_| ())
                .map_err(|e| format!("poll: {e}"))
        };
        let mut times = Vec::new();
        let screen = [scene.camera.width, scene.camera.height];
        let family_name = settings.variant.family().name();
        // The cookie follows the scene: a family that reads none refuses a scene with one.
        let variant = match scene.light.cookie() {
            None => settings.variant,
            Some(_) => settings.variant.with_cookie(true).ok_or_else(|| {
                format!(
                    "the scene's spot light has a cookie, which the {family_name} family does \
                     not read"
                )
            })?,
        };

        // The family's passes first: a variant or size it refuses ends the frame before
        // anything is drawn.
        let t = Instant::now();
        let res = Resolutions {
            screen,
            rectified: settings.rectified,
        };
        let mut family = FamilyPasses::new(ctx, &variant, res, settings.shadow_map)
            .map_err(|e| format!("{family_name} {}: {e}", variant.id()))?;
        // The cookie the family's passes and the shading read (white 1 x 1 without one,
        // for the shading's binding).
        let (cookie_size, cookie_texels) = scene.light.cookie().map_or_else(
            || ([1, 1], vec![[1.0; 4]]),
            |c| ([c.width(), c.height()], c.rgba()),
        );
        let cookie = scatter_runtime::textures::upload_cookie(
            ctx,
            Kernel::Raymarch,
            cookie_size,
            &cookie_texels,
        )
        .map_err(|e| format!("cookie: {e}"))?
        .create_view(&wgpu::TextureViewDescriptor::default());
        if scene.light.cookie().is_some() {
            family
                .set_cookie(&cookie)
                .map_err(|e| format!("cookie: {e}"))?;
        }
        times.push((format!("{family_name} set-up (pipelines)"), t.elapsed()));

        let t = Instant::now();
        let raster = self
            .rasteriser
            .render(ctx, scene, bvh, settings.shadow_map)?;
        wait()?;
        times.push(("raster: camera depth + shadow map".to_owned(), t.elapsed()));

        let report = family
            .prepare(
                ctx,
                &FrameInput {
                    camera: scene.camera_desc(),
                    light: scene.light_desc(),
                    medium: scene.medium_desc(),
                    shadow_map: raster.shadow_frame.desc(),
                    settings: FrameSettings::for_screen(screen[0], screen[1]),
                },
            )
            .map_err(|e| format!("{family_name} prepare: {e}"))?;
        let rectified = match report.as_ref().and_then(|r| r.projective.as_ref()) {
            Some(maps) => {
                let t = Instant::now();
                let map = self
                    .rasteriser
                    .rectified(ctx, &raster, maps, settings.rectified)?;
                wait()?;
                times.push((
                    format!("raster: rectified map ({} regions)", maps.matrices.len()),
                    t.elapsed(),
                ));
                Some(map)
            }
            None => None,
        };

        let t = Instant::now();
        let depth_view = raster.depth.create_view(&Default::default());
        let shadow_view = raster.shadow_map.create_view(&Default::default());
        let rectified_view = rectified
            .as_ref()
            .map(|r| r.create_view(&Default::default()));
        let mut encoder = device.create_command_encoder(&Default::default());
        family
            .encode(
                ctx,
                &mut encoder,
                &Inputs {
                    depth: &depth_view,
                    shadow_map: Some(&shadow_view),
                    rectified: rectified_view.as_ref(),
                    vpl_maps: None,
                },
            )
            .map_err(|e| format!("{family_name} encode: {e}"))?;
        ctx.queue().submit([encoder.finish()]);
        wait()?;
        times.push((format!("{family_name} passes"), t.elapsed()));

        let t = Instant::now();
        let shaded = self.shade(ctx, scene, &raster, &cookie, screen);
        wait()?;
        times.push(("shade".to_owned(), t.elapsed()));

        let exposure = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("engine exposure"),
            size: 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let composite = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("engine composite"),
            size: wgpu::Extent3d {
                width: screen[0],
                height: screen[1],
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let shaded_view = shaded.create_view(&Default::default());
        let shafts_view = family.output_texture().create_view(&Default::default());
        let image_view = composite.create_view(&Default::default());
        let bind = |pipeline: &wgpu::ComputePipeline, image: bool| {
            let mut entries = vec![
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&shaded_view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&shafts_view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: exposure.as_entire_binding(),
                },
            ];
            if image {
                entries.push(wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(&image_view),
                });
            }
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("engine composite"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            })
        };
        match settings.exposure {
            Some(e) => ctx.queue().write_buffer(&exposure, 0, &e.to_le_bytes()),
            None => {
                let t = Instant::now();
                let mut encoder = device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    pass.set_pipeline(&self.log_histogram);
                    pass.set_bind_group(0, &bind(&self.log_histogram, false), &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                }
                ctx.queue().submit([encoder.finish()]);
                wait()?;
                times.push(("exposure (histogram)".to_owned(), t.elapsed()));
            }
        }
        let t = Instant::now();
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.composite);
            pass.set_bind_group(0, &bind(&self.composite, true), &[]);
            pass.dispatch_workgroups(screen[0].div_ceil(8), screen[1].div_ceil(8), 1);
        }
        ctx.queue().submit([encoder.finish()]);
        wait()?;
        times.push(("composite".to_owned(), t.elapsed()));

        let t = Instant::now();
        let rgba = read_texture(ctx, &composite, 4)?;
        let image = rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        times.push(("readback".to_owned(), t.elapsed()));
        Ok(EngineFrame {
            raster,
            rectified,
            family,
            report,
            shaded,
            exposure,
            composite,
            image,
            times,
        })
    }

    /// The forward shading pass (sky, then the scene) into a new `Rgba16Float` texture.
    fn shade(
        &self,
        ctx: &Context,
        scene: &Scene,
        raster: &RasterFrame,
        cookie: &wgpu::TextureView,
        [w, h]: [u32; 2],
    ) -> wgpu::Texture {
        let device = ctx.device();
        let extent = wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        };
        let texture = |format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some("engine shade"),
                size: extent,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let shaded = texture(
            wgpu::TextureFormat::Rgba16Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let zbuffer = texture(
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("engine shade"),
            size: SHADE_UNIFORM_SIZE,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bytes = shade_uniform(scene, &raster.shadow_frame);
        debug_assert_eq!(bytes.len() as u64, SHADE_UNIFORM_SIZE);
        ctx.queue().write_buffer(&uniform, 0, &bytes);
        let vertices = shade_vertices(scene, &raster.soup);
        let vertex_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("engine shade vertices"),
            size: vertices.len() as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.queue().write_buffer(&vertex_buffer, 0, &vertices);
        let index_bytes: Vec<u8> = raster
            .soup
            .indices
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let index_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("engine shade indices"),
            size: index_bytes.len() as u64,
            usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.queue().write_buffer(&index_buffer, 0, &index_bytes);
        let shadow_view = raster.shadow_map.create_view(&Default::default());
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("engine shade"),
            layout: &self.shade_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&shadow_view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(cookie),
                },
            ],
        });
        let target_view = shaded.create_view(&Default::default());
        let z_view = zbuffer.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("engine shade"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(cleared_depth(&z_view)),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, &bind, &[]);
            pass.set_pipeline(&self.sky);
            pass.draw(0..3, 0..1);
            pass.set_pipeline(&self.shade);
            pass.set_vertex_buffer(0, vertex_buffer.slice(..));
            pass.set_index_buffer(index_buffer.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..raster.soup.indices.len() as u32, 0, 0..1);
        }
        ctx.queue().submit([encoder.finish()]);
        shaded
    }
}

/// A buffer's bytes, copied to a mappable one and read.
fn read_buffer(ctx: &Context, buffer: &wgpu::Buffer) -> Result<Vec<u8>, RasterError> {
    let staging = ctx.device().create_buffer(&wgpu::BufferDescriptor {
        label: Some("engine readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device().create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    ctx.queue().submit([encoder.finish()]);
    crate::raster::map_read(ctx, &staging)
}

/// The files [`write_outputs`] writes into a folder.
pub const OUTPUTS: [&str; 3] = ["engine.png", "shafts.png", "depth.png"];

/// Writes `engine.png` (the composite read back), `shafts.png` (the family's output alone,
/// with the composite's exposure, [`tonemap`]) and `depth.png` (the rasterised view depth,
/// log-scaled from `near` (white) to `far` (black)) into `dir`, each to a temporary name
/// and renamed; returns their paths.
///
/// # Errors
///
/// A readback or a write fails.
pub fn write_outputs(
    ctx: &Context,
    frame: &EngineFrame,
    scene: &Scene,
    dir: &std::path::Path,
) -> Result<Vec<std::path::PathBuf>, RasterError> {
    use scatter_reference::image::write_png_rgb8;
    let [w, h] = [scene.camera.width, scene.camera.height];
    let exposure = frame.exposure(ctx)?;
    let shafts: Vec<u8> = frame
        .read_shafts(ctx)?
        .iter()
        .flat_map(|c| tonemap([c[0], c[1], c[2]], exposure))
        .collect();
    let (near, far) = (scene.camera.near, scene.camera.far);
    let depth: Vec<u8> = crate::raster::read_r32float(ctx, &frame.raster.depth)?
        .iter()
        .flat_map(|z| {
            let x = 1.0 - (f64::from(*z) / near).max(1.0).ln() / (far / near).ln();
            [(srgb(x.clamp(0.0, 1.0) as f32) * 255.0 + 0.5) as u8; 3]
        })
        .collect();
    let mut written = Vec::new();
    for (name, pixels) in OUTPUTS.iter().zip([&frame.image, &shafts, &depth]) {
        let path = dir.join(name);
        write_png_rgb8(&path, w, h, pixels).map_err(|e| format!("{}: {e}", path.display()))?;
        written.push(path);
    }
    Ok(written)
}
