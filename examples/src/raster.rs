//! A small rasterising engine (issue 18): the scene tessellated into triangles and drawn with
//! wgpu render pipelines into the inputs scatter's kernels take, the camera's linear view
//! depth and the light's standard shadow map, in the conventions of
//! `scatter_reference::buffers` (which ray-casts the same buffers). The textures stay on the
//! GPU: `scatter-runtime`'s passes read them as they are.
//!
//! Both passes draw every triangle (no culling: the reference hits both sides) with a
//! `Depth32Float` depth test (`Less`, cleared to 1) and write an `R32Float` colour target:
//! - camera: clip = (x / (t a), y / t, far (z - near) / (far - near), z) in the camera's
//!   frame (right, up, forward; `t = tan(fov_y / 2)`, `a` the aspect), the standard wgpu
//!   depth of [`scatter_reference::buffers::ndc_depth`]; the target holds the linear view
//!   depth `z`, cleared to `far` (sky);
//! - light: the map [`ShadowMap::fit`] places (orthographic window or perspective cone,
//!   `u = (x + 1) / 2`, `v = (1 - y) / 2`); the target holds the normalised linear light depth
//!   `(z - near) / (far - near)` clamped to [0, 1], cleared to 1 (no occluder).
//!
//! The rasteriser samples pixel and texel centres, as the ray caster does; they differ at
//! silhouettes (a centre on either side of an edge) and by the tessellation of curved
//! shapes (chords inside a sphere or cylinder: `r (1 - cos(pi / segments))`).

use std::sync::mpsc;

use glam::DVec3;
use scatter_reference::buffers::{ShadowMap, ShadowProjection};
use scatter_reference::bvh::Bvh;
use scatter_reference::scene::{Scene, Shape};
use scatter_runtime::Context;
use scatter_runtime::shaderlib::prefiltered::ProjectiveMaps;
use scatter_runtime::wgpu;

/// Segments around a sphere or cylinder: chords 1.2e-4 of the radius inside it at 200.
pub const SEGMENTS: u32 = 200;

/// Cells per side of the grid a plane is drawn as.
pub const PLANE_CELLS: u32 = 64;

/// A triangle soup, with what shading needs per vertex.
#[derive(Clone, Debug, Default)]
pub struct Triangles {
    /// Vertex positions (world).
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals (world), one per position: the face's for planes, boxes, meshes
    /// and heightfields (flat: their vertices are not shared between faces), the surface's
    /// for spheres and cylinder sides. Their sign is arbitrary (surfaces are two-sided).
    pub normals: Vec<[f32; 3]>,
    /// Index of the vertex's shape in `Scene::geometry`, one per position.
    pub shapes: Vec<u32>,
    /// Three indices per triangle.
    pub indices: Vec<u32>,
}

impl Triangles {
    fn vertex(&mut self, p: DVec3, n: DVec3, shape: u32) -> u32 {
        let i = self.positions.len() as u32;
        let f = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        self.positions.push(f(p));
        self.normals.push(f(n.normalize_or_zero()));
        self.shapes.push(shape);
        i
    }

    fn triangle(&mut self, a: u32, b: u32, c: u32) {
        self.indices.extend([a, b, c]);
    }

    /// A flat triangle with its own three vertices.
    fn flat(&mut self, [a, b, c]: [DVec3; 3], shape: u32) {
        let n = (b - a).cross(c - a);
        let i = [a, b, c].map(|p| self.vertex(p, n, shape));
        self.triangle(i[0], i[1], i[2]);
    }

    fn quad(&mut self, a: DVec3, b: DVec3, c: DVec3, d: DVec3, shape: u32) {
        let n = (c - a).cross(d - b);
        let i = [a, b, c, d].map(|p| self.vertex(p, n, shape));
        self.triangle(i[0], i[1], i[2]);
        self.triangle(i[0], i[2], i[3]);
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.indices.len() / 3
    }

    /// No triangles.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }
}

/// Two unit vectors perpendicular to `n` and to each other.
fn tangents(n: DVec3) -> (DVec3, DVec3) {
    let helper = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let t1 = n.cross(helper).normalize();
    (t1, n.cross(t1))
}

