//! Thin adapters from the result types of `identify` and `aeroelastic` to the figure
//! structs of this crate: no computation beyond unit conversion, selection and labelling.
//!
//! - [`identification`]: time series with model overlay and spectra with key frequencies
//!   (from [`identify::series::CaseSeries`]), δ path, coefficient heat maps per
//!   configuration, R²/MFWA histograms and derivative curves H*(K), A*(K) with the
//!   flat-plate reference (from [`identify::pipeline::Identification`]).
//! - [`aeroelastic`](mod@self::aeroelastic): V–g / V–f from a
//!   [`::aeroelastic::flutter::FlutterAnalysis`], bifurcation diagram from LCO sweeps,
//!   phase portraits from [`::aeroelastic::trajectory::Trajectory`].
//!
//! Labels never use combining diacritics (the bundled font renderer does not place them):
//! a time derivative is written with a prime, `Bα'/U`, `h'/U`, `dα/dt`.

pub mod aeroelastic;
pub mod diagnosis;
pub mod identification;

pub use study::documents::term_label;

/// Label of an Eq. 19 coefficient (`"A2"` → `"A2*"`; `N` terms keep their channel:
/// `("lift", "N1")` → `"N1* (lift)"` is left to the caller; this only appends the star).
pub fn eq19_label(name: &str) -> String {
    format!("{name}*")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn term_labels_have_no_combining_marks() {
        for name in [
            "alpha",
            "alpha_dot",
            "h",
            "h_dot",
            "alpha*alpha_dot",
            "alpha^3",
            "alpha_dot^3",
            "alpha*h*h_dot",
            "alpha_dot^2*h",
            "1",
        ] {
            let l = term_label(name);
            assert!(
                !l.chars().any(|c| ('\u{300}'..='\u{36f}').contains(&c)),
                "{name} → {l}"
            );
        }
        assert_eq!(term_label("alpha_dot"), "Bα'/U");
        assert_eq!(term_label("h_dot^2"), "(h'/U)²");
        assert_eq!(term_label("alpha*h*h_dot"), "α·h/B·h'/U");
        assert_eq!(eq19_label("A2"), "A2*");
    }
}
