//! Every kernel in every mode renders, composes and validates; every kernel's template names
//! its CPU mirror and the mirror exists (one name per kernel across the workspace).

use std::path::Path;

use scatter_shaderlib::family::{Family, kernels};
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
