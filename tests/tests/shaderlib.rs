//! Every kernel in every mode renders, composes and validates; every kernel's template names
//! its CPU mirror and the mirror exists (one name per kernel across the workspace).

use std::path::Path;

use scatter_shaderlib::family::{Family, KernelFamily, kernels};
use scatter_shaderlib::sampling::SamplingKnobs;
use scatter_shaderlib::uniform_branches::uniform_branches;
use scatter_shaderlib::{Kernel, KernelParams, build};

fn workspace_root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ lives in the workspace root")
}

#[test]
fn every_kernel_and_mode_validates() {
    let all = KernelParams::all_modes();
    for &kernel in Kernel::ALL {
        assert!(
            all.iter().any(|p| p.kernel() == kernel),
            "kernel `{kernel}` has no parameter set in KernelParams::all_modes()"
        );
    }
    for params in &all {
        // The family whose kernels include this one (from the family table), or `common`.
        let owner = Family::ALL
            .iter()
            .find(|&&f| kernels(f).contains(&params.kernel()))
            .map_or("common", |f| f.name());
        let trial = match params {
            KernelParams::RowPrefix(p) => {
                format!("{owner}::{}::{}::validate", params.kernel(), p.mode.name())
            }
            _ => format!("{owner}::{}::validate", params.kernel()),
        };
        let built = build(params).unwrap_or_else(|e| panic!("{trial}: {e}"));
        assert_eq!(built.entry_point, params.kernel().name(), "{trial}");
        eprintln!(
            "ok   {trial}: entry point `{}`, workgroup {:?}, {} bytes of WGSL",
            built.entry_point,
            built.workgroup_size,
            built.wgsl.len()
        );
    }
}

#[test]
fn every_template_names_its_existing_mirror() {
    for &kernel in Kernel::ALL {
        let name = kernel.name();
        let template = workspace_root().join(format!("shaderlib/templates/{name}.wgsl"));
        let text = std::fs::read_to_string(&template)
            .unwrap_or_else(|e| panic!("{}: {e}", template.display()));
        let mirror = format!("reference/src/kernels/{name}.rs");
        assert!(
            text.contains(&format!("Mirrors {mirror}")),
            "{}: header must say `Mirrors {mirror}`",
            template.display()
        );
        assert!(
            workspace_root().join(&mirror).is_file(),
            "missing CPU mirror {mirror}"
        );
    }
}

/// No kernel of any family's grid branches on uniforms alone: lavapipe 22.3 re-specialises
/// such a shader at every dispatch (`scatter_shaderlib::uniform_branches`; the raymarch
/// epipolar samples pass 6.9-7.7 ms with one such branch, 3.3-4.2 without). The one exception
/// is the projective variants' rectification switch (`frame.proj[0]`, chosen per frame in
/// `rectification = projective`): a branch between two whole algorithms, which on a GPU costs
/// nothing and as a select would run both for every pixel.
#[test]
fn no_kernel_branches_on_uniforms_only() {
    // Every grid variant, and every family's default with each sampling (the samples
    // passes are kernels of their own).
    let mut params: Vec<KernelParams> = KernelParams::all_modes();
    for &f in Family::ALL {
        let sampled = [
            SamplingKnobs::lowres(2),
            SamplingKnobs::lowres(4),
            SamplingKnobs::epipolar(256),
            SamplingKnobs::epipolar(SamplingKnobs::DEFAULT_SLICES),
        ]
        .map(|k| f.default_variant().with_sampling(k))
        .into_iter()
        .filter(|v| v.validate().is_ok());
        for v in f.grid().into_iter().chain(sampled) {
            for p in v.kernel_params() {
                if !params.contains(&p) {
                    params.push(p);
                }
            }
        }
    }
    let mut failures = Vec::new();
    let mut switches = 0;
    for p in &params {
        let built = build(p).unwrap_or_else(|e| panic!("{}: {e}", p.kernel()));
        // The `proj` member of the kernel's `frame` uniform, where it has one.
        let proj = built.module.global_variables.iter().find_map(|(_, g)| {
            let naga::TypeInner::Struct { members, .. } = &built.module.types[g.ty].inner else {
                return None;
            };
            let i = members
                .iter()
                .position(|m| m.name.as_deref() == Some("proj"))?;
            (g.name.as_deref() == Some("frame")).then(|| format!("frame.{i}.0"))
        });
        for b in uniform_branches(&built.module, built.entry_point) {
            let switch = proj.as_ref().is_some_and(|proj| b.reads == [proj.clone()])
                && matches!(
                    p.kernel(),
                    Kernel::Scatter | Kernel::Prefilter | Kernel::SliceFit
                );
            if switch {
                switches += 1;
            } else {
                failures.push(format!("{}: {b}", p.kernel()));
            }
        }
    }
    failures.sort();
    failures.dedup();
    eprintln!(
        "{} parameter sets, {switches} rectification switches (projective variants)",
        params.len()
    );
    assert!(
        failures.is_empty(),
        "branches on uniforms alone:\n{}",
        failures.join("\n")
    );
    assert!(
        switches > 0,
        "the projective variants' switch was not seen: the check reads nothing"
    );
}