/// The scene as triangles: planes as one quad `half_extent` wide each way around the point
/// nearest the camera, spheres and cylinders with `segments` around, heightfields split
/// as the reference splits them, meshes as they are.
pub fn tessellate(scene: &Scene, segments: u32, half_extent: f64) -> Triangles {
    let mut t = Triangles::default();
    let seg = segments.max(3);
    for (index, shape) in scene.geometry.iter().enumerate() {
        let id = index as u32;
        match shape {
            Shape::Plane { point, normal, .. } => {
                let n = normal.normalize();
                let centre = scene.camera.position - n * n.dot(scene.camera.position - *point);
                // A grid of PLANE_CELLS^2 quads, not one quad: a triangle that reaches behind
                // a perspective map's centre (w < 0) is not clipped there once depth clamping
                // turns near clipping off, and rasterisers differ on it; small cells keep
                // such triangles out of the cone.
                let (t1, t2) = tangents(n);
                let f = |k: u32| (2.0 * f64::from(k) / f64::from(PLANE_CELLS) - 1.0) * half_extent;
                let at = |i: u32, j: u32| centre + t1 * f(i) + t2 * f(j);
                for i in 0..PLANE_CELLS {
                    for j in 0..PLANE_CELLS {
                        t.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), id);
                    }
                }
            }
            Shape::Box { min, max, .. } => {
                let c = |x: bool, y: bool, z: bool| {
                    DVec3::new(
                        if x { max.x } else { min.x },
                        if y { max.y } else { min.y },
                        if z { max.z } else { min.z },
                    )
                };
                for axis in 0..3 {
                    for side in [false, true] {
                        let corner = |u: bool, v: bool| match axis {
                            0 => c(side, u, v),
                            1 => c(u, side, v),
                            _ => c(u, v, side),
                        };
                        t.quad(
                            corner(false, false),
                            corner(true, false),
                            corner(true, true),
                            corner(false, true),
                            id,
                        );
                    }
                }
            }
            Shape::Sphere { center, radius, .. } => {
                let rings = seg / 2;
                let base = t.positions.len() as u32;
                for i in 0..=rings {
                    let theta = std::f64::consts::PI * f64::from(i) / f64::from(rings);
                    for j in 0..seg {
                        let phi = std::f64::consts::TAU * f64::from(j) / f64::from(seg);
                        let d = DVec3::new(
                            theta.sin() * phi.cos(),
                            theta.cos(),
                            theta.sin() * phi.sin(),
                        );
                        t.vertex(*center + d * *radius, d, id);
                    }
                }
                let at = |i: u32, j: u32| base + i * seg + j % seg;
                for i in 0..rings {
                    for j in 0..seg {
                        t.triangle(at(i, j), at(i + 1, j), at(i + 1, j + 1));
                        t.triangle(at(i, j), at(i + 1, j + 1), at(i, j + 1));
                    }
                }
            }
            Shape::Cylinder { a, b, radius, .. } => {
                let axis = (*b - *a).normalize();
                let (t1, t2) = tangents(axis);
                let ring = |k: u32| {
                    let phi = std::f64::consts::TAU * f64::from(k) / f64::from(seg);
                    (t1 * phi.cos() + t2 * phi.sin()) * *radius
                };
                // The side's ring vertices carry radial normals; the caps have their own
                // (same positions, axial normals).
                let (ca, cb) = (t.vertex(*a, -axis, id), t.vertex(*b, axis, id));
                let base = t.positions.len() as u32;
                for k in 0..seg {
                    let r = ring(k);
                    t.vertex(*a + r, r, id);
                    t.vertex(*b + r, r, id);
                    t.vertex(*a + r, -axis, id);
                    t.vertex(*b + r, axis, id);
                }
                for k in 0..seg {
                    let (i, j) = (base + 4 * k, base + 4 * ((k + 1) % seg));
                    t.triangle(i, i + 1, j + 1);
                    t.triangle(i, j + 1, j);
                    t.triangle(ca, i + 2, j + 2);
                    t.triangle(cb, j + 3, i + 3);
                }
            }
            Shape::Heightfield {
                origin,
                size,
                samples,
                heights,
                ..
            } => {
                let (nx, nz) = (samples[0], samples[1]);
                let at = |ix: u32, iz: u32| {
                    *origin
                        + DVec3::new(
                            size[0] * f64::from(ix) / f64::from(nx - 1),
                            heights[(iz * nx + ix) as usize],
                            size[1] * f64::from(iz) / f64::from(nz - 1),
                        )
                };
                for iz in 0..nz - 1 {
                    for ix in 0..nx - 1 {
                        let (a, b, c, d) = (
                            at(ix, iz),
                            at(ix + 1, iz),
                            at(ix, iz + 1),
                            at(ix + 1, iz + 1),
                        );
                        t.flat([a, c, b], id);
                        t.flat([b, c, d], id);
                    }
                }
            }
            Shape::Mesh {
                vertices,
                triangles,
                ..
            } => {
                for tri in triangles {
                    t.flat(tri.map(|k| vertices[k as usize]), id);
                }
            }
        }
    }
    t
}

