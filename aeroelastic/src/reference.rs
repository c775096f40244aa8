//! Reference sections with their published or closed-form answers (diffsol style): each
//! model carries its reference values and tolerance; one generic checker (in the flutter
//! tests) runs them all. Also the benchmark model of `benches/lco.rs`.

use std::sync::Arc;

use crate::aero::{AeroModel, DerivativeTable, QuasiSteady, QuasiSteadyKind, TheodorsenAero};
use crate::flutter::{FlutterMethod, FlutterOptions};
use crate::section::Section;
use crate::structure::{NondimStructure, PolyTerm, Structure};

/// A flutter test model with its reference answer.
pub struct FlutterCase {
    /// Name (reported on failure).
    pub name: &'static str,
    /// The section (b = 1 m, ω_α = 1 rad/s, ρ = 1 so that U/(bω_α) = U).
    pub section: Section,
    /// Method.
    pub method: FlutterMethod,
    /// Expected U_F/(bω_α).
    pub u_reduced: f64,
    /// Expected ω_F/ω_α (None: not checked).
    pub omega_ratio: Option<f64>,
    /// Expected divergence U_D/(bω_α) (None: not checked).
    pub divergence: Option<f64>,
    /// Relative tolerance.
    pub tol: f64,
}

/// Hodges & Pierce's typical section HP-1 structure (a = −1/5, e = −1/10, x_α = 0.1,
/// μ = 20, r² = 6/25, σ = 2/5), b = 1, ω_α = 1, ρ = 1.
pub fn hp1_structure() -> Structure {
    Structure::from_nondimensional(&NondimStructure {
        mu: 20.0,
        r_alpha2: 6.0 / 25.0,
        sigma: 0.4,
        x_alpha: 0.1,
        semi_chord: 1.0,
        omega_alpha: 1.0,
        rho: 1.0,
        zeta_h: 0.0,
        zeta_alpha: 0.0,
    })
    .expect("valid HP-1")
}

/// Flat plate, elastic axis = mass centre at mid-chord, μ = 20, r² = 0.25, σ = 0.5.
pub fn flat_plate_structure() -> Structure {
    Structure::from_nondimensional(&NondimStructure {
        mu: 20.0,
        r_alpha2: 0.25,
        sigma: 0.5,
        x_alpha: 0.0,
        semi_chord: 1.0,
        omega_alpha: 1.0,
        rho: 1.0,
        zeta_h: 0.0,
        zeta_alpha: 0.0,
    })
    .expect("valid flat plate")
}

/// K grid of the flat-plate derivative table (0.05 … 4.0, step 0.05).
pub fn flat_plate_k_grid() -> Vec<f64> {
    (1..=80).map(|i| 0.05 * i as f64).collect()
}

/// HP-1 section with the exact/Jones Theodorsen model.
pub fn hp1_theodorsen() -> Section {
    let aero: Arc<dyn AeroModel> = Arc::new(TheodorsenAero::new(2.0, -0.2).expect("valid"));
    Section::new(hp1_structure(), aero, 1.0).expect("valid")
}

/// Flat plate from the derivative table (RFA with `n_lag` lags for the time domain).
pub fn flat_plate_table(n_lag: usize) -> Section {
    let aero: Arc<dyn AeroModel> = Arc::new(
        DerivativeTable::flat_plate(2.0, &flat_plate_k_grid(), n_lag).expect("valid table"),
    );
    Section::new(flat_plate_structure(), aero, 1.0).expect("valid")
}

/// Every flutter reference case of DESIGN.md §6.
pub fn flutter_cases() -> Vec<FlutterCase> {
    let steady: Arc<dyn AeroModel> =
        Arc::new(QuasiSteady::new(2.0, -0.2, QuasiSteadyKind::Steady, false).expect("valid"));
    vec![
        FlutterCase {
            name: "HP-1 exact Theodorsen (p-k)",
            section: hp1_theodorsen(),
            method: FlutterMethod::Pk,
            u_reduced: 2.1839,
            omega_ratio: Some(0.6490),
            divergence: Some(2.8284),
            tol: 2e-3,
        },
        FlutterCase {
            name: "HP-1 Jones state space (p)",
            section: hp1_theodorsen(),
            method: FlutterMethod::P,
            u_reduced: 2.1704,
            omega_ratio: Some(0.6443),
            divergence: Some(2.8284),
            tol: 2e-3,
        },
        FlutterCase {
            name: "HP-1 steady aerodynamics (p)",
            section: Section::new(hp1_structure(), steady, 1.0).expect("valid"),
            method: FlutterMethod::P,
            u_reduced: 1.8425,
            omega_ratio: None,
            divergence: Some(2.8284),
            tol: 2e-3,
        },
        FlutterCase {
            name: "flat plate from derivative table (p-k)",
            section: flat_plate_table(4),
            method: FlutterMethod::Pk,
            u_reduced: 2.0054,
            omega_ratio: Some(0.7051),
            divergence: None,
            tol: 2e-3,
        },
    ]
}

/// Options used by the checker: U/(bω_α) from 0.05 to 4 in 80 steps.
pub fn flutter_options() -> FlutterOptions {
    FlutterOptions {
        u_min: 0.05,
        u_max: 4.0,
        n_speeds: 80,
        tol_rel: 1e-9,
    }
}

/// Benchmark / LCO model: HP-1 with Theodorsen–Jones aerodynamics and a cubic hardening
/// pitch spring k_α(α + 10 α³) (supercritical LCO above the Jones flutter speed
/// U/(bω_α) = 2.1704). b = 1 m, ω_α = 1 rad/s, ρ = 1 kg/m³.
pub fn hp1_cubic_pitch() -> Section {
    let mut st = hp1_structure();
    st.nonlinear.pitch_stiffness_terms.push(PolyTerm {
        power: 3,
        coefficient: 10.0 * st.k_alpha,
    });
    let aero: Arc<dyn AeroModel> = Arc::new(TheodorsenAero::new(2.0, -0.2).expect("valid"));
    Section::new(st, aero, 1.0).expect("valid")
}

/// Lee, Price & Wong's section (Prog. Aerosp. Sci. 35, 1999): a = −1/2, x_α = 0.25,
/// r² = 0.25, μ = 100, σ = ω_h/ω_α = 0.2, no structural damping, exact Theodorsen
/// aerodynamics; b = 1 m, ω_α = 1 rad/s, ρ = 1 kg/m³ (so U = U* / 2 with U* = U/(bω_α)…
/// here U is directly U/(bω_α)).
pub fn lpw_theodorsen() -> Section {
    let st = Structure::from_nondimensional(&NondimStructure {
        mu: 100.0,
        r_alpha2: 0.25,
        sigma: 0.2,
        x_alpha: 0.25,
        semi_chord: 1.0,
        omega_alpha: 1.0,
        rho: 1.0,
        zeta_h: 0.0,
        zeta_alpha: 0.0,
    })
    .expect("valid LPW section");
    let aero: Arc<dyn AeroModel> = Arc::new(TheodorsenAero::new(2.0, -0.5).expect("valid"));
    Section::new(st, aero, 1.0).expect("valid")
}
