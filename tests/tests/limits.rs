//! Requests beyond the device's limits are refused before anything is created, with an
//! error naming the limit, the requested value and the device's value; zero sizes are
//! refused with an error naming the input, not a wgpu validation error.
//!
//! Two devices: the shared one at the adapter's limits (texture sizes beyond
//! `max_texture_dimension_2d`, the minmax tree, zero sizes), and one created on the same
//! adapter with lowered limits (`Context::from_device`), which reaches the limits a
//! software adapter is too generous to reach otherwise: `max_texture_array_layers`,
//! `max_storage_buffer_binding_size` and `max_buffer_size` (the filtered bases, the slice
//! table, a readback buffer, the partial-sum-tree sweep's leaves, the hybrid_volume
//! crossings),
//! `max_compute_workgroup_storage_size` (the sweep's per-sample arrays),
//! `max_uniform_buffer_binding_size` (the uniform blocks),
//! `max_compute_workgroups_per_dimension` (the scatter, raymarch and minmax dispatches).
//! Skips without a GPU, like every GPU test.

use scatter_conformance::gpu;
use scatter_runtime::textures::{read_rgba16float, upload_r32float};
use scatter_runtime::{
    Context, HybridVolume, Minmax, PartialSumTree, Prefiltered, Raymarch, RuntimeError, wgpu,
};
use scatter_shaderlib::Kernel;
use scatter_shaderlib::hybrid_volume::HybridVolumeVariant;
use scatter_shaderlib::minmax::MinmaxVariant;
use scatter_shaderlib::partial_sum_tree::PartialSumTreeVariant;
use scatter_shaderlib::prefiltered::{PrefilteredVariant, Resolutions};
use scatter_shaderlib::raymarch::RaymarchVariant;

/// Checks that `result` is a [`RuntimeError::LimitExceeded`] for `limit` with `value` and
/// the device's `max`, and that the message names all three.
fn assert_limit<T>(name: &str, result: Result<T, RuntimeError>, limit: &str, value: u64, max: u64) {
    let Err(err) = result else {
        panic!("limits::{name}: accepted a request beyond {limit} = {max}");
    };
    let text = err.to_string();
    assert!(
        matches!(&err, RuntimeError::LimitExceeded { limit: l, value: v, max: m, .. }
            if *l == limit && *v == value && *m == max),
        "limits::{name}: expected {limit} ({value} > {max}), got {text}"
    );
    for part in [limit.to_owned(), value.to_string(), max.to_string()] {
        assert!(
            text.contains(&part),
            "limits::{name}: {text:?} lacks {part:?}"
        );
    }
    assert!(!text.contains('\n'), "limits::{name}: {text:?}");
    eprintln!("ok   limits::{name}: {text}");
}

/// Checks that `result` is a [`RuntimeError::EmptyInput`] whose message contains `size`.
fn assert_empty<T>(name: &str, result: Result<T, RuntimeError>, size: &str) {
    let Err(err) = result else {
        panic!("limits::{name}: accepted an empty {size}");
    };
    let text = err.to_string();
    assert!(
        matches!(err, RuntimeError::EmptyInput { .. }) && text.contains(size),
        "limits::{name}: expected an empty-input error naming {size:?}, got {text}"
    );
    eprintln!("ok   limits::{name}: {text}");
}

fn res(screen: [u32; 2], rectified: [u32; 2]) -> Resolutions {
    Resolutions { screen, rectified }
}