const SHADER: &str = r"
struct View {
    origin: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    forward: vec4<f32>,
    // perspective: 1 / (t a), 1 / t; orthographic: x0, x1, y0, y1
    window: vec4<f32>,
    // near, far, 1 = perspective, 1 = write normalised depth
    range: vec4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;

struct Out {
    @builtin(position) clip: vec4<f32>,
    @location(0) z: f32,
}

@vertex
fn vs(@location(0) p: vec3<f32>) -> Out {
    let q = p - view.origin.xyz;
    let x = dot(q, view.right.xyz);
    let y = dot(q, view.up.xyz);
    let z = dot(q, view.forward.xyz);
    let near = view.range.x;
    let far = view.range.y;
    var out: Out;
    if view.range.z > 0.5 {
        out.clip = vec4<f32>(x * view.window.x, y * view.window.y, far * (z - near) / (far - near), z);
    } else {
        let w = view.window;
        out.clip = vec4<f32>(
            2.0 * (x - w.x) / (w.y - w.x) - 1.0,
            2.0 * (y - w.z) / (w.w - w.z) - 1.0,
            (z - near) / (far - near),
            1.0,
        );
    }
    out.z = z;
    return out;
}

@fragment
fn fs(in: Out) -> @location(0) vec4<f32> {
    if view.range.w > 0.5 {
        let d = clamp((in.z - view.range.x) / (view.range.y - view.range.x), 0.0, 1.0);
        return vec4<f32>(d, 0.0, 0.0, 0.0);
    }
    return vec4<f32>(in.z, 0.0, 0.0, 0.0);
}
";

/// What a pass draws from: the frame, the projection, the depth range, the output.
#[derive(Clone, Copy, Debug)]
struct ViewUniform {
    origin: DVec3,
    basis: [DVec3; 3],
    window: [f64; 4],
    near: f64,
    far: f64,
    perspective: bool,
    normalised: bool,
}

impl ViewUniform {
    fn bytes(&self) -> Vec<u8> {
        let v = |d: DVec3| [d.x as f32, d.y as f32, d.z as f32, 0.0];
        let rows: [[f32; 4]; 6] = [
            v(self.origin),
            v(self.basis[0]),
            v(self.basis[1]),
            v(self.basis[2]),
            self.window.map(|w| w as f32),
            [
                self.near as f32,
                self.far as f32,
                f32::from(u8::from(self.perspective)),
                f32::from(u8::from(self.normalised)),
            ],
        ];
        rows.iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect()
    }
}

/// The rasterised inputs of one frame.
#[derive(Debug)]
pub struct RasterFrame {
    /// Linear view depth, `R32Float`, screen-sized (the runtime's `depth` input).
    pub depth: wgpu::Texture,
    /// Normalised linear light depth, `R32Float`, `size x size` (the `shadow_map` input).
    pub shadow_map: wgpu::Texture,
    /// The map's frame (its `depth` is empty: the texels are on the GPU); `desc()` gives
    /// the runtime's shadow-map description.
    pub shadow_frame: ShadowMap,
    /// Triangles drawn.
    pub triangles: usize,
    /// The triangles on the CPU, clipped per region for the rectified map.
    pub soup: Triangles,
}

/// Smallest clip `w` kept by [`clip_w`], relative to the scene's scale (world units).
const W_MIN: f64 = 1e-6;

/// `soup`'s triangles clipped to `w >= W_MIN` under `m` (world to clip), as a vertex list
/// (three per triangle; a triangle cut by the plane becomes one or two).
fn clip_w(soup: &Triangles, m: &glam::DMat4) -> Vec<[f32; 3]> {
    let w_row = m.row(3);
    let w = |p: DVec3| w_row.dot(p.extend(1.0));
    let mut out = Vec::with_capacity(soup.indices.len());
    let p = |i: u32| {
        let v = soup.positions[i as usize];
        DVec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]))
    };
    let f32x3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
    for t in soup.indices.chunks_exact(3) {
        let corners = [p(t[0]), p(t[1]), p(t[2])];
        let ws = corners.map(w);
        if ws.iter().all(|x| *x >= W_MIN) {
            out.extend(corners.map(f32x3));
            continue;
        }
        if ws.iter().all(|x| *x < W_MIN) {
            continue;
        }
        // Sutherland-Hodgman against the one plane.
        let mut poly = Vec::with_capacity(4);
        for k in 0..3 {
            let (a, b) = (corners[k], corners[(k + 1) % 3]);
            let (wa, wb) = (ws[k], ws[(k + 1) % 3]);
            if wa >= W_MIN {
                poly.push(a);
            }
            if (wa >= W_MIN) != (wb >= W_MIN) {
                poly.push(a + (b - a) * ((W_MIN - wa) / (wb - wa)));
            }
        }
        for k in 1..poly.len().saturating_sub(1) {
            out.extend([poly[0], poly[k], poly[k + 1]].map(f32x3));
        }
    }
    out
}

