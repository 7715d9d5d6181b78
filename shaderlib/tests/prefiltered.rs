//! The prefiltered family's kernels (`rectify`, `prefilter`, `scatter`): every variant of the
//! design card's cross product renders and validates, bad variants are rejected naming the
//! knob, workgroup sizes and bindings read back from the naga IR match the documented ones,
//! and the SPIR-V and GLSL back-ends accept the modules.

use std::collections::HashMap;
use std::sync::Mutex;
use std::time::Instant;

use scatter_shaderlib::prefiltered::{
    DEPTH_COLUMNS_WORKGROUP_SIZE, LightKind, PREFILTER_WORKGROUP_SIZE, PrefilteredVariant,
    RECTIFY_WORKGROUP_SIZE, Rectification, SCATTER_WORKGROUP_SIZE, SLICE_FIT_WORKGROUP_SIZE,
    Storage, VisibilityMode,
};
use scatter_shaderlib::{BuiltKernel, Kernel, KernelParams, ShaderError, build, render};

/// Every valid variant: bases {4, .., 128} x every bases_per_thread x regions 1..=16 (1..=8
/// projective) x
/// visibility x light x storage x rectification, the moment basis (4 or 6 moments) x
/// regions x visibility x light x rectification, the spot's cookie (3 bases x visibility
/// x rectification), and the coarse filtered columns (`filtered_stride` 2, 4, 8 x light x
/// rectification x visibility x 5 bases, and 4 cookie variants each), and `resume` (each
/// stride x light x rectification x visibility, the bases cycling, and 2 cookie variants).
fn cross_product() -> Vec<PrefilteredVariant> {
    PrefilteredVariant::grid(PrefilteredVariant::REGIONS)
}

/// Renders every kernel of every variant and validates each distinct rendered source once
/// (rendering is deterministic, so identical sources validate identically: `rectify` only
/// depends on the light, `scatter` not on `bases_per_thread`). Two threads.
#[test]
fn full_cross_product_validates() {
    let variants = cross_product();
    assert_eq!(
        variants.len(),
        21 * (8 * 2 + 8) * 2 * 3 * 2
            + 2 * (8 * 2 + 8) * 2 * 2
            + 3 * 2 * 2
            + 3 * (2 * 2 * 2 * 5 + 4)
            + 3 * (2 * 2 * 2 + 2),
        "21 (bases, bases_per_thread) pairs x regions (1..=8 with both rectifications, 9..=16 \
         epipolar only); 2 moment counts (rgba32float only); cookies; filtered strides; resume"
    );
    let start = Instant::now();
    // (kernel, rendered source) -> first parameter set that produced it.
    let mut distinct: HashMap<(Kernel, String), KernelParams> = HashMap::new();
    let mut rendered = 0usize;
    for &variant in &variants {
        assert_eq!(variant.validate(), Ok(()), "{variant}");
        for params in KernelParams::prefiltered(variant) {
            let source = render(&params).unwrap_or_else(|e| panic!("{variant}: {e}"));
            rendered += 1;
            distinct.entry((params.kernel(), source)).or_insert(params);
        }
    }
    let render_time = start.elapsed();
    let jobs: Mutex<Vec<KernelParams>> = Mutex::new(distinct.into_values().collect());
    let total = jobs.lock().map(|j| j.len()).unwrap_or(0);
    let per_kernel: Mutex<HashMap<Kernel, usize>> = Mutex::new(HashMap::new());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| {
                loop {
                    let Some(params) = jobs.lock().expect("not poisoned").pop() else {
                        break;
                    };
                    let built = build(&params).unwrap_or_else(|e| panic!("{params:?}: {e}"));
                    assert_eq!(built.entry_point, params.kernel().name());
                    *per_kernel
                        .lock()
                        .expect("not poisoned")
                        .entry(params.kernel())
                        .or_default() += 1;
                }
            });
        }
    });
    let per_kernel = per_kernel.into_inner().expect("not poisoned");
    assert_eq!(
        per_kernel[&Kernel::Rectify],
        2,
        "rectify depends on the light only"
    );
    // Scatter: the Fourier layer counts (6 bases values) x the 3 storage formats (the
    // `filtered` buffer's element) and the 2 moment counts (rgba32float only), each x
    // (regions x rectification: 8 x 2 + 8 epipolar) x visibility x light; the cookie's 3 bases x visibility x
    // rectification; every coarse-column variant (its stride is in the source), and every
    // `resume` one.
    assert_eq!(
        per_kernel[&Kernel::Scatter],
        (6 * 3 + 2) * (8 * 2 + 8) * 2 * 2
            + 3 * 2 * 2
            + 3 * (2 * 2 * 2 * 5 + 4)
            + 3 * (2 * 2 * 2 + 2)
    );
    assert_eq!(per_kernel[&Kernel::Prefilter], variants.len());
    eprintln!(
        "{} variants, {rendered} kernels rendered in {:.2?}; {total} distinct sources \
         (rectify {}, prefilter {}, scatter {}) composed and validated, {:.2?} in all",
        variants.len(),
        render_time,
        per_kernel[&Kernel::Rectify],
        per_kernel[&Kernel::Prefilter],
        per_kernel[&Kernel::Scatter],
        start.elapsed(),
    );
}

