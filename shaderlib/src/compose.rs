//! Composition (naga_oil) of a rendered kernel with the shared modules in
//! `templates/common/`, and validation (naga) of the result.

use std::collections::HashMap;
use std::error::Error as _;

use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};
use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, NagaModuleDescriptor, ShaderLanguage, ShaderType,
};

use crate::{Kernel, ShaderError};

/// Shared WGSL modules, in dependency order (a module may import only earlier ones).
const COMMON_MODULES: &[(&str, &str)] = &[(
    "common/indexing.wgsl",
    include_str!("../templates/common/indexing.wgsl"),
)];

/// Composes the rendered source of `kernel` with every shared module.
pub(crate) fn compose(kernel: Kernel, source: &str) -> Result<naga::Module, ShaderError> {
    let mut composer = Composer::default();
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
            message: e.emit_to_string(&composer),
        })
}

/// Validates a composed module with every check naga has.
pub(crate) fn validate(kernel: Kernel, module: &naga::Module) -> Result<ModuleInfo, ShaderError> {
    Validator::new(ValidationFlags::all(), Capabilities::default())
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

/// The template file of a kernel, relative to `shaderlib/templates`.
pub(crate) const fn template_path(kernel: Kernel) -> &'static str {
    match kernel {
        Kernel::RowPrefix => "row_prefix.wgsl",
    }
}