/// The render pipelines: camera depth and shadow map (one pipeline, two uniforms) and, where
/// the device clamps depth, the projective rectified map.
#[derive(Debug)]
pub struct Rasteriser {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    /// `None` without `Features::DEPTH_CLIP_CONTROL`.
    rectified: Option<wgpu::RenderPipeline>,
}

const RECTIFIED_SHADER: &str = r"
@group(0) @binding(0) var<uniform> world_to_clip: mat4x4<f32>;

@vertex
fn vs(@location(0) p: vec3<f32>) -> @builtin(position) vec4<f32> {
    return world_to_clip * vec4<f32>(p, 1.0);
}

// Depth clamping is on: an occluder in front of the near plane stores 0.
@fragment
fn fs(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(clamp(position.z, 0.0, 1.0), 0.0, 0.0, 0.0);
}
";

/// The z-buffer attachment of every pass here: cleared to 1 (depth test `Less`), not kept.
pub(crate) fn cleared_depth(
    view: &wgpu::TextureView,
) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Discard,
        }),
        stencil_ops: None,
    }
}

/// Any failure of the rasteriser, as text naming the step.
pub type RasterError = String;

impl Rasteriser {
    /// Compiles the pipeline.
    pub fn new(ctx: &Context) -> Self {
        let device = ctx.device();
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raster"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raster view"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("raster"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = render_pipeline(device, &pipeline_layout, &module, false);
        let rectified = device
            .features()
            .contains(wgpu::Features::DEPTH_CLIP_CONTROL)
            .then(|| {
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("raster rectified"),
                    source: wgpu::ShaderSource::Wgsl(RECTIFIED_SHADER.into()),
                });
                render_pipeline(device, &pipeline_layout, &module, true)
            });
        Rasteriser {
            pipeline,
            layout,
            rectified,
        }
    }

    /// Tessellates `scene`, fits its light's map (`ShadowMap::fit`) and draws both passes
    /// into new textures (submitted; nothing read back).
    ///
    /// # Errors
    ///
    /// The map cannot be fitted (size, spot cone), or the scene has no triangles.
    pub fn render(
        &self,
        ctx: &Context,
        scene: &Scene,
        bvh: &Bvh,
        shadow_map_size: u32,
    ) -> Result<RasterFrame, RasterError> {
        let shadow_frame =
            ShadowMap::fit(scene, bvh, shadow_map_size).map_err(|e| format!("shadow map: {e}"))?;
        let cam = &scene.camera;
        let light_reach = (shadow_frame.origin - cam.position).length() + shadow_frame.far;
        let tris = tessellate(scene, SEGMENTS, 8.0 * cam.far.max(light_reach));
        if tris.is_empty() {
            return Err("the scene has no triangles to draw".into());
        }
        let frame = cam.frame();
        let t = cam.tan_half_fov();
        let camera = ViewUniform {
            origin: cam.position,
            basis: [frame.right, frame.up, frame.forward],
            window: [1.0 / (t * cam.aspect()), 1.0 / t, 0.0, 0.0],
            near: cam.near,
            far: cam.far,
            perspective: true,
            normalised: false,
        };
        let light = ViewUniform {
            origin: shadow_frame.origin,
            basis: shadow_frame.basis,
            window: match shadow_frame.projection {
                ShadowProjection::Orthographic { x0, x1, y0, y1 } => [x0, x1, y0, y1],
                ShadowProjection::Perspective { tan_half } => {
                    [1.0 / tan_half, 1.0 / tan_half, 0.0, 0.0]
                }
            },
            near: shadow_frame.near,
            far: shadow_frame.far,
            perspective: matches!(
                shadow_frame.projection,
                ShadowProjection::Perspective { .. }
            ),
            normalised: true,
        };
        let device = ctx.device();
        let vertices = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("raster vertices"),
            size: (tris.positions.len() * 12) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bytes: Vec<u8> = tris
            .positions
            .iter()
            .flatten()
            .flat_map(|f| f.to_le_bytes())
            .collect();
        ctx.queue().write_buffer(&vertices, 0, &bytes);
        let indices = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("raster indices"),
            size: (tris.indices.len() * 4) as u64,
            usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bytes: Vec<u8> = tris.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        ctx.queue().write_buffer(&indices, 0, &bytes);
        let mut encoder = device.create_command_encoder(&Default::default());
        let depth = self.pass(
            ctx,
            &mut encoder,
            &camera,
            [cam.width, cam.height],
            cam.far,
            (&vertices, &indices, tris.indices.len() as u32),
        );
        let shadow_map = self.pass(
            ctx,
            &mut encoder,
            &light,
            [shadow_map_size; 2],
            1.0,
            (&vertices, &indices, tris.indices.len() as u32),
        );
        ctx.queue().submit([encoder.finish()]);
        Ok(RasterFrame {
            depth,
            shadow_map,
            shadow_frame,
            triangles: tris.len(),
            soup: tris,
        })
    }

    /// The projective rectified map of a frame whose report carries `maps`
    /// (`FrameReport::projective`), `size` = the rectified map's: every triangle drawn once
    /// per region with `maps.matrices[r]` into the columns `maps.viewports[r]` of an
    /// `R32Float` target, depth test `Less`, cleared to 1, depth clamping on, no culling,
    /// clip `z / w` stored: the README's contract, to pass as `Inputs::rectified`.
    ///
    /// # Errors
    ///
    /// The device cannot clamp depth (`Features::DEPTH_CLIP_CONTROL`), a size is zero, or a
    /// viewport lies outside the map.
    pub fn rectified(
        &self,
        ctx: &Context,
        frame: &RasterFrame,
        maps: &ProjectiveMaps,
        [w, h]: [u32; 2],
    ) -> Result<wgpu::Texture, RasterError> {
        let pipeline = self.rectified.as_ref().ok_or(
            "the device cannot clamp depth (wgpu::Features::DEPTH_CLIP_CONTROL), which the \
             projective rectified map needs; use an epipolar variant",
        )?;
        if w == 0 || h == 0 {
            return Err(format!("rectified map {w}x{h}: sizes must be at least 1"));
        }
        if let Some([first, count]) = maps
            .viewports
            .iter()
            .find(|[first, count]| *count == 0 || first + count > w)
        {
            return Err(format!(
                "viewport of columns {first}..{} outside the {w}-column rectified map",
                first + count
            ));
        }
        let device = ctx.device();
        let extent = wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        };
        let (target, zbuffer) = targets(device, extent, "raster rectified");
        // Each region's triangles clipped to w >= W_MIN: with depth clamping on, near
        // clipping is off, and a triangle reaching behind the map's centre (w < 0) is
        // rasterised differently by different rasterisers (llvmpipe drew none of the ground
        // under spot_grate/grazing's lamp along a grid line); nothing there is in the map.
        let regions: Vec<(wgpu::Buffer, u32)> = maps
            .matrices
            .iter()
            .map(|m| {
                let clipped = clip_w(&frame.soup, m);
                let bytes: Vec<u8> = clipped
                    .iter()
                    .flatten()
                    .flat_map(|f| f.to_le_bytes())
                    .collect();
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("raster region triangles"),
                    size: (bytes.len() as u64).max(12),
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                ctx.queue().write_buffer(&buffer, 0, &bytes);
                (buffer, clipped.len() as u32)
            })
            .collect();
        let binds: Vec<wgpu::BindGroup> = maps
            .matrices
            .iter()
            .map(|m| {
                let uniform = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("raster region matrix"),
                    size: 64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let bytes: Vec<u8> = m
                    .to_cols_array()
                    .iter()
                    .flat_map(|x| (*x as f32).to_le_bytes())
                    .collect();
                ctx.queue().write_buffer(&uniform, 0, &bytes);
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("raster region matrix"),
                    layout: &self.layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 0,
                        resource: uniform.as_entire_binding(),
                    }],
                })
            })
            .collect();
        let target_view = target.create_view(&Default::default());
        let z_view = zbuffer.create_view(&Default::default());
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("raster rectified"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: 1.0,
                            g: 0.0,
                            b: 0.0,
                            a: 0.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(cleared_depth(&z_view)),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(pipeline);
            for ((bind, &[first, count]), (vertices, n)) in
                binds.iter().zip(&maps.viewports).zip(&regions)
            {
                if *n == 0 {
                    continue;
                }
                pass.set_viewport(first as f32, 0.0, count as f32, h as f32, 0.0, 1.0);
                pass.set_bind_group(0, bind, &[]);
                pass.set_vertex_buffer(0, vertices.slice(..));
                pass.draw(0..*n, 0..1);
            }
        }
        ctx.queue().submit([encoder.finish()]);
        Ok(target)
    }

    /// One render pass into a new `R32Float` texture cleared to `clear`.
    fn pass(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        view: &ViewUniform,
        [w, h]: [u32; 2],
        clear: f64,
        (vertices, indices, count): (&wgpu::Buffer, &wgpu::Buffer, u32),
    ) -> wgpu::Texture {
        let device = ctx.device();
        let extent = wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        };
        let (target, zbuffer) = targets(device, extent, "raster target");
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("raster view"),
            size: 96,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.queue().write_buffer(&uniform, 0, &view.bytes());
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("raster view"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            }],
        });
        let target_view = target.create_view(&Default::default());
        let z_view = zbuffer.create_view(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("raster"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: clear,
                            g: 0.0,
                            b: 0.0,
                            a: 0.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(cleared_depth(&z_view)),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..count, 0, 0..1);
        }
        target
    }
}

