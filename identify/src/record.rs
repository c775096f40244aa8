//! Records in SI per unit span, and their nondimensional regression form.
//!
//! These are the types shared by [`crate::dataset`] (which produces [`Record`]s),
//! [`crate::preprocess`] (which turns them into [`PreparedCase`]s) and the regression
//! modules (which consume [`NondimCase`]s).

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// Geometry and air of the section model (manifest `[section]`), SI.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SectionGeometry {
    /// Chord (deck width) B \[m\].
    pub chord: f64,
    /// Span of the model \[m\]; divides total forces into forces per unit span.
    pub span: f64,
    /// Air density ρ \[kg/m³\].
    pub air_density: f64,
}

/// Kind of a record: prescribed (forced) motion, or free response on springs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum CaseKind {
    /// Prescribed motion; `lift` and `moment` are required.
    Forced,
    /// Free response of the section on springs in the flow.
    Free,
}

/// Descriptors of a case from the manifest, converted to SI.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct CaseMeta {
    /// Unique case id (`[A-Za-z0-9._-]+`).
    pub id: String,
    /// Wind speed U \[m/s\].
    pub wind_speed: f64,
    /// Motion configuration label (paper Table I: "A".."G").
    pub config: Option<String>,
    /// Pitch amplitude \[rad\].
    pub amplitude: Option<f64>,
    /// Heave amplitude / pitch amplitude, mm per deg as in the paper (unit-free label).
    pub amplitude_ratio: Option<f64>,
    /// Prescribed pitch frequency \[Hz\].
    pub freq_pitch: Option<f64>,
    /// Prescribed heave frequency \[Hz\].
    pub freq_heave: Option<f64>,
    /// Mean angle of attack \[rad\].
    pub mean_pitch: Option<f64>,
}

/// One record after unit conversion: SI, forces per unit span, uniform sampling.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Kind of record.
    pub kind: CaseKind,
    /// Manifest descriptors.
    pub meta: CaseMeta,
    /// Time of the first sample \[s\].
    pub t0: f64,
    /// Sample interval \[s\] (least-squares slope of t against row number).
    pub dt: f64,
    /// Heave h \[m\], positive down.
    pub h: Vec<f64>,
    /// Pitch α \[rad\], positive nose-up.
    pub alpha: Vec<f64>,
    /// Lift L \[N/m\], positive down (required for forced cases).
    pub lift: Option<Vec<f64>>,
    /// Moment M about the elastic axis \[N·m/m\], positive nose-up (required for forced cases).
    pub moment: Option<Vec<f64>>,
    /// Still-air run of the same motion (raw balance forces), when the manifest names one.
    pub nowind: Option<Box<Record>>,
    /// The feedback controller's signal of a controlled free-response record
    /// (control-based continuation; DATA_FORMAT.md, "Controlled records"), when the case
    /// file has a `control_raw` or `control_force` column.
    pub control: Option<ControlSignal>,
}

/// The signal of a feedback controller acting on the heave DOF during a record (an
/// electrodynamic shaker on the heave stage, as in control-based continuation): the force
/// it applies is a measured input of the equations of motion, not part of the free response.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlSignal {
    /// `true`: `values` is a calibrated force on the heave DOF \[N/m\], positive in lift's
    /// sense (down, like h), from the `control_force` column. `false`: the controller's raw
    /// output (`control_raw`, uncalibrated units); the force is g·u + o with a gain g
    /// \[N/m per unit\] and offset o \[N/m\] the diagnosis fits.
    pub calibrated: bool,
    /// The signal, one value per sample of the record.
    pub values: Vec<f64>,
    /// The controller's heave target \[m\] (positive down, like h), when recorded
    /// (`h_target`): with h and the signal it lets a feedback law be reconstructed.
    pub h_target: Option<Vec<f64>>,
}

impl Record {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.alpha.len()
    }

    /// True when the record holds no sample.
    pub fn is_empty(&self) -> bool {
        self.alpha.is_empty()
    }

    /// Record duration n·dt \[s\].
    pub fn duration(&self) -> f64 {
        self.len() as f64 * self.dt
    }
}

/// A forced-motion case ready for regression, still dimensional (SI per unit span).
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedCase {
    /// Manifest descriptors.
    pub meta: CaseMeta,
    /// Sample interval \[s\].
    pub dt: f64,
    /// Pitch α \[rad\].
    pub alpha: Vec<f64>,
    /// Pitch rate α̇ \[rad/s\].
    pub alpha_dot: Vec<f64>,
    /// Heave h \[m\].
    pub h: Vec<f64>,
    /// Heave rate ḣ \[m/s\].
    pub h_dot: Vec<f64>,
    /// Aerodynamic lift L \[N/m\] (after wind–no-wind subtraction when applicable).
    pub lift: Vec<f64>,
    /// Aerodynamic moment M \[N·m/m\].
    pub moment: Vec<f64>,
    /// Forcing frequencies (pitch, heave) \[Hz\] refined from the measured motion; `None`
    /// for a degree of freedom without harmonic forcing.
    pub forcing: Forcing,
}

/// Forcing frequencies of a forced-motion case \[Hz\].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct Forcing {
    /// Pitch forcing frequency f_α \[Hz\].
    pub pitch: Option<f64>,
    /// Heave forcing frequency f_h \[Hz\].
    pub heave: Option<f64>,
}

