//! Generator round trips: what `manifest.json` tells a foreign engine agrees with what
//! `scatter-runtime` really allocates and dispatches and with the host structs the runtime
//! uploads: texture formats and layers, the uniform block's size and every field offset,
//! the slice table's stride, and the dispatch formulas evaluated at real sizes against the
//! workgroup sizes of the kernels the runtime builds.

use scatter_gen::{FamilyVariant, Request, Target, generate};
use scatter_runtime::prefiltered::{DEPTH_FORMAT, OUTPUT_FORMAT};
use scatter_shaderlib::prefiltered::{
    FrameUniforms, LightKind, PrefilteredVariant, RECTIFY_TEXELS, Rectification, SliceParams,
    Storage, VisibilityMode, filtered_word_bytes,
};
use scatter_shaderlib::{KernelParams, build};
use serde_json::Value;

/// The manifest of one variant, parsed.
fn manifest(v: PrefilteredVariant) -> Value {
    let g = generate(&Request {
        variants: vec![FamilyVariant::Prefiltered(v)],
        targets: vec![Target::Wgsl],
    })
    .unwrap_or_else(|e| panic!("{}: {e}", v.id()));
    serde_json::from_slice(&g.manifest).unwrap_or_else(|e| panic!("manifest: {e}"))
}

fn wgpu_name(format: impl std::fmt::Debug) -> String {
    format!("{format:?}").to_lowercase()
}

fn get<'a>(v: &'a Value, key: &str) -> &'a Value {
    v.get(key)
        .unwrap_or_else(|| panic!("manifest lacks `{key}` in {v}"))
}

fn str_of<'a>(v: &'a Value, key: &str) -> &'a str {
    get(v, key)
        .as_str()
        .unwrap_or_else(|| panic!("`{key}` is not a string in {v}"))
}

fn resource<'a>(variant: &'a Value, name: &str) -> &'a Value {
    get(variant, "resources")
        .as_array()
        .and_then(|a| {
            a.iter()
                .find(|r| r.get("name").and_then(Value::as_str) == Some(name))
        })
        .unwrap_or_else(|| panic!("no resource `{name}`"))
}

/// Evaluates a manifest formula at the given sizes.
fn eval(formula: &str, sizes: &[(&str, u32)]) -> u32 {
    let f = formula.trim();
    if let Some(inner) = f.strip_prefix("ceil(").and_then(|s| s.strip_suffix(')')) {
        let (a, b) = inner
            .split_once(" / ")
            .unwrap_or_else(|| panic!("{formula}"));
        return eval(a, sizes).div_ceil(eval(b, sizes));
    }
    if let Some((a, b)) = f.split_once(" * ") {
        return eval(a, sizes) * eval(b, sizes);
    }
    f.parse().unwrap_or_else(|_| {
        sizes
            .iter()
            .find(|(n, _)| *n == f)
            .map(|(_, v)| *v)
            .unwrap_or_else(|| panic!("unknown symbol in formula {formula}"))
    })
}

/// Coarse filtered columns: `filtered` and `bounds` hold `rectified.width / k` columns, and the
/// manifest says so (the runtime sizes them from these formulas).
#[test]
fn manifest_sizes_coarse_filtered_columns() {
    for k in [2, 4, 8] {
        let v = PrefilteredVariant {
            filtered_stride: k,
            ..PrefilteredVariant::default()
        };
        let m = manifest(v);
        let variant = &get(&m, "variants")[0];
        let filtered = get(resource(variant, "filtered"), "buffer");
        assert_eq!(
            str_of(filtered, "size_bytes"),
            format!(
                "{} * {} * ceil(rectified.width / {k}) * rectified.height",
                filtered_word_bytes(v.storage),
                v.filtered_layers()
            ),
            "{}",
            v.id()
        );
        let bounds = get(resource(variant, "bounds"), "buffer");
        assert_eq!(
            str_of(bounds, "size_bytes"),
            format!("8 * ceil(rectified.width / {k}) * rectified.height"),
            "{}",
            v.id()
        );
    }
}