#[test]
fn bad_variants_are_rejected_naming_the_knob() {
    let cases = [
        (
            PrefilteredVariant {
                bases: 30,
                ..PrefilteredVariant::default()
            },
            "bases",
        ),
        (
            PrefilteredVariant {
                bases: 132,
                bases_per_thread: 4,
                ..PrefilteredVariant::default()
            },
            "bases",
        ),
        (
            PrefilteredVariant {
                bases_per_thread: 12,
                ..PrefilteredVariant::default()
            },
            "bases_per_thread",
        ),
        (
            PrefilteredVariant {
                regions: 17,
                ..PrefilteredVariant::default()
            },
            "regions",
        ),
        (
            PrefilteredVariant {
                regions: 9,
                rectification: Rectification::Projective,
                ..PrefilteredVariant::default()
            },
            "regions",
        ),
    ];
    for (variant, knob) in cases {
        for params in KernelParams::prefiltered(variant) {
            let err = build(&params).expect_err("rejected");
            let text = err.to_string();
            assert!(
                matches!(&err, ShaderError::Variant { kernel, source }
                    if *kernel == params.kernel() && source.knob == knob),
                "{err:?}"
            );
            assert!(
                text.contains(params.kernel().name()) && text.contains(knob),
                "{text}"
            );
        }
    }
    let text = build(&KernelParams::Prefilter(PrefilteredVariant {
        bases: 30,
        ..PrefilteredVariant::default()
    }))
    .expect_err("rejected")
    .to_string();
    assert_eq!(
        text,
        "kernel `prefilter`: invalid variant: bases must be a multiple of 4 in 4..=128, got 30"
    );
}

