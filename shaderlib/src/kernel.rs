//! The kernel table's macro: [`Kernel`] (one variant per WGSL template, named like its
//! template file, its CPU mirror `reference/src/kernels/<name>.rs` and its conformance
//! trials), [`KernelParams`](crate::KernelParams) (a kernel with the parameters it is
//! rendered with) and [`render`](crate::render) all come from one line per kernel in
//! `lib.rs`'s `kernels!` table.

use std::fmt;

/// Defines `Kernel`, `KernelParams` and `render` from the table: one line per kernel,
/// `Name("stem", ParameterType, render function)` with its doc comment; the stem is the
/// template file stem, entry point, mirror module and trial name, and the serde name of both
/// enums.
macro_rules! kernels {
    ($($(#[$doc:meta])* $name:ident($stem:literal, $params:ty, $render:path)),* $(,)?) => {
        /// Every kernel the library ships. Matches on it must stay exhaustive, so that a new
        /// kernel cannot be added without its template, CPU mirror and tests.
        #[derive(
            Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize,
            serde::Deserialize,
        )]
        #[serde(rename_all = "snake_case")]
        pub enum Kernel {
            $($(#[$doc])* $name,)*
        }

        impl Kernel {
            /// All kernels, in table order (sorted by name).
            pub const ALL: &'static [Self] = &[$(Self::$name,)*];

            /// The kernel's name: template file stem, entry point, mirror module and trial
            /// name.
            pub const fn name(self) -> &'static str {
                match self {
                    $(Self::$name => $stem,)*
                }
            }

            /// The kernel's askama template, relative to `templates/`.
            pub const fn template(self) -> &'static str {
                match self {
                    $(Self::$name => concat!($stem, ".wgsl"),)*
                }
            }
        }

        /// A kernel together with the template parameters it is rendered with.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
        #[serde(tag = "kernel", rename_all = "snake_case")]
        pub enum KernelParams {
            $(
                #[doc = concat!("`", $stem, "` with its parameters.")]
                $name($params),
            )*
        }

        impl KernelParams {
            /// The kernel these parameters belong to.
            pub fn kernel(&self) -> Kernel {
                match self {
                    $(Self::$name(_) => Kernel::$name,)*
                }
            }
        }

        /// Renders a kernel's askama template to WGSL source that still contains naga_oil
        /// `#import` directives (the input of composition).
        ///
        /// # Errors
        ///
        /// [`ShaderError::InvalidParameter`] or [`ShaderError::Variant`] for out-of-range
        /// parameters, [`ShaderError::Render`] when askama fails.
        pub fn render(params: &KernelParams) -> Result<String, ShaderError> {
            match params {
                $(KernelParams::$name(p) => $render(p),)*
            }
        }
    };
}

pub(crate) use kernels;

impl fmt::Display for crate::Kernel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
