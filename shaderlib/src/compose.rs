//! Composition (naga_oil) of a rendered kernel with the shared modules in
//! `templates/common/`, and validation (naga) of the result.

use std::cell::RefCell;
use std::collections::HashMap;
use std::error::Error as _;

use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};
use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, NagaModuleDescriptor, ShaderLanguage, ShaderType,
};

use crate::{Kernel, ShaderError};

/// Shared WGSL modules, in dependency order (a module may import only earlier ones).
const COMMON_MODULES: &[(&str, &str)] = &[
    (
        "common/indexing.wgsl",
        include_str!("../templates/common/indexing.wgsl"),
    ),
    (
        "common/model.wgsl",
        include_str!("../templates/common/model.wgsl"),
    ),
    (
        "common/shadow.wgsl",
        include_str!("../templates/common/shadow.wgsl"),
    ),
    (
        "common/raymarch.wgsl",
        include_str!("../templates/common/raymarch.wgsl"),
    ),
    (
        "common/epipolar.wgsl",
        include_str!("../templates/common/epipolar.wgsl"),
    ),
    (
        "common/projective.wgsl",
        include_str!("../templates/common/projective.wgsl"),
    ),
    (
        "common/prefiltered.wgsl",
        include_str!("../templates/common/prefiltered.wgsl"),
    ),
    (
        "common/moments.wgsl",
        include_str!("../templates/common/moments.wgsl"),
    ),
    (
        "common/prefiltered_projective.wgsl",
        include_str!("../templates/common/prefiltered_projective.wgsl"),
    ),
    (
        "common/minmax.wgsl",
        include_str!("../templates/common/minmax.wgsl"),
    ),
    (
        "common/sampling.wgsl",
        include_str!("../templates/common/sampling.wgsl"),
    ),
    (
        "common/cookie.wgsl",
        include_str!("../templates/common/cookie.wgsl"),
    ),
    (
        "common/ivsv.wgsl",
        include_str!("../templates/common/ivsv.wgsl"),
    ),
];

thread_local! {
    /// A composer with every shared module added, built once per thread: adding the shared
    /// modules costs more than composing a kernel, and the generator and the tests build
    /// thousands of kernels.
    static COMPOSER: RefCell<Option<Composer>> = const { RefCell::new(None) };
}

/// The naga capabilities a kernel may use: naga's default and `SHADER_FLOAT16_IN_FLOAT32`
/// (`pack2x16float` / `unpack2x16float`: the rgba16float `filtered` buffer of the prefiltered
/// family), which wgpu grants with `DownlevelFlags::SHADER_F16_IN_F32` (Vulkan, Metal and
/// DX12 devices have it; GLSL ES 3.0 has `packHalf2x16`).
pub fn capabilities() -> Capabilities {
    Capabilities::default() | Capabilities::SHADER_FLOAT16_IN_FLOAT32
}

/// A fresh composer with every shared module of [`COMMON_MODULES`] added.
fn new_composer(kernel: Kernel) -> Result<Composer, ShaderError> {
    let mut composer = Composer::default().with_capabilities(capabilities());
    for &(file, common) in COMMON_MODULES {
        composer
            .add_composable_module(ComposableModuleDescriptor {
                source: common,
                file_path: file,
                language: ShaderLanguage::Wgsl,
                as_name: None,
                additional_imports: &[],
                shader_defs: HashMap::new(),
            })
            .map(|_| ())
            .map_err(|e| ShaderError::Compose {
                kernel,
                file,
                message: e.emit_to_string(&composer),
            })?;
    }
    Ok(composer)
}

/// Composes the rendered source of `kernel` with every shared module.
pub(crate) fn compose(kernel: Kernel, source: &str) -> Result<naga::Module, ShaderError> {
    COMPOSER.with(|cell| {
        let mut cached = cell.borrow_mut();
        let composer = match &mut *cached {
            Some(composer) => composer,
            empty => empty.insert(new_composer(kernel)?),
        };
        let result = make_module(composer, kernel, source);
        if result.is_err() {
            // Start the next kernel from a fresh composer, whatever state the failure left.
            *cached = None;
        }
        result
    })
}

/// Composes `source` with the shared modules already in `composer`.
fn make_module(
    composer: &mut Composer,
    kernel: Kernel,
    source: &str,
) -> Result<naga::Module, ShaderError> {
    let file = template_path(kernel);
    composer
        .make_naga_module(NagaModuleDescriptor {
            source,
            file_path: file,
            shader_type: ShaderType::Wgsl,
            shader_defs: HashMap::new(),
            additional_imports: &[],
        })
        .map_err(|e| ShaderError::Compose {
            kernel,
            file,
            message: e.emit_to_string(composer),
        })
}

/// Validates a composed module with every check naga has.
pub(crate) fn validate(kernel: Kernel, module: &naga::Module) -> Result<ModuleInfo, ShaderError> {
    Validator::new(ValidationFlags::all(), capabilities())
        .validate(module)
        .map_err(|e| {
            let mut message = e.as_inner().to_string();
            let mut cause = e.as_inner().source();
            while let Some(c) = cause {
                message.push_str(": ");
                message.push_str(&c.to_string());
                cause = c.source();
            }
            ShaderError::Validate { kernel, message }
        })
}

/// The template file of a kernel, relative to `shaderlib/templates` (from the kernel table).
pub(crate) const fn template_path(kernel: Kernel) -> &'static str {
    kernel.template()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prefiltered::{LightKind, PrefilteredVariant};
    use crate::{KernelParams, render};

    fn wgsl(module: &naga::Module) -> String {
        let info = validate(Kernel::Scatter, module).expect("valid");
        naga::back::wgsl::write_string(module, &info, naga::back::wgsl::WriterFlags::empty())
            .expect("writes")
    }

    /// The per-thread cached composer gives the same module as a fresh one, whatever was
    /// composed before, and survives a failed composition.
    #[test]
    fn cached_composer_matches_a_fresh_one() {
        let spot = PrefilteredVariant {
            light: LightKind::Spot,
            ..PrefilteredVariant::default()
        };
        let mut all = KernelParams::all_modes();
        all.extend(KernelParams::prefiltered(spot));
        assert!(compose(Kernel::Scatter, "fn broken( {").is_err());
        for params in all.iter().chain(all.iter().rev()) {
            let kernel = params.kernel();
            let source = render(params).expect("renders");
            let cached = compose(kernel, &source).expect("composes");
            let mut fresh = new_composer(kernel).expect("shared modules compose");
            let fresh = make_module(&mut fresh, kernel, &source).expect("composes");
            assert_eq!(wgsl(&cached), wgsl(&fresh), "{kernel}");
        }
    }
}
