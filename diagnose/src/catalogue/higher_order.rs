//! `higher_order`: force terms outside the Eq. 19 library (quintic, cross-DOF…):
//! harmonics beyond the third, amplitude dependence steeper than cubic.
//!
//! * Force level: forward selection of up to [`MAX_SPARSE`] terms from a pool of degree-4
//!   and degree-5 monomials outside the cubic library (quintic in α, Bα̇/U; quartic
//!   cross-DOF), each step kept only when it lowers the training residual by more than
//!   [`crate::force::candidates::STEP_GAIN`] noise units.
//! * Generator: moment terms of degree 4 and 5 with coefficient c from −0.05 to −20.

use aeroelastic::effects::{Form, InjectedEffect};
use identify::library::Term;

use super::entry::{Draw, DrawContext, Entry};
use super::Level;
use crate::force::candidates::{sparse, Context, ForceFit, PoolColumn, Scored};
use crate::force::data::CaseData;

/// Largest number of terms of the selection.
pub const MAX_SPARSE: usize = 3;

/// The `higher_order` entry.
pub(crate) struct HigherOrder;

impl Entry for HigherOrder {
    fn name(&self) -> &'static str {
        "higher_order"
    }
    fn short_label(&self) -> &'static str {
        "h.order"
    }
    fn level(&self) -> Level {
        Level::Aerodynamic
    }
    fn force(&self) -> Option<&dyn ForceFit> {
        Some(self)
    }
    fn draw(&self) -> Option<&dyn Draw> {
        Some(self)
    }
}

/// A monomial column of the pool.
struct Mono(Term);

impl PoolColumn for Mono {
    fn name(&self) -> String {
        self.0.name()
    }
    fn column(&self, c: &CaseData) -> Vec<f64> {
        c.column(&self.0).to_vec()
    }
}

impl ForceFit for HigherOrder {
    fn fit(&self, cx: &Context<'_>) -> Scored {
        sparse(cx, &pool(), MAX_SPARSE, 1)
    }
}

/// Pool of the forward selection: monomials of degree 4–5 outside the cubic library
/// (quintic in α, Bα̇/U; quartic cross-DOF; odd in the pitch variables).
fn pool() -> Vec<Mono> {
    let p = |a, b, c, d| Mono(Term::new([a, b, c, d]));
    vec![
        p(5, 0, 0, 0),
        p(4, 1, 0, 0),
        p(3, 2, 0, 0),
        p(2, 3, 0, 0),
        p(1, 4, 0, 0),
        p(0, 5, 0, 0),
        p(3, 0, 1, 0),
        p(3, 0, 0, 1),
        p(2, 1, 1, 0),
        p(2, 1, 0, 1),
        p(1, 0, 3, 0),
        p(1, 2, 1, 0),
    ]
}

impl Draw for HigherOrder {
    fn range(&self, _form: Form) -> (&'static str, f64, f64) {
        ("c [-]", -0.05, -20.0)
    }
    fn inject(
        &self,
        p: f64,
        _s: f64,
        _form: Form,
        _cx: &DrawContext,
    ) -> (InjectedEffect, Vec<(String, f64)>) {
        (
            InjectedEffect::HigherOrder { c: p },
            Vec::new(),
        )
    }
}