/// `resume`: `bounds` holds a second plane (the weight sums) and `scatter` and its fallback
/// (the passes that evaluate the integral) read the rectified map at binding 10, as the
/// manifest says.
#[test]
fn manifest_resume_sizes_bounds_and_binds_the_rectified_map() {
    for k in [2, 4, 8] {
        let v = PrefilteredVariant {
            filtered_stride: k,
            resume: true,
            sampling: scatter_shaderlib::sampling::Sampling::Epipolar,
            ..PrefilteredVariant::default()
        };
        let m = manifest(v);
        let variant = &get(&m, "variants")[0];
        let bounds = get(resource(variant, "bounds"), "buffer");
        assert_eq!(
            str_of(bounds, "size_bytes"),
            format!("8 * 2 * ceil(rectified.width / {k}) * rectified.height"),
            "{}",
            v.id()
        );
        let passes = get(variant, "passes")
            .as_array()
            .cloned()
            .unwrap_or_default();
        let reads_rectified = |kernel: &str| {
            passes
                .iter()
                .filter(|p| str_of(p, "kernel") == kernel)
                .flat_map(|p| get(p, "bindings").as_array().cloned().unwrap_or_default())
                .any(|b| {
                    get(&b, "binding").as_u64() == Some(10) && str_of(&b, "resource") == "rectified"
                })
        };
        for kernel in ["scatter", "scatter_fallback"] {
            assert!(reads_rectified(kernel), "{}: {kernel}", v.id());
        }
        assert!(!reads_rectified("prefilter"), "{}", v.id());
    }
}

#[test]
fn manifest_resources_match_the_runtime() {
    for (&storage, &rectification) in Storage::ALL.iter().zip(Rectification::ALL.iter().cycle()) {
        for &light in LightKind::SINGLE {
            let v = PrefilteredVariant {
                storage,
                light,
                rectification,
                bases: 64,
                ..PrefilteredVariant::default()
            };
            let m = manifest(v);
            let variant = &get(&m, "variants")[0];
            let tex = |name: &str| get(resource(variant, name), "texture").clone();
            // The runtime's buffer: one storage-format texel's bytes per layer and texel.
            let filtered = get(resource(variant, "filtered"), "buffer");
            assert_eq!(
                str_of(filtered, "size_bytes"),
                format!(
                    "{} * {} * rectified.width * rectified.height",
                    filtered_word_bytes(storage),
                    v.filtered_layers()
                ),
                "{}",
                v.id()
            );
            for name in ["depth", "shadow_map", "rectified"] {
                assert_eq!(
                    str_of(&tex(name), "format"),
                    wgpu_name(DEPTH_FORMAT),
                    "{name}"
                );
            }
            assert_eq!(str_of(&tex("output"), "format"), wgpu_name(OUTPUT_FORMAT));
            if rectification == Rectification::Projective {
                // The map the engine rasterises (checked by the runtime as DEPTH_FORMAT).
                assert_eq!(
                    str_of(&tex("rectified_raster"), "format"),
                    wgpu_name(DEPTH_FORMAT)
                );
            }
            let frame = get(resource(variant, "frame"), "buffer");
            assert_eq!(
                str_of(frame, "size_bytes"),
                size_of::<FrameUniforms>().to_string()
            );
            let slices = get(resource(variant, "slices"), "buffer");
            assert_eq!(
                str_of(slices, "size_bytes"),
                format!("{} * rectified.height", size_of::<SliceParams>())
            );
        }
    }
}

#[test]
fn manifest_frame_layout_matches_the_host_struct() {
    let m = manifest(PrefilteredVariant::default());
    let frame = get(&m, "structs")
        .as_array()
        .and_then(|a| {
            a.iter()
                .find(|s| s.get("name").and_then(Value::as_str) == Some("Frame"))
        })
        .unwrap_or_else(|| panic!("no struct Frame"));
    assert_eq!(
        get(frame, "size").as_u64(),
        Some(size_of::<FrameUniforms>() as u64)
    );
    use std::mem::offset_of;
    // Shader spelling (naga appends `_` to names ending in a digit) -> host offset.
    let host = [
        ("eye", offset_of!(FrameUniforms, eye)),
        ("axis", offset_of!(FrameUniforms, axis)),
        ("e1_", offset_of!(FrameUniforms, e1)),
        ("e2_", offset_of!(FrameUniforms, e2)),
        ("cam_forward", offset_of!(FrameUniforms, cam_forward)),
        ("cam_right", offset_of!(FrameUniforms, cam_right)),
        ("cam_up", offset_of!(FrameUniforms, cam_up)),
        ("theta", offset_of!(FrameUniforms, theta)),
        ("medium", offset_of!(FrameUniforms, medium)),
        ("light_color", offset_of!(FrameUniforms, light_color)),
        ("light_pos", offset_of!(FrameUniforms, light_pos)),
        ("light_dir", offset_of!(FrameUniforms, light_dir)),
        ("sm_right", offset_of!(FrameUniforms, sm_right)),
        ("sm_up", offset_of!(FrameUniforms, sm_up)),
        ("sm_forward", offset_of!(FrameUniforms, sm_forward)),
        ("sm_origin", offset_of!(FrameUniforms, sm_origin)),
        ("sm_proj", offset_of!(FrameUniforms, sm_proj)),
        ("epipole", offset_of!(FrameUniforms, epipole)),
        ("anti_epipole", offset_of!(FrameUniforms, anti_epipole)),
        ("sizes", offset_of!(FrameUniforms, sizes)),
        ("sizes2_", offset_of!(FrameUniforms, sizes2)),
        ("proj", offset_of!(FrameUniforms, proj)),
        ("proj_g0_", offset_of!(FrameUniforms, proj_g0)),
        ("proj_g1_", offset_of!(FrameUniforms, proj_g1)),
        ("proj_g2_", offset_of!(FrameUniforms, proj_g2)),
        ("fan_origin", offset_of!(FrameUniforms, fan_origin)),
        ("fan_angles", offset_of!(FrameUniforms, fan_angles)),
    ];
    let fields = get(frame, "fields").as_array().cloned().unwrap_or_default();
    assert_eq!(fields.len(), host.len(), "{fields:?}");
    for (f, (name, offset)) in fields.iter().zip(host) {
        assert_eq!(str_of(f, "name"), name);
        assert_eq!(get(f, "offset").as_u64(), Some(offset as u64), "{name}");
    }
}

