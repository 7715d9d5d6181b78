//! Every kernel's emitted SPIR-V, for both lights, both rectifications and every storage
//! format (prefiltered) and the raymarch grid, parses with naga's SPIR-V front-end and validates: what wgpu does with
//! `ShaderSource::SpirV` (`examples/foreign_engine` loads the files that way). naga 30's
//! back-end alone fails this (a signed constant in an unsigned vector, see
//! `src/spirv_fixup.rs`); spirv-val 2023.1 does not notice.

use scatter_gen::{FamilyVariant, Request, Target, generate};
use scatter_shaderlib::prefiltered::{LightKind, PrefilteredVariant, Rectification, Storage};
use scatter_shaderlib::sampling::Sampling;

#[test]
fn emitted_spirv_passes_naga_spirv_front_end() {
    let mut variants = Vec::new();
    for &light in LightKind::SINGLE {
        for &rectification in Rectification::ALL {
            for &storage in Storage::ALL {
                variants.push(FamilyVariant::Prefiltered(PrefilteredVariant {
                    light,
                    rectification,
                    storage,
                    ..PrefilteredVariant::default()
                }));
            }
        }
    }
    variants.extend(
        scatter_shaderlib::raymarch::RaymarchVariant::grid()
            .into_iter()
            .map(FamilyVariant::Raymarch),
    );
    // Every family with a per-pixel mode sampled (lowres and epipolar: workgroup memory,
    // atomics, the unwarp passes), both lights; `partial_sum_tree` (epipolar only) over its
    // grid (ranks 1, 4, 8: one and two vec4 per leaf); area_ivsv over its grid.
    variants.extend(
        scatter_shaderlib::area_ivsv::AreaIvsvVariant::grid()
            .into_iter()
            .map(FamilyVariant::AreaIvsv),
    );
    variants.extend(
        scatter_shaderlib::partial_sum_tree::PartialSumTreeVariant::grid()
            .into_iter()
            .map(FamilyVariant::PartialSumTree),
    );
    for light in LightKind::SINGLE.iter().copied().chain([LightKind::Area]) {
        for family in scatter_shaderlib::family::Family::ALL
            .iter()
            .filter(|f| f.default_variant().sampling().sampling == Sampling::Pixels)
        {
            for knobs in [
                scatter_shaderlib::sampling::SamplingKnobs::lowres(4),
                scatter_shaderlib::sampling::SamplingKnobs::epipolar(64),
            ] {
                // Families of another light are left out (area_ivsv takes only `area`).
                let v = family
                    .default_variant()
                    .with_light(light)
                    .with_sampling(knobs);
                if v.validate().is_ok() {
                    variants.push(v);
                }
            }
        }
    }
    let generated = generate(&Request {
        variants,
        targets: vec![Target::Spirv],
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let mut checked = 0;
    for file in generated.files.iter().filter(|f| f.path.ends_with(".spv")) {
        let module =
            naga::front::spv::parse_u8_slice(&file.bytes, &naga::front::spv::Options::default())
                .unwrap_or_else(|e| panic!("{}: naga spv-in: {e:?}", file.path));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|e| {
            panic!(
                "{}: naga validation after spv-in: {e:?}\nfunctions: {:?}",
                file.path,
                module
                    .functions
                    .iter()
                    .map(|(h, f)| (h.index(), f.name.clone()))
                    .collect::<Vec<_>>()
            )
        });
        checked += 1;
    }
    assert!(checked >= 3 * 2 * 2 * 3 - 12, "only {checked} SPIR-V files");
    eprintln!("{checked} SPIR-V files through naga's SPIR-V front-end");
}
