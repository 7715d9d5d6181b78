//! Every family's conformance grid (`Family::grid`: for the prefiltered family
//! `PrefilteredVariant::grid(1..=4)`, every `bases` power of two with every
//! `bases_per_thread`, 1-4 regions, both visibilities and lights, every storage format and
//! every rectification; raymarch samples 8/32/128, interleave 1/2/4, jitter, both lights;
//! minmax, partial-sum-tree, hybrid-volume and area_ivsv grids as their modules list) through the
//! generator with every target, then every distinct emitted SPIR-V through `spirv-val`,
//! every distinct GLSL through `glslangValidator` and every distinct HLSL through
//! `glslangValidator -D` (its HLSL front end, to SPIR-V). Identical files (e.g. `rectify`
//! only depends on the light) are validated once.
//!
//! glslang's HLSL front end lacks one construct naga writes and FXC/DXC take: the cast of
//! the scalar `0` to an array, `(float4[8])0`, naga's zero value of an array (every local
//! array, and workgroup memory zeroed in the entry point). [`for_glslang`] replaces exactly
//! that cast with an element loop in a copy given to glslang, so every other line is still
//! checked; the count is printed and the README states it.

mod common;

use std::collections::BTreeMap;
use std::process::Command;
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;
use scatter_gen::{Family, FamilyVariant, KernelFamily, Request, Target, generate, manifest};

use common::{require, scratch};

/// The grid the generator is validated on (documented in the README): every family's.
fn grid() -> Vec<FamilyVariant> {
    Family::ALL.iter().flat_map(|f| f.grid()).collect()
}