/// The dispatch formulas, evaluated at odd sizes, give `ceil(invocations / workgroup)` with
/// the invocation grid of `scatter_runtime::prefiltered::Scatter::encode` and the workgroup
/// sizes of the kernels it builds.
#[test]
fn manifest_dispatch_matches_the_runtime_grid() {
    let (w, h, wr, hr) = (333u32, 187u32, 509u32, 257u32);
    let sizes = [
        ("screen.width", w),
        ("screen.height", h),
        ("rectified.width", wr),
        ("rectified.height", hr),
        ("shadow.size", 1024),
    ];
    for (bases, bases_per_thread, regions, visibility) in [
        (32, 8, 3, VisibilityMode::Weighted),
        (128, 4, 8, VisibilityMode::Average),
        (4, 4, 1, VisibilityMode::Weighted),
    ] {
        let v = PrefilteredVariant {
            bases,
            bases_per_thread,
            regions,
            visibility,
            ..PrefilteredVariant::default()
        };
        let m = manifest(v);
        let passes = get(&get(&m, "variants")[0], "passes")
            .as_array()
            .cloned()
            .unwrap_or_default();
        // Prefiltered::encode's invocation grids, in pass order.
        let grids = [
            [w, 1, 1],
            [256, 1, 1],
            [wr.div_ceil(RECTIFY_TEXELS), hr, 1],
            [hr, v.regions, v.threads_per_row_region()],
            [w, h, 1],
        ];
        assert_eq!(passes.len(), grids.len());
        for ((pass, params), grid) in passes.iter().zip(KernelParams::prefiltered(v)).zip(grids) {
            let built = build(&params).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(str_of(pass, "kernel"), built.kernel.name());
            let dispatch = get(pass, "dispatch")
                .as_array()
                .cloned()
                .unwrap_or_default();
            for i in 0..3 {
                let got = eval(str_of(&dispatch[i], "workgroups"), &sizes);
                let want = grid[i].div_ceil(built.workgroup_size[i]);
                assert_eq!(got, want, "{} {} dim {i}", v.id(), built.kernel);
            }
        }
    }
}

