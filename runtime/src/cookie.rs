//! The spot light's cookie a `cookie` variant reads (`scatter_shaderlib::cookie`): what every
//! family's runtime type keeps of it and checks.

use scatter_shaderlib::Kernel;

use crate::RuntimeError;

/// The cookie view a family's passes bind as `cookie`, set once and kept until replaced.
#[derive(Debug, Default)]
pub(crate) struct CookieSlot(Option<wgpu::TextureView>);

impl CookieSlot {
    /// Keeps `view` for a variant that `reads` a cookie (`variant` its id, `kernel` the pass
    /// that binds it).
    ///
    /// # Errors
    ///
    /// [`RuntimeError::NoCookie`] when the variant reads none;
    /// [`RuntimeError::InputMismatch`] for a view of the wrong format, dimension or usage.
    pub(crate) fn set(
        &mut self,
        reads: bool,
        variant: String,
        kernel: Kernel,
        view: &wgpu::TextureView,
    ) -> Result<(), RuntimeError> {
        if !reads {
            return Err(RuntimeError::NoCookie { variant });
        }
        crate::textures::check_cookie(kernel, view)?;
        self.0 = Some(view.clone());
        Ok(())
    }

    /// Appends the `cookie` engine texture to `engine` for a variant that `reads` one.
    ///
    /// # Errors
    ///
    /// [`RuntimeError::MissingInput`] when it reads one and none was set.
    pub(crate) fn bind<'a>(
        &'a self,
        reads: bool,
        kernel: Kernel,
        engine: &mut Vec<(&'static str, &'a wgpu::TextureView)>,
    ) -> Result<(), RuntimeError> {
        if reads {
            let view = self.0.as_ref().ok_or(RuntimeError::MissingInput {
                kernel,
                what: "the spot light's cookie (a `cookie` variant: call set_cookie first)",
            })?;
            engine.push(("cookie", view));
        }
        Ok(())
    }
}
