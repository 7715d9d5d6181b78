//! Throwaway: texture vs buffer stores/loads on this adapter.
use scatter_runtime::{Context, wgpu};
use std::time::Instant;

const S: u32 = 1024;
const HEAD: &str = "
@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var dtex: texture_storage_2d<r32float, write>;
@group(0) @binding(2) var darr: texture_storage_2d_array<rgba8unorm, write>;
@group(0) @binding(3) var<storage, read_write> buf: array<u32>;
@group(0) @binding(4) var sarr: texture_2d_array<f32>;
@group(0) @binding(5) var<storage, read> rbuf: array<u32>;
@group(0) @binding(6) var darr32: texture_storage_2d_array<rgba32float, write>;
@group(0) @binding(7) var<storage, read_write> buf4: array<vec4<f32>>;
";

fn main() {
    let ctx = Context::new().unwrap();
    let device = ctx.device();
    let mk = |format, layers, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: S,
                height: S,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let src = mk(
        wgpu::TextureFormat::R32Float,
        1,
        wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let dtex = mk(
        wgpu::TextureFormat::R32Float,
        1,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    let darr = mk(
        wgpu::TextureFormat::Rgba8Unorm,
        8,
        wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let darr32 = mk(
        wgpu::TextureFormat::Rgba32Float,
        2,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    let buf = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (S * S * 8 * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let rbuf = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (S * S * 8 * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let buf4 = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (S * S * 2 * 16) as u64,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let v = |t: &wgpu::Texture, arr: bool| {
        t.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(if arr {
                wgpu::TextureViewDimension::D2Array
            } else {
                wgpu::TextureViewDimension::D2
            }),
            ..Default::default()
        })
    };
    let views = [
        v(&src, false),
        v(&dtex, false),
        v(&darr, true),
        v(&darr, true),
        v(&darr32, true),
    ];
    let probes: Vec<(&str, Vec<u32>, String)> = vec![
        ("tex r32 store (4B)", vec![0, 1], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { textureStore(dtex, id.xy, textureLoad(src, id.xy, 0)); }".into()),
        ("buf u32 store (4B)", vec![0, 3], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { buf[id.y * 1024u + id.x] = bitcast<u32>(textureLoad(src, id.xy, 0).x); }".into()),
        ("tex 8 x rgba8 array store (32B)", vec![0, 2], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { let x = textureLoad(src, id.xy, 0).x; for (var l = 0u; l < 8u; l++) { textureStore(darr, id.xy, l, vec4<f32>(x, x * 0.5, x * 0.25, f32(l) * 0.1)); } }".into()),
        ("buf 8 x pack4x8unorm store (32B), layer-major", vec![0, 3], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { let x = textureLoad(src, id.xy, 0).x; for (var l = 0u; l < 8u; l++) { buf[(l * 1024u + id.y) * 1024u + id.x] = pack4x8unorm(vec4<f32>(x, x * 0.5, x * 0.25, f32(l) * 0.1)); } }".into()),
        ("buf 8 x pack4x8unorm store (32B), texel-major", vec![0, 3], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { let x = textureLoad(src, id.xy, 0).x; let base = (id.y * 1024u + id.x) * 8u; for (var l = 0u; l < 8u; l++) { buf[base + l] = pack4x8unorm(vec4<f32>(x, x * 0.5, x * 0.25, f32(l) * 0.1)); } }".into()),
        ("tex 2 x rgba32f array store (32B)", vec![0, 6], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { let x = textureLoad(src, id.xy, 0).x; for (var l = 0u; l < 2u; l++) { textureStore(darr32, id.xy, l, vec4<f32>(x, x * 0.5, x * 0.25, f32(l) * 0.1)); } }".into()),
        ("buf 2 x vec4f store (32B)", vec![0, 7], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { let x = textureLoad(src, id.xy, 0).x; let base = (id.y * 1024u + id.x) * 2u; for (var l = 0u; l < 2u; l++) { buf4[base + l] = vec4<f32>(x, x * 0.5, x * 0.25, f32(l) * 0.1); } }".into()),
        ("tex 16 rgba8 array loads (scattered cols)", vec![4, 1], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { var s = vec4<f32>(0.0); for (var l = 0u; l < 8u; l++) { let c = (id.x + 61u * l) % 1024u; s += textureLoad(sarr, vec2<u32>(c, id.y), l, 0) + textureLoad(sarr, vec2<u32>(c + 1u, id.y), l, 0); } textureStore(dtex, id.xy, s); }".into()),
        ("buf 16 u32 loads + unpack (scattered cols)", vec![5, 1], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { var s = vec4<f32>(0.0); for (var l = 0u; l < 8u; l++) { let c = (id.x + 61u * l) % 1024u; let b = (id.y * 1024u + c) * 8u + l; s += unpack4x8unorm(rbuf[b]) + unpack4x8unorm(rbuf[b + 8u]); } textureStore(dtex, id.xy, s); }".into()),
        ("empty (store 1 r32)", vec![1], "@compute @workgroup_size(8,8,1) fn main(@builtin(global_invocation_id) id: vec3<u32>) { textureStore(dtex, id.xy, vec4<f32>(f32(id.x))); }".into()),
    ];
    for (name, binds, body) in probes {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: None,
            source: wgpu::ShaderSource::Wgsl(format!("{HEAD}{body}").into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: None,
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let entries: Vec<_> = binds
            .iter()
            .map(|&b| wgpu::BindGroupEntry {
                binding: b,
                resource: match b {
                    0 => wgpu::BindingResource::TextureView(&views[0]),
                    1 => wgpu::BindingResource::TextureView(&views[1]),
                    2 => wgpu::BindingResource::TextureView(&views[2]),
                    3 => buf.as_entire_binding(),
                    4 => wgpu::BindingResource::TextureView(&views[3]),
                    5 => rbuf.as_entire_binding(),
                    6 => wgpu::BindingResource::TextureView(&views[4]),
                    _ => buf4.as_entire_binding(),
                },
            })
            .collect();
        let bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut t = Vec::new();
        for f in 0..8 {
            let mut enc = device.create_command_encoder(&Default::default());
            {
                let mut p = enc.begin_compute_pass(&Default::default());
                p.set_pipeline(&pipeline);
                p.set_bind_group(0, &bg, &[]);
                p.dispatch_workgroups(S / 8, S / 8, 1);
            }
            let st = Instant::now();
            ctx.queue().submit([enc.finish()]);
            device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
            if f > 0 {
                t.push(st.elapsed().as_secs_f64() * 1e3);
            }
        }
        t.sort_by(f64::total_cmp);
        println!(
            "{name:50} median {:7.2} ms  min {:7.2}",
            t[t.len() / 2],
            t[0]
        );
    }
}