/// The raymarch family's manifest against `scatter_runtime::raymarch`: formats, the `RaymarchFrame`
/// block's size and field offsets, and the dispatch of both passes at odd sizes.
#[test]
fn raymarch_manifest_matches_the_runtime() {
    use scatter_runtime::raymarch::PARTIAL_FORMAT;
    use scatter_shaderlib::raymarch::{RaymarchUniforms, RaymarchVariant};
    use std::mem::offset_of;
    let v = RaymarchVariant {
        samples: 64,
        interleave: 4,
        jitter: true,
        light: LightKind::Spot,
        ..RaymarchVariant::default()
    };
    let g = generate(&Request {
        variants: vec![FamilyVariant::Raymarch(v)],
        targets: vec![Target::Wgsl],
    })
    .unwrap_or_else(|e| panic!("{v}: {e}"));
    let m: Value = serde_json::from_slice(&g.manifest).unwrap_or_else(|e| panic!("{e}"));
    let variant = &get(&m, "variants")[0];
    let tex = |name: &str| get(resource(variant, name), "texture").clone();
    assert_eq!(str_of(&tex("partial"), "format"), wgpu_name(PARTIAL_FORMAT));
    assert_eq!(str_of(&tex("output"), "format"), wgpu_name(OUTPUT_FORMAT));
    for name in ["depth", "shadow_map"] {
        assert_eq!(str_of(&tex(name), "format"), wgpu_name(DEPTH_FORMAT));
    }
    assert_eq!(
        str_of(get(resource(variant, "frame"), "buffer"), "size_bytes"),
        size_of::<RaymarchUniforms>().to_string()
    );
    let march = get(&m, "structs")
        .as_array()
        .and_then(|a| {
            a.iter()
                .find(|s| s.get("name").and_then(Value::as_str) == Some("RaymarchFrame"))
        })
        .unwrap_or_else(|| panic!("no struct RaymarchFrame"));
    let host = [
        ("eye", offset_of!(RaymarchUniforms, eye)),
        ("cam_forward", offset_of!(RaymarchUniforms, cam_forward)),
        ("cam_right", offset_of!(RaymarchUniforms, cam_right)),
        ("cam_up", offset_of!(RaymarchUniforms, cam_up)),
        ("medium", offset_of!(RaymarchUniforms, medium)),
        ("light_color", offset_of!(RaymarchUniforms, light_color)),
        ("light_pos", offset_of!(RaymarchUniforms, light_pos)),
        ("light_dir", offset_of!(RaymarchUniforms, light_dir)),
        ("sm_right", offset_of!(RaymarchUniforms, sm_right)),
        ("sm_up", offset_of!(RaymarchUniforms, sm_up)),
        ("sm_forward", offset_of!(RaymarchUniforms, sm_forward)),
        ("sm_origin", offset_of!(RaymarchUniforms, sm_origin)),
        ("sm_proj", offset_of!(RaymarchUniforms, sm_proj)),
        ("sizes", offset_of!(RaymarchUniforms, sizes)),
        ("interleave", offset_of!(RaymarchUniforms, interleave)),
    ];
    let fields = get(march, "fields").as_array().cloned().unwrap_or_default();
    assert_eq!(fields.len(), host.len(), "{fields:?}");
    for (f, (name, offset)) in fields.iter().zip(host) {
        assert_eq!(str_of(f, "name"), name);
        assert_eq!(get(f, "offset").as_u64(), Some(offset as u64), "{name}");
    }
    let (w, h) = (333u32, 187u32);
    let sizes = [
        ("screen.width", w),
        ("screen.height", h),
        ("shadow.size", 512),
    ];
    let passes = get(variant, "passes")
        .as_array()
        .cloned()
        .unwrap_or_default();
    let params = KernelParams::raymarch(v);
    assert_eq!(passes.len(), params.len());
    for (pass, p) in passes.iter().zip(params) {
        let built = build(&p).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(str_of(pass, "kernel"), built.kernel.name());
        let dispatch = get(pass, "dispatch")
            .as_array()
            .cloned()
            .unwrap_or_default();
        for (i, n) in [w, h, 1].into_iter().enumerate() {
            let got = eval(str_of(&dispatch[i], "workgroups"), &sizes);
            assert_eq!(
                got,
                n.div_ceil(built.workgroup_size[i]),
                "{} dim {i}",
                built.kernel
            );
        }
    }
}

/// The minmax family's manifest against `scatter_runtime::minmax`: formats (the tree's
/// rg32float included), the `Frame` block's size, and the dispatch of the three passes at
/// odd sizes, `tree.width` evaluated with `scatter_frame::minmax::tree_width`.
#[test]
fn minmax_manifest_matches_the_runtime() {
    use scatter_runtime::minmax::TREE_FORMAT;
    use scatter_shaderlib::minmax::{BUILD_LANES, MinmaxVariant, tree_width};
    use scatter_shaderlib::prefiltered::FrameUniforms;
    let v = MinmaxVariant {
        light: LightKind::Spot,
        ..MinmaxVariant::default()
    };
    let g = generate(&Request {
        variants: vec![FamilyVariant::Minmax(v)],
        targets: vec![Target::Wgsl],
    })
    .unwrap_or_else(|e| panic!("{v}: {e}"));
    let m: Value = serde_json::from_slice(&g.manifest).unwrap_or_else(|e| panic!("{e}"));
    let variant = &get(&m, "variants")[0];
    let tex = |name: &str| get(resource(variant, name), "texture").clone();
    assert_eq!(str_of(&tex("tree"), "format"), wgpu_name(TREE_FORMAT));
    assert_eq!(str_of(&tex("output"), "format"), wgpu_name(OUTPUT_FORMAT));
    for name in ["depth", "shadow_map", "rectified"] {
        assert_eq!(str_of(&tex(name), "format"), wgpu_name(DEPTH_FORMAT));
    }
    assert_eq!(
        str_of(get(resource(variant, "frame"), "buffer"), "size_bytes"),
        size_of::<FrameUniforms>().to_string()
    );
    let (w, h, wr, hr) = (333u32, 187u32, 300u32, 97u32);
    let tw = tree_width(wr);
    let sizes = [
        ("screen.width", w),
        ("screen.height", h),
        ("shadow.size", 512),
        ("rectified.width", wr),
        ("rectified.height", hr),
        ("tree.width", tw),
    ];
    let passes = get(variant, "passes")
        .as_array()
        .cloned()
        .unwrap_or_default();
    let params = KernelParams::minmax(v);
    assert_eq!(passes.len(), params.len());
    for ((pass, p), grid) in passes.iter().zip(params).zip([
        [w, 1, 1],
        [256, 1, 1],
        [wr.div_ceil(RECTIFY_TEXELS), hr, 1],
        [BUILD_LANES, hr, 1],
        [w, h, 1],
    ]) {
        let built = build(&p).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(str_of(pass, "kernel"), built.kernel.name());
        let dispatch = get(pass, "dispatch")
            .as_array()
            .cloned()
            .unwrap_or_default();
        for (i, n) in grid.into_iter().enumerate() {
            let got = eval(str_of(&dispatch[i], "workgroups"), &sizes);
            assert_eq!(
                got,
                n.div_ceil(built.workgroup_size[i]),
                "{} dim {i}",
                built.kernel
            );
        }
    }
}

