//! Parameters valid by construction.
//!
//! An algorithm that runs many times with the same parameters (a fit per
//! segment, a count per window) takes them as [`Checked<P>`]: parameters
//! that [`Validate::validate`] accepted. The only way to make one is
//! [`Validate::check`], so a function that takes `&Checked<P>` needs no
//! check of its own and no unchecked twin.
//!
//! ```
//! use mp_geom::Validate;
//! use mp_geom::{fit_best_checked, FitParams};
//! use ndarray::array;
//!
//! let params = FitParams::default().check()?;
//! // Three points on a line, 100 reference pixels apart.
//! let points = array![[0.0, 0.0], [100.0, 100.0], [200.0, 200.0]];
//! let fit = fit_best_checked(points.view(), None, &params)?;
//! assert!(fit.error < 1e-6, "{}", fit.error);
//! # Ok::<(), mp_geom::GeomError>(())
//! ```

use std::ops::Deref;

/// Parameters with a check of every field.
pub trait Validate: Sized {
    /// What a failed check returns.
    type Error;

    /// Checks every field; the error names the first field that is wrong.
    fn validate(&self) -> Result<(), Self::Error>;

    /// The parameters as [`Checked`] once [`Self::validate`] accepts them.
    fn check(self) -> Result<Checked<Self>, Self::Error> {
        self.validate()?;
        Ok(Checked(self))
    }
}

/// Borrowed parameters check as their owner does: `(&params).check()?`
/// gives a `Checked<&P>` without copying them.
impl<P: Validate> Validate for &P {
    type Error = P::Error;

    fn validate(&self) -> Result<(), Self::Error> {
        (**self).validate()
    }
}

/// Parameters that [`Validate::validate`] accepted; read them through
/// `Deref`. Made only by [`Validate::check`].
#[derive(Debug, Clone, PartialEq)]
pub struct Checked<P>(P);

impl<P> Checked<P> {
    /// The parameters themselves, to change and check again.
    pub fn into_inner(self) -> P {
        self.0
    }
}

impl<P> Deref for Checked<P> {
    type Target = P;

    fn deref(&self) -> &P {
        &self.0
    }
}