#[test]
fn texture_sizes_beyond_the_device_are_refused() {
    let Some(ctx) = gpu() else { return };
    let max = ctx.device().limits().max_texture_dimension_2d;
    let (over, m) = (u64::from(max) + 1, u64::from(max));
    let limit = "max_texture_dimension_2d";
    let v = PrefilteredVariant::default();
    assert_limit(
        "scatter_rectified_width",
        Prefiltered::new(ctx, &v, res([64, 36], [max + 1, 64]), 64),
        limit,
        over,
        m,
    );
    assert_limit(
        "scatter_rectified_height",
        Prefiltered::new(ctx, &v, res([64, 36], [64, max + 1]), 64),
        limit,
        over,
        m,
    );
    assert_limit(
        "scatter_screen_width",
        Prefiltered::new(ctx, &v, res([max + 1, 36], [64, 64]), 64),
        limit,
        over,
        m,
    );
    assert_limit(
        "scatter_screen_height",
        Prefiltered::new(ctx, &v, res([64, max + 1], [64, 64]), 64),
        limit,
        over,
        m,
    );
    assert_limit(
        "scatter_shadow_map",
        Prefiltered::new(ctx, &v, res([64, 36], [64, 64]), max + 1),
        limit,
        over,
        m,
    );
    let r = RaymarchVariant::default();
    assert_limit(
        "raymarch_screen_width",
        Raymarch::new(ctx, &r, [max + 1, 8], 64),
        limit,
        over,
        m,
    );
    assert_limit(
        "raymarch_shadow_map",
        Raymarch::new(ctx, &r, [8, 8], max + 1),
        limit,
        over,
        m,
    );
    let mm = MinmaxVariant::default();
    assert_limit(
        "minmax_screen_height",
        Minmax::new(ctx, &mm, res([8, max + 1], [64, 64]), 64),
        limit,
        over,
        m,
    );
    // A rectified row the device can hold whose min-max tree (every level side by side)
    // it cannot.
    let tree = u64::from(scatter_shaderlib::minmax::tree_width(max));
    assert_limit(
        "minmax_tree_width",
        Minmax::new(ctx, &mm, res([8, 8], [max, 8]), 64),
        limit,
        tree,
        m,
    );
    // Sizes near u32::MAX: refused by the same check, no overflow on the way.
    assert_limit(
        "minmax_rectified_u32_max",
        Minmax::new(ctx, &mm, res([8, 8], [u32::MAX, 8]), 64),
        limit,
        u64::from(u32::MAX),
        m,
    );
    let data = vec![0.0f32; max as usize + 1];
    assert_limit(
        "upload_r32float_width",
        upload_r32float(ctx, Kernel::Rectify, "too wide", [max + 1, 1], &data),
        limit,
        over,
        m,
    );
}

#[test]
fn zero_sizes_are_refused_with_the_input_named() {
    let Some(ctx) = gpu() else { return };
    let v = PrefilteredVariant::default();
    assert_empty(
        "scatter_screen",
        Prefiltered::new(ctx, &v, res([0, 36], [64, 64]), 64),
        "screen 0x36",
    );
    assert_empty(
        "scatter_rectified",
        Prefiltered::new(ctx, &v, res([64, 36], [64, 0]), 64),
        "rectified 64x0",
    );
    assert_empty(
        "scatter_shadow_map",
        Prefiltered::new(ctx, &v, res([64, 36], [64, 64]), 0),
        "shadow map 0x0",
    );
    assert_empty(
        "raymarch_screen",
        Raymarch::new(ctx, &RaymarchVariant::default(), [8, 0], 64),
        "screen 8x0",
    );
    assert_empty(
        "minmax_rectified",
        Minmax::new(ctx, &MinmaxVariant::default(), res([8, 8], [0, 8]), 64),
        "rectified 0x8",
    );
    assert_empty(
        "hybrid_volume_rectified",
        HybridVolume::new(
            ctx,
            &HybridVolumeVariant::default(),
            res([8, 8], [0, 8]),
            64,
        ),
        "rectified 0x8",
    );
    assert_empty(
        "upload_r32float",
        upload_r32float(ctx, Kernel::Rectify, "depth", [0, 4], &[]),
        "depth 0x4",
    );
}