/// `hlsl` with every cast of `0` to an array (`= (T[N])0;`, `= (T[N][M])0;`: naga's zero
/// value of an array, valid HLSL that glslang's front end does not parse: "array constructor
/// needs one argument per array element") replaced by loops that zero each element, and the
/// number of casts replaced. A declaration `T x[N] = (T[N])0;` becomes `T x[N];` and the
/// loops; an assignment `x = (T[N])0;` the loops. Any other form is left for glslang to
/// reject.
fn for_glslang(hlsl: &str) -> (String, usize) {
    let mut out = String::with_capacity(hlsl.len() + 256);
    let mut replaced = 0;
    for line in hlsl.lines() {
        match zero_array_assignment(line) {
            Some((indent, lhs, elem, dims)) => {
                let target = if lhs.contains('[') {
                    out.push_str(&format!("{indent}{lhs};\n"));
                    lhs.split('[')
                        .next()
                        .and_then(|d| d.split_whitespace().last())
                        .unwrap_or(lhs)
                } else {
                    lhs
                };
                out.push_str(indent);
                let mut index = String::new();
                for (k, len) in dims.iter().enumerate() {
                    out.push_str(&format!(
                        "for (uint scatter_zero_{k} = 0u; scatter_zero_{k} < {len}u; \
                         ++scatter_zero_{k}) {{ "
                    ));
                    index.push_str(&format!("[scatter_zero_{k}]"));
                }
                out.push_str(&format!("{target}{index} = ({elem})0; "));
                out.push_str(&"}".repeat(dims.len()));
                out.push('\n');
                replaced += 1;
            }
            None => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    (out, replaced)
}

/// `(indent, left-hand side, element type, lengths)` of a line
/// `<lhs> = (<elem>[<len>]...)0;`.
fn zero_array_assignment(line: &str) -> Option<(&str, &str, &str, Vec<u32>)> {
    let body = line.trim_start();
    let indent = &line[..line.len() - body.len()];
    let (lhs, rhs) = body.split_once(" = ")?;
    let cast = rhs.strip_prefix('(')?.strip_suffix(")0;")?;
    let (elem, dims) = cast.split_once('[')?;
    let dims = dims
        .strip_suffix(']')?
        .split("][")
        .map(|d| d.parse().ok())
        .collect::<Option<Vec<u32>>>()?;
    let ident = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    (ident(elem) && !lhs.contains('=')).then_some(())?;
    Some((indent, lhs, elem, dims))
}

#[test]
fn zero_array_casts_become_element_loops_and_nothing_else_changes() {
    let src = "    float4 coeffs[8] = (float4[8])0;\n        deepest = (float[256])0;\n    float a = (float)0;\n        hsum = (float3[15][8])0;\n    uint m[2] = { 1u, 2u };\n";
    let (out, n) = for_glslang(src);
    assert_eq!(n, 3);
    assert_eq!(
        out,
        "    float4 coeffs[8];\n    for (uint scatter_zero_0 = 0u; scatter_zero_0 < 8u; ++scatter_zero_0) { coeffs[scatter_zero_0] = (float4)0; }\n        for (uint scatter_zero_0 = 0u; scatter_zero_0 < 256u; ++scatter_zero_0) { deepest[scatter_zero_0] = (float)0; }\n    float a = (float)0;\n        for (uint scatter_zero_0 = 0u; scatter_zero_0 < 15u; ++scatter_zero_0) { for (uint scatter_zero_1 = 0u; scatter_zero_1 < 8u; ++scatter_zero_1) { hsum[scatter_zero_0][scatter_zero_1] = (float3)0; }}\n    uint m[2] = { 1u, 2u };\n"
    );
}

/// Distinct files: (extension, sha256 without banner) -> (first file name, bytes).
type Distinct = BTreeMap<(String, String), (String, Vec<u8>)>;

/// `bytes` without the generator's banner comment lines.
fn without_banner(bytes: &[u8]) -> Vec<u8> {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return bytes.to_vec();
    };
    text.lines()
        .filter(|l| {
            !l.starts_with("// Generated by scatter-gen") && !l.starts_with("// Do not edit:")
        })
        .flat_map(|l| l.bytes().chain([b'\n']))
        .collect()
}

#[test]
fn every_grid_variant_emits_and_passes_external_validators() {
    let test = "every_grid_variant_emits_and_passes_external_validators";
    let spirv_val = require("spirv-val", "spirv-tools", test);
    let glslang = require("glslangValidator", "glslang-tools", test);
    let start = Instant::now();
    let variants = grid();
    // sha256 -> (first file name, bytes), per extension.
    let distinct: Mutex<Distinct> = Mutex::default();
    let kernel_files = Mutex::new(0usize);
    variants.par_iter().for_each(|v| {
        let generated = generate(&Request {
            variants: vec![*v],
            targets: Target::ALL.to_vec(),
        })
        .unwrap_or_else(|e| panic!("{}: {e}", v.id()));
        let mut n = 0;
        let mut local = Vec::new();
        for f in &generated.files {
            let ext = f.path.rsplit('.').next().unwrap_or_default().to_owned();
            if ext == "h" || ext == "rs" {
                continue;
            }
            n += 1;
            if ext == "spv" || ext == "comp" || ext == "hlsl" {
                // The banner names the variant: leave it out of the key.
                let key = manifest::sha256_hex(&without_banner(&f.bytes));
                local.push(((ext, key), (f.path.clone(), f.bytes.clone())));
            }
        }
        *kernel_files.lock().unwrap_or_else(|e| e.into_inner()) += n;
        let mut map = distinct.lock().unwrap_or_else(|e| e.into_inner());
        for (k, v) in local {
            map.entry(k).or_insert(v);
        }
    });
    let generated_in = start.elapsed();
    let distinct = distinct.into_inner().unwrap_or_else(|e| e.into_inner());
    let kernel_files = kernel_files.into_inner().unwrap_or_else(|e| e.into_inner());

    let dir = scratch("grid");
    let mut spv = Vec::new();
    let mut comp = Vec::new();
    let mut hlsl = Vec::new();
    let mut zero_casts = 0;
    let mut hlsl_rewritten = 0;
    for ((ext, hash), (name, bytes)) in &distinct {
        let path = dir.join(format!("{}.{ext}", &hash[..16]));
        match ext.as_str() {
            "spv" => spv.push((path.clone(), name.clone())),
            "comp" => comp.push((path.clone(), name.clone())),
            _ => {
                let (text, n) = for_glslang(&String::from_utf8_lossy(bytes));
                zero_casts += n;
                hlsl_rewritten += usize::from(n > 0);
                std::fs::write(&path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                hlsl.push((path, name.clone()));
                continue;
            }
        }
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }

    let validate_start = Instant::now();
    let mut failures: Vec<String> = Vec::new();
    if spirv_val {
        failures.extend(
            spv.par_iter()
                .filter_map(|(path, name)| {
                    let out = Command::new("spirv-val")
                        .args(["--target-env", "vulkan1.0"])
                        .arg(path)
                        .output()
                        .unwrap_or_else(|e| panic!("spirv-val: {e}"));
                    (!out.status.success()).then(|| {
                        format!(
                            "spirv-val rejects {name}: {}{}",
                            String::from_utf8_lossy(&out.stdout),
                            String::from_utf8_lossy(&out.stderr)
                        )
                    })
                })
                .collect::<Vec<_>>(),
        );
    }
    if glslang {
        // glslangValidator starts slowly: many files per process (validated separately,
        // not linked).
        failures.extend(
            comp.par_chunks(48)
                .filter_map(|chunk| {
                    let out = Command::new("glslangValidator")
                        .args(chunk.iter().map(|(p, _)| p))
                        .output()
                        .unwrap_or_else(|e| panic!("glslangValidator: {e}"));
                    (!out.status.success()).then(|| {
                        let names: Vec<_> = chunk
                            .iter()
                            .map(|(p, n)| format!("{} = {n}", p.display()))
                            .collect();
                        format!(
                            "glslangValidator rejects one of [{}]: {}",
                            names.join(", "),
                            String::from_utf8_lossy(&out.stdout)
                        )
                    })
                })
                .collect::<Vec<_>>(),
        );
    }
    if glslang {
        // One file per process: glslang links the files of one run into one program, and
        // each file names its own entry point (the kernel, the head of the file name).
        failures.extend(
            hlsl.par_iter()
                .filter_map(|(path, name)| {
                    let entry = name
                        .rsplit('/')
                        .next()
                        .and_then(|f| f.split('.').next())
                        .unwrap_or_default();
                    let out = Command::new("glslangValidator")
                        .args(["-D", "-V", "-S", "comp", "-e", entry, "-o"])
                        .arg(path.with_extension("hlsl.spv"))
                        .arg(path)
                        .output()
                        .unwrap_or_else(|e| panic!("glslangValidator: {e}"));
                    (!out.status.success()).then(|| {
                        format!(
                            "glslangValidator -D rejects {name} ({}): {}",
                            path.display(),
                            String::from_utf8_lossy(&out.stdout)
                        )
                    })
                })
                .collect::<Vec<_>>(),
        );
    }
    eprintln!(
        "grid: {} variants, {kernel_files} kernel files emitted (5 targets) in {:.1} s; \
         {} distinct SPIR-V through spirv-val{}, {} distinct GLSL through glslangValidator{}, \
         {} distinct HLSL through glslangValidator -D{} ({zero_casts} zero-array casts in \
         {hlsl_rewritten} files given as loops) in {:.1} s",
        variants.len(),
        generated_in.as_secs_f64(),
        spv.len(),
        if spirv_val { "" } else { " (SKIPPED)" },
        comp.len(),
        if glslang { "" } else { " (SKIPPED)" },
        hlsl.len(),
        if glslang { "" } else { " (SKIPPED)" },
        validate_start.elapsed().as_secs_f64(),
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let kernels: usize = variants.iter().map(|v| v.kernel_params().len()).sum();
    assert_eq!(kernel_files, kernels * Target::ALL.len());
}