/// Reads an `R32Float` texture back (row-major from the top-left texel), for tests and
/// reports; the frame itself never needs it.
///
/// # Errors
///
/// The map or the poll fails.
pub fn read_r32float(ctx: &Context, texture: &wgpu::Texture) -> Result<Vec<f32>, RasterError> {
    Ok(read_texture(ctx, texture, 4)?
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// Reads a 2D texture of `bytes_per_texel` back: its texels' bytes, rows unpadded, from the
/// top-left texel.
///
/// # Errors
///
/// The map or the poll fails.
pub fn read_texture(
    ctx: &Context,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
) -> Result<Vec<u8>, RasterError> {
    let (w, h) = (texture.width(), texture.height());
    let row = (w * bytes_per_texel).div_ceil(256) * 256;
    let buffer = ctx.device().create_buffer(&wgpu::BufferDescriptor {
        label: Some("raster readback"),
        size: u64::from(row) * u64::from(h),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device().create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        texture.size(),
    );
    ctx.queue().submit([encoder.finish()]);
    let bytes = map_read(ctx, &buffer)?;
    let used = (w * bytes_per_texel) as usize;
    Ok(bytes
        .chunks_exact(row as usize)
        .flat_map(|r| r[..used].iter().copied())
        .collect())
}

/// Maps a `MAP_READ` buffer once the queue is done and copies its bytes out.
///
/// # Errors
///
/// The map or the poll fails.
pub fn map_read(ctx: &Context, buffer: &wgpu::Buffer) -> Result<Vec<u8>, RasterError> {
    let (sender, receiver) = mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = sender.send(r);
    });
    ctx.device()
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| format!("poll: {e}"))?;
    receiver
        .recv()
        .map_err(|e| format!("map callback: {e}"))?
        .map_err(|e| format!("map_async: {e}"))?;
    let bytes = buffer
        .get_mapped_range(..)
        .map_err(|e| format!("get_mapped_range: {e}"))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// A triangle-list pipeline drawing into `R32Float` with a `Depth32Float` test (`Less`), no
/// culling; `unclipped_depth` clamps depth instead of clipping (needs
/// `Features::DEPTH_CLIP_CONTROL`).
fn render_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    unclipped_depth: bool,
) -> wgpu::RenderPipeline {
    let attributes = [wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x3,
        offset: 0,
        shader_location: 0,
    }];
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("raster"),
        layout: Some(layout),

        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attributes,
            })],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            unclipped_depth,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: wgpu::TextureFormat::R32Float,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// An `R32Float` colour target (rendered, sampled, copied) and its `Depth32Float` z-buffer.
fn targets(
    device: &wgpu::Device,
    extent: wgpu::Extent3d,
    label: &str,
) -> (wgpu::Texture, wgpu::Texture) {
    let texture = |format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    (
        texture(
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        ),
        texture(
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        ),
    )
}