/// A device on the shared context's adapter with `lower` applied to its limits.
fn lowered(ctx: &Context, lower: impl FnOnce(&mut wgpu::Limits)) -> Context {
    let adapter = ctx.adapter().clone();
    let mut limits = ctx.device().limits();
    lower(&mut limits);
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("scatter limits test (lowered limits)"),
        required_features: ctx.device().features(),
        required_limits: limits,
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    }))
    .unwrap_or_else(|e| panic!("a device with lowered limits: {e}"));
    Context::from_device(adapter, device, queue)
}

#[test]
fn lowered_device_limits_are_named() {
    let Some(shared) = gpu() else { return };
    let ctx = lowered(shared, |l| {
        l.max_texture_dimension_2d = 256;
        l.max_texture_array_layers = 4;
        l.max_storage_buffer_binding_size = 1024;
        l.max_compute_workgroups_per_dimension = 16;
    });
    let ctx = &ctx;
    // 32 bases are 8 rgba8unorm layers of filtered bases, 4 bytes per layer and texel:
    // 64 x 16 texels take 32 KiB of storage buffer.
    let v32 = PrefilteredVariant::default();
    assert_limit(
        "scatter_filtered_bytes",
        Prefiltered::new(ctx, &v32, res([64, 36], [64, 16]), 64),
        "max_storage_buffer_binding_size",
        64 * 16 * 8 * 4,
        1024,
    );
    let v16 = PrefilteredVariant {
        bases: 16,
        ..PrefilteredVariant::default()
    };
    // 65 rows of 16 bytes in the slice table.
    assert_limit(
        "scatter_slice_table",
        Prefiltered::new(ctx, &v16, res([64, 36], [64, 65]), 64),
        "max_storage_buffer_binding_size",
        65 * 16,
        1024,
    );
    assert_limit(
        "minmax_slice_table",
        Minmax::new(ctx, &MinmaxVariant::default(), res([64, 36], [64, 65]), 64),
        "max_storage_buffer_binding_size",
        65 * 16,
        1024,
    );
    // The sweep's leaves: 512 slices x 64 columns x 16 bytes.
    assert_limit(
        "partial_sum_tree_leaves",
        PartialSumTree::new(
            ctx,
            &PartialSumTreeVariant::default(),
            res([64, 36], [64, 16]),
            64,
        ),
        "max_storage_buffer_binding_size",
        512 * 64 * 16,
        1024,
    );
    // The crossings: 256 bins x 16 rows x 8 bytes.
    assert_limit(
        "hybrid_volume_crossings",
        HybridVolume::new(
            ctx,
            &HybridVolumeVariant::default(),
            res([64, 36], [64, 16]),
            64,
        ),
        "max_storage_buffer_binding_size",
        256 * 16 * 8,
        1024,
    );
    // 256 pixels wide in 8x8 workgroups: 32 workgroups along x (a 16 x 4 rectified map,
    // whose filtered bases, 4 layers of 4 bytes per texel, fit in 1024 bytes).
    assert_limit(
        "scatter_workgroups",
        Prefiltered::new(ctx, &v16, res([256, 8], [16, 4]), 64),
        "max_compute_workgroups_per_dimension",
        32,
        16,
    );
    assert_limit(
        "raymarch_workgroups",
        Raymarch::new(ctx, &RaymarchVariant::default(), [8, 256], 64),
        "max_compute_workgroups_per_dimension",
        32,
        16,
    );
    assert_limit(
        "minmax_workgroups",
        Minmax::new(ctx, &MinmaxVariant::default(), res([256, 8], [64, 16]), 64),
        "max_compute_workgroups_per_dimension",
        32,
        16,
    );

    // The sweep keeps seven 4-byte values per sample of a slice in workgroup memory: 512
    // samples need 14340 bytes.
    let small = lowered(shared, |l| l.max_compute_workgroup_storage_size = 8192);
    assert_limit(
        "partial_sum_tree_workgroup_memory",
        PartialSumTree::new(
            &small,
            &PartialSumTreeVariant {
                slice_samples: 512,
                ..PartialSumTreeVariant::default()
            },
            res([64, 36], [64, 16]),
            64,
        ),
        "max_compute_workgroup_storage_size",
        28 * 512 + 4,
        8192,
    );

    // A device whose buffers are smaller than its bindings (the slice table, a readback
    // buffer of 8x8 rgba16float, rows padded to 256 bytes: 2048 bytes) and whose uniform
    // bindings are smaller than the uniform blocks (432 bytes of `Frame`, 240 of `RaymarchFrame`).
    let ctx = lowered(shared, |l| {
        l.max_buffer_size = 1024;
        l.max_uniform_buffer_binding_size = 128;
    });
    let ctx = &ctx;
    assert_limit(
        "scatter_uniform_block",
        Prefiltered::new(ctx, &v16, res([64, 36], [64, 16]), 64),
        "max_uniform_buffer_binding_size",
        432,
        128,
    );
    assert_limit(
        "minmax_uniform_block",
        Minmax::new(ctx, &MinmaxVariant::default(), res([64, 36], [64, 16]), 64),
        "max_uniform_buffer_binding_size",
        432,
        128,
    );
    assert_limit(
        "raymarch_uniform_block",
        Raymarch::new(ctx, &RaymarchVariant::default(), [64, 36], 64),
        "max_uniform_buffer_binding_size",
        240,
        128,
    );
    assert_limit(
        "scatter_slice_table_buffer",
        Prefiltered::new(ctx, &v16, res([64, 36], [64, 65]), 64),
        "max_buffer_size",
        65 * 16,
        1024,
    );
    let texture = ctx.device().create_texture(&wgpu::TextureDescriptor {
        label: Some("limits readback"),
        size: wgpu::Extent3d {
            width: 8,
            height: 8,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    assert_limit(
        "readback_buffer",
        read_rgba16float(ctx, Kernel::Scatter, &texture),
        "max_buffer_size",
        2048,
        1024,
    );
}

/// The foreign engine (examples/foreign_engine) checks the sizes its formulas compute
/// against the device before creating a resource, naming the limit.
#[test]
fn foreign_engine_names_the_limit() {
    use scatter_foreign_engine::prefiltered::Sizes;
    use scatter_foreign_engine::{Engine, EngineError, Target};
    use scatter_gen::{FamilyVariant, Request, generate, output};

    let Some(shared) = gpu() else { return };
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("limits_foreign_engine");
    let _ = std::fs::remove_dir_all(&dir);
    let variant = PrefilteredVariant::default();
    let generated = generate(&Request {
        variants: vec![FamilyVariant::Prefiltered(variant)],
        targets: vec![scatter_gen::Target::Wgsl],
    })
    .unwrap_or_else(|e| panic!("scatter-gen: {e}"));
    output::write(&dir, &generated, false).unwrap_or_else(|e| panic!("scatter-gen: {e}"));
    let ctx = lowered(shared, |l| {
        l.max_texture_dimension_2d = 256;
        l.max_storage_buffer_binding_size = 1024;
    });
    let load = |sizes: Sizes| {
        Engine::load(
            ctx.device(),
            ctx.queue(),
            &dir,
            &variant.id(),
            Target::Wgsl,
            &sizes.params(),
        )
    };
    let cases = [
        // A parameter beyond its manifest constraint.
        (
            "screen_width",
            Sizes {
                screen: [257, 8],
                rectified: [64, 16],
                shadow_map: 64,
            },
            "max_texture_dimension_2d = 256",
        ),
        // A buffer whose formula (16 bytes per rectified row) exceeds the binding limit.
        (
            "slice_table",
            Sizes {
                screen: [64, 8],
                rectified: [64, 65],
                shadow_map: 64,
            },
            "max_storage_buffer_binding_size = 1024",
        ),
    ];
    for (name, sizes, expected) in cases {
        let err = load(sizes).expect_err(name);
        let text = err.to_string();
        assert!(
            matches!(err, EngineError::Constraint { .. }) && text.contains(expected),
            "limits::foreign_engine::{name}: {text}"
        );
        eprintln!("ok   limits::foreign_engine::{name}: {text}");
    }
}