fn built(params: KernelParams) -> BuiltKernel {
    build(&params).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn workgroup_sizes_read_back_from_the_ir() {
    for variant in [
        PrefilteredVariant::default(),
        PrefilteredVariant {
            bases: 128,
            bases_per_thread: 128,
            regions: 8,
            light: LightKind::Spot,
            visibility: VisibilityMode::Average,
            storage: Storage::Rgba32float,
            ..PrefilteredVariant::default()
        },
    ] {
        let [depth_columns, slice_fit, rectify, prefilter, scatter] =
            KernelParams::prefiltered(variant).map(built);
        assert_eq!(depth_columns.workgroup_size, DEPTH_COLUMNS_WORKGROUP_SIZE);
        assert_eq!(depth_columns.workgroup_size, [64, 1, 1]);
        assert_eq!(slice_fit.workgroup_size, SLICE_FIT_WORKGROUP_SIZE);
        assert_eq!(slice_fit.workgroup_size, [256, 1, 1]);
        assert_eq!(rectify.workgroup_size, RECTIFY_WORKGROUP_SIZE);
        assert_eq!(rectify.workgroup_size, [8, 8, 1]);
        assert_eq!(prefilter.workgroup_size, PREFILTER_WORKGROUP_SIZE);
        assert_eq!(prefilter.workgroup_size, [64, 1, 1]);
        assert_eq!(scatter.workgroup_size, SCATTER_WORKGROUP_SIZE);
        assert_eq!(scatter.workgroup_size, [8, 8, 1]);
    }
}

/// (binding, variable name, naga type description) of every group-0 resource, sorted.
fn bindings(built: &BuiltKernel) -> Vec<(u32, String, String)> {
    let m = &built.module;
    let mut out: Vec<_> = m
        .global_variables
        .iter()
        .filter_map(|(_, var)| {
            let binding = var.binding.as_ref()?;
            assert_eq!(binding.group, 0, "{:?}", var.name);
            let ty = match &m.types[var.ty].inner {
                naga::TypeInner::Struct { .. } => format!("{:?} struct", var.space),
                naga::TypeInner::Array { base, .. } => {
                    format!("{:?} array<{:?}>", var.space, m.types[*base].inner)
                }
                naga::TypeInner::Image {
                    dim,
                    arrayed,
                    class,
                } => format!("{dim:?} arrayed={arrayed} {class:?}"),
                naga::TypeInner::Sampler { comparison } => format!("sampler cmp={comparison}"),
                other => format!("{other:?}"),
            };
            Some((binding.binding, var.name.clone().unwrap_or_default(), ty))
        })
        .collect();
    out.sort();
    out
}

#[test]
fn bindings_match_the_documented_tables() {
    use naga::{ImageClass, ImageDimension, StorageAccess, StorageFormat};
    let uniform = "Uniform struct".to_owned();
    let slices = "Storage { access: StorageAccess(LOAD) } array<Vector { size: Quad, scalar: \
                  Scalar { kind: Float, width: 4 } }>"
        .to_owned();
    let slices_rw = "Storage { access: StorageAccess(LOAD | STORE) } array<Vector { size: Quad, \
                     scalar: Scalar { kind: Float, width: 4 } }>"
        .to_owned();
    let column_depth_rw = "Storage { access: StorageAccess(LOAD | STORE) } array<Scalar(Scalar { \
                        kind: Float, width: 4 })>"
        .to_owned();
    let bounds_rw = "Storage { access: StorageAccess(LOAD | STORE) } array<Vector { size: Bi, \
                     scalar: Scalar { kind: Float, width: 4 } }>"
        .to_owned();
    let bounds_read = "Storage { access: StorageAccess(LOAD) } array<Vector { size: Bi, scalar: \
                       Scalar { kind: Float, width: 4 } }>"
        .to_owned();
    let column_depth_read = "Storage { access: StorageAccess(LOAD) } array<Scalar(Scalar { kind: \
                          Float, width: 4 })>"
        .to_owned();
    let sampled = |arrayed: bool| {
        format!(
            "{:?} arrayed={arrayed} {:?}",
            ImageDimension::D2,
            ImageClass::Sampled {
                kind: naga::ScalarKind::Float,
                multi: false
            }
        )
    };
    let storage = |format: StorageFormat, arrayed: bool| {
        format!(
            "{:?} arrayed={arrayed} {:?}",
            ImageDimension::D2,
            ImageClass::Storage {
                format,
                access: StorageAccess::STORE
            }
        )
    };
    for &light in LightKind::SINGLE {
        // `filtered` is a storage buffer of one storage-format texel's bits per element.
        for (&storage_knob, word) in Storage::ALL.iter().zip([
            "Vector { size: Bi, scalar: Scalar { kind: Uint, width: 4 } }",
            "Vector { size: Quad, scalar: Scalar { kind: Float, width: 4 } }",
            "Scalar(Scalar { kind: Uint, width: 4 })",
        ]) {
            let filtered_rw =
                format!("Storage {{ access: StorageAccess(LOAD | STORE) }} array<{word}>");
            let filtered_read = format!("Storage {{ access: StorageAccess(LOAD) }} array<{word}>");
            let variant = PrefilteredVariant {
                light,
                storage: storage_knob,
                ..PrefilteredVariant::default()
            };
            let [depth_columns, slice_fit, rectify, prefilter, scatter] =
                KernelParams::prefiltered(variant).map(built);
            let b = |n: u32, name: &str, ty: &String| (n, name.to_owned(), ty.clone());
            assert_eq!(
                bindings(&depth_columns),
                vec![
                    b(0, "frame", &uniform),
                    b(1, "depth", &sampled(false)),
                    b(2, "column_depth", &column_depth_rw),
                ]
            );
            assert_eq!(
                bindings(&slice_fit),
                vec![
                    b(0, "frame", &uniform),
                    b(1, "slices", &slices_rw),
                    b(2, "column_depth", &column_depth_read),
                ]
            );
            assert_eq!(
                bindings(&rectify),
                vec![
                    b(0, "frame", &uniform),
                    b(1, "slices", &slices),
                    b(2, "shadow_map", &sampled(false)),
                    b(3, "rectified", &storage(StorageFormat::R32Float, false)),
                ]
            );
            assert_eq!(
                bindings(&prefilter),
                vec![
                    b(0, "frame", &uniform),
                    b(1, "slices", &slices),
                    b(2, "rectified", &sampled(false)),
                    b(3, "filtered", &filtered_rw),
                    b(4, "bounds", &bounds_rw),
                ]
            );
            assert_eq!(
                bindings(&scatter),
                vec![
                    b(0, "frame", &uniform),
                    b(1, "slices", &slices),
                    b(2, "depth", &sampled(false)),
                    b(3, "shadow_map", &sampled(false)),
                    b(4, "filtered", &filtered_read),
                    b(5, "output", &storage(StorageFormat::Rgba16Float, false)),
                    b(6, "bounds", &bounds_read),
                ]
            );
        }
    }
}

/// The `Frame` struct has the host `FrameUniforms` layout: 19 vec4<f32>, 2 vec4<u32>, then
/// 6 vec4<f32>.
#[test]
fn frame_layout_matches_the_host_struct() {
    let built = built(KernelParams::Scatter(PrefilteredVariant::default()));
    let m = &built.module;
    let (_, frame) = m
        .global_variables
        .iter()
        .find(|(_, v)| v.name.as_deref() == Some("frame"))
        .expect("frame binding");
    let naga::TypeInner::Struct { members, span } = &m.types[frame.ty].inner else {
        panic!("frame is not a struct");
    };
    assert_eq!(
        *span as usize,
        size_of::<scatter_shaderlib::prefiltered::FrameUniforms>()
    );
    assert_eq!(members.len(), 27);
    for (i, member) in members.iter().enumerate() {
        assert_eq!(member.offset as usize, 16 * i, "{:?}", member.name);
        let naga::TypeInner::Vector { size, scalar } = m.types[member.ty].inner else {
            panic!("{:?} is not a vector", member.name);
        };
        assert_eq!(size, naga::VectorSize::Quad);
        let kind = if (19..21).contains(&i) {
            naga::ScalarKind::Uint
        } else {
            naga::ScalarKind::Float
        };
        assert_eq!(scalar, naga::Scalar { kind, width: 4 }, "{:?}", member.name);
    }
    let names: Vec<_> = members.iter().filter_map(|m| m.name.as_deref()).collect();
    assert_eq!(
        names,
        [
            "eye",
            "axis",
            "e1_",
            "e2_",
            "cam_forward",
            "cam_right",
            "cam_up",
            "theta",
            "medium",
            "light_color",
            "light_pos",
            "light_dir",
            "sm_right",
            "sm_up",
            "sm_forward",
            "sm_origin",
            "sm_proj",
            "epipole",
            "anti_epipole",
            "sizes",
            "sizes2_",
            "proj",
            "proj_g0_",
            "proj_g1_",
            "proj_g2_",
            "fan_origin",
            "fan_angles",
        ]
    );
}

/// The generator's targets: SPIR-V and GLSL 450 accept the extreme variants.
#[test]
fn spirv_and_glsl_back_ends_accept_the_modules() {
    let small = PrefilteredVariant {
        bases: 4,
        bases_per_thread: 4,
        regions: 1,
        visibility: VisibilityMode::Average,
        ..PrefilteredVariant::default()
    };
    let large = PrefilteredVariant {
        bases: 128,
        bases_per_thread: 128,
        regions: 8,
        light: LightKind::Spot,
        storage: Storage::Rgba16float,
        ..PrefilteredVariant::default()
    };
    for variant in [small, large, PrefilteredVariant::default()] {
        for built in KernelParams::prefiltered(variant).map(built) {
            let stage = naga::ShaderStage::Compute;
            naga::back::spv::write_vec(
                &built.module,
                &built.info,
                &naga::back::spv::Options::default(),
                Some(&naga::back::spv::PipelineOptions {
                    shader_stage: stage,
                    entry_point: built.entry_point.into(),
                }),
            )
            .unwrap_or_else(|e| panic!("{} {variant}: SPIR-V: {e}", built.kernel));
            let mut glsl = String::new();
            let options = naga::back::glsl::Options {
                version: naga::back::glsl::Version::Desktop(450),
                ..Default::default()
            };
            let pipeline = naga::back::glsl::PipelineOptions {
                shader_stage: stage,
                entry_point: built.entry_point.into(),
                multiview: None,
            };
            naga::back::glsl::Writer::new(
                &mut glsl,
                &built.module,
                &built.info,
                &options,
                &pipeline,
                naga::proc::BoundsCheckPolicies::default(),
            )
            .and_then(|mut w| w.write().map(|_| ()))
            .unwrap_or_else(|e| panic!("{} {variant}: GLSL: {e}", built.kernel));
        }
    }
}

#[test]
fn templates_receive_the_variant_s_values() {
    let variant = PrefilteredVariant {
        bases: 64,
        bases_per_thread: 16,
        regions: 5,
        visibility: VisibilityMode::Average,
        light: LightKind::Spot,
        storage: Storage::Rgba16float,
        ..PrefilteredVariant::default()
    };
    let [depth_columns, slice_fit, rectify, prefilter, scatter] =
        KernelParams::prefiltered(variant).map(|p| render(&p).unwrap_or_else(|e| panic!("{e}")));
    assert!(depth_columns.contains("Mirrors reference/src/kernels/depth_columns.rs"));
    assert!(slice_fit.contains("let spot = true;"), "{slice_fit}");
    assert!(slice_fit.contains("Mirrors reference/src/kernels/slice_fit.rs"));
    assert!(rectify.contains("let spot = true;"), "{rectify}");
    assert!(rectify.contains("Mirrors reference/src/kernels/rectify.rs"));
    for needle in [
        "var<storage, read_write> filtered: array<vec2<u32>>;",
        "pack2x16float",
        "const REGIONS: u32 = 5u;",
        "const BASES_PER_THREAD: u32 = 16u;",
        "const THREADS_PER_ROW_REGION: u32 = 4u;",
        "var acc: array<vec4<f32>, 4>;",
        "let weighted = false;",
        "let spot = true;",
        "Mirrors reference/src/kernels/prefilter.rs",
    ] {
        assert!(prefilter.contains(needle), "{needle}\n{prefilter}");
    }
    for needle in [
        "const REGIONS: u32 = 5u;",
        "const LAYERS: u32 = 16u;",
        // Average and weighted visibility share scatter's code (they differ in prefilter's
        // texel weights); the header names the mode.
        "5 regions, average visibility",
        "let spot = true;",
        "var<storage, read> filtered: array<vec2<u32>>;",
        "unpack2x16float",
        "Mirrors reference/src/kernels/scatter.rs",
    ] {
        assert!(scatter.contains(needle), "{needle}\n{scatter}");
    }
    // Deterministic: same inputs, same bytes.
    assert_eq!(render(&KernelParams::Scatter(variant)).ok(), Some(scatter));
}

#[test]
fn params_round_trip_through_json() {
    for params in KernelParams::prefiltered(PrefilteredVariant {
        bases: 16,
        light: LightKind::Spot,
        ..PrefilteredVariant::default()
    }) {
        let json = serde_json::to_string(&params).expect("serialises");
        let back: KernelParams = serde_json::from_str(&json).expect("deserialises");
        assert_eq!(back, params, "{json}");
    }
    let json = r#"{"kernel":"scatter","bases":8,"regions":2}"#;
    let params: KernelParams = serde_json::from_str(json).expect("defaults fill the rest");
    assert_eq!(
        params,
        KernelParams::Scatter(PrefilteredVariant {
            bases: 8,
            regions: 2,
            ..PrefilteredVariant::default()
        })
    );
    assert!(serde_json::from_str::<KernelParams>(r#"{"kernel":"scatter","base":8}"#).is_err());
}