/// The hybrid_volume family's manifest against the runtime: formats, the `Frame` block's
/// size, the `crossings` buffer's size formula (two u32 per rectified row and bin) and the
/// dispatch of the five passes at odd sizes (`volume_bounds`: one workgroup per row).
#[test]
fn hybrid_volume_manifest_matches_the_runtime() {
    use scatter_shaderlib::hybrid_volume::HybridVolumeVariant;
    use scatter_shaderlib::prefiltered::FrameUniforms;
    let v = HybridVolumeVariant {
        light: LightKind::Spot,
        bins: 100,
        ..HybridVolumeVariant::default()
    };
    let g = generate(&Request {
        variants: vec![FamilyVariant::HybridVolume(v)],
        targets: vec![Target::Wgsl],
    })
    .unwrap_or_else(|e| panic!("{v}: {e}"));
    let m: Value = serde_json::from_slice(&g.manifest).unwrap_or_else(|e| panic!("{e}"));
    let variant = &get(&m, "variants")[0];
    let tex = |name: &str| get(resource(variant, name), "texture").clone();
    assert_eq!(str_of(&tex("output"), "format"), wgpu_name(OUTPUT_FORMAT));
    for name in ["depth", "shadow_map", "rectified"] {
        assert_eq!(str_of(&tex(name), "format"), wgpu_name(DEPTH_FORMAT));
    }
    assert_eq!(
        str_of(get(resource(variant, "frame"), "buffer"), "size_bytes"),
        size_of::<FrameUniforms>().to_string()
    );
    let (w, h, wr, hr) = (333u32, 187u32, 300u32, 97u32);
    let sizes = [
        ("screen.width", w),
        ("screen.height", h),
        ("shadow.size", 512),
        ("rectified.width", wr),
        ("rectified.height", hr),
    ];
    let crossings = get(resource(variant, "crossings"), "buffer");
    assert_eq!(
        eval(str_of(crossings, "elements"), &sizes),
        2 * v.bins * hr,
        "crossings elements"
    );
    assert_eq!(
        eval(str_of(crossings, "size_bytes"), &sizes),
        8 * v.bins * hr,
        "crossings bytes"
    );
    let passes = get(variant, "passes")
        .as_array()
        .cloned()
        .unwrap_or_default();
    let params = KernelParams::hybrid_volume(v);
    assert_eq!(passes.len(), params.len());
    for ((pass, p), grid) in passes.iter().zip(params).zip([
        [w, 1, 1],
        [256, 1, 1],
        [wr.div_ceil(RECTIFY_TEXELS), hr, 1],
        [64, hr, 1],
        [w, h, 1],
    ]) {
        let built = build(&p).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(str_of(pass, "kernel"), built.kernel.name());
        let dispatch = get(pass, "dispatch")
            .as_array()
            .cloned()
            .unwrap_or_default();
        for (i, n) in grid.into_iter().enumerate() {
            let got = eval(str_of(&dispatch[i], "workgroups"), &sizes);
            assert_eq!(
                got,
                n.div_ceil(built.workgroup_size[i]),
                "{} dim {i}",
                built.kernel
            );
        }
    }
}