impl Forcing {
    /// The distinct forcing frequencies present \[Hz\] (pitch first).
    pub fn frequencies(&self) -> Vec<f64> {
        let mut f = Vec::with_capacity(2);
        if let Some(p) = self.pitch {
            f.push(p);
        }
        if let Some(h) = self.heave {
            if f.iter().all(|&x| (x - h).abs() > 1e-9 * h.abs().max(1.0)) {
                f.push(h);
            }
        }
        f
    }
}

/// Nondimensional regressors and targets of one case (DESIGN.md §2).
///
/// `x[0] = α`, `x[1] = Bα̇/U`, `x[2] = h/B`, `x[3] = ḣ/U`;
/// `c_lift = L/(½ρU²B)`, `c_moment = M/(½ρU²B²)`.
#[derive(Debug, Clone, PartialEq)]
pub struct NondimCase {
    /// Manifest descriptors.
    pub meta: CaseMeta,
    /// Sample interval \[s\].
    pub dt: f64,
    /// Chord B \[m\].
    pub chord: f64,
    /// The four regression variables (α, Bα̇/U, h/B, ḣ/U).
    pub x: [Vec<f64>; 4],
    /// Lift coefficient C_L (positive down).
    pub c_lift: Vec<f64>,
    /// Moment coefficient C_M (positive nose-up).
    pub c_moment: Vec<f64>,
    /// Forcing frequencies \[Hz\].
    pub forcing: Forcing,
}

impl NondimCase {
    /// Reduced frequency of pitch K_α = Bω_α/U (None without pitch forcing).
    pub fn k_alpha(&self) -> Option<f64> {
        self.forcing
            .pitch
            .map(|f| self.chord * 2.0 * std::f64::consts::PI * f / self.meta.wind_speed)
    }

    /// Reduced frequency of heave K_h = Bω_h/U (None without heave forcing).
    pub fn k_h(&self) -> Option<f64> {
        self.forcing
            .heave
            .map(|f| self.chord * 2.0 * std::f64::consts::PI * f / self.meta.wind_speed)
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.c_lift.len()
    }

    /// True when the case holds no sample.
    pub fn is_empty(&self) -> bool {
        self.c_lift.is_empty()
    }
}

impl PreparedCase {
    /// As [`PreparedCase::nondimensional`], consuming the case: the six series are
    /// converted in place (the same floating-point operations, so the result is bit for bit
    /// the same), so that peak memory holds one set of series instead of two.
    ///
    /// # Errors
    /// As [`PreparedCase::nondimensional`].
    pub fn into_nondimensional(self, section: &SectionGeometry) -> Result<NondimCase> {
        let b = section.chord;
        let u = self.meta.wind_speed;
        let rho = section.air_density;
        // the checks of `nondimensional` (on an empty view: they read no series)
        let check = PreparedCase {
            meta: self.meta.clone(),
            dt: self.dt,
            alpha: Vec::new(),
            alpha_dot: Vec::new(),
            h: Vec::new(),
            h_dot: Vec::new(),
            lift: Vec::new(),
            moment: Vec::new(),
            forcing: self.forcing,
        };
        check.nondimensional(section)?;
        let q = 0.5 * rho * u * u;
        let map = |mut v: Vec<f64>, f: &dyn Fn(f64) -> f64| {
            for x in v.iter_mut() {
                *x = f(*x);
            }
            v
        };
        Ok(NondimCase {
            meta: self.meta,
            dt: self.dt,
            chord: b,
            x: [
                self.alpha,
                map(self.alpha_dot, &|v| b * v / u),
                map(self.h, &|v| v / b),
                map(self.h_dot, &|v| v / u),
            ],
            c_lift: map(self.lift, &|v| v / (q * b)),
            c_moment: map(self.moment, &|v| v / (q * b * b)),
            forcing: self.forcing,
        })
    }

    /// Converts to the nondimensional regression form.
    ///
    /// # Errors
    /// [`Error::InvalidData`] when U ≤ 0 or not finite (no nondimensional form exists),
    /// or when the section has a non-positive chord or air density.
    pub fn nondimensional(&self, section: &SectionGeometry) -> Result<NondimCase> {
        let u = self.meta.wind_speed;
        let bad = |field: &str, message: String| Error::InvalidData {
            case: self.meta.id.clone(),
            field: field.to_string(),
            message,
        };
        if !(u.is_finite() && u > 0.0) {
            return Err(bad(
                "wind_speed",
                format!("{u} m/s: identification needs U > 0"),
            ));
        }
        let b = section.chord;
        if !(b.is_finite() && b > 0.0) {
            return Err(bad("section.chord", format!("{b} m must be > 0")));
        }
        let rho = section.air_density;
        if !(rho.is_finite() && rho > 0.0) {
            return Err(bad(
                "section.air_density",
                format!("{rho} kg/m^3 must be > 0"),
            ));
        }
        let q = 0.5 * rho * u * u;
        Ok(NondimCase {
            meta: self.meta.clone(),
            dt: self.dt,
            chord: b,
            x: [
                self.alpha.clone(),
                self.alpha_dot.iter().map(|v| b * v / u).collect(),
                self.h.iter().map(|v| v / b).collect(),
                self.h_dot.iter().map(|v| v / u).collect(),
            ],
            c_lift: self.lift.iter().map(|v| v / (q * b)).collect(),
            c_moment: self.moment.iter().map(|v| v / (q * b * b)).collect(),
            forcing: self.forcing,
        })
    }
}
