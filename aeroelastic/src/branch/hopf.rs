//! Hopf points of the equilibrium: its Jacobian, the exact quadratic fit A(U) of linear
//! models ([`QuadraticJacobian`]), the scan of det(2A⊙I) ([`Bialternate`]) and the
//! regula-falsi solution of each bracket ([`Section::hopf_points`]).

use nalgebra::DMatrix;
use num_complex::Complex64;

use super::floquet::eigenvalues6;
use super::types::HopfPoint;
use crate::dynamics::SectionDynamics;
use crate::flutter::{eigenvalues, eigenvector};
use crate::section::Section;
use crate::{Error, Result};

/// The equilibrium Jacobian A(U) (row-major, [`Section::equilibrium_jacobian`]) as the
/// quadratic A₀ + U A₁ + U² A₂ through its values at `nodes`, when it is one: checked at a
/// fourth speed to 1e-8 of A's largest entry, and the total mass M_s − M_a the same at all
/// four (then (M_s − M_a)⁻¹ is constant too). Linear aerodynamic models in dimensional form
/// (Theodorsen, Theodorsen–Jones, RFA tables, quasi-steady) are exactly quadratic in U:
/// stiffness ∝ U², damping and lag rates ∝ U, apparent mass constant. `None` otherwise.
pub(crate) struct QuadraticJacobian {
    n: usize,
    coef: [Vec<f64>; 3],
}

impl QuadraticJacobian {
    pub(crate) fn fit(section: &Section, nodes: [f64; 3], check: f64) -> Result<Option<Self>> {
        let n = section.n_states();
        let jac = |u: f64| -> Result<Vec<f64>> {
            let mut a = vec![0.0; n * n];
            SectionDynamics::new(section, u)?.jacobian(
                &vec![0.0; n],
                &mut a,
                &mut vec![0.0; 3 * n],
            );
            Ok(a)
        };
        let m0 = section.total_mass(nodes[0]);
        for u in [nodes[1], nodes[2], check] {
            if (section.total_mass(u) - m0).amax() > 1e-12 * m0.amax() {
                return Ok(None);
            }
        }
        let vals = [jac(nodes[0])?, jac(nodes[1])?, jac(nodes[2])?];
        // Lagrange → monomial coefficients per entry.
        let [u0, u1, u2] = nodes;
        let d0 = (u0 - u1) * (u0 - u2);
        let d1 = (u1 - u0) * (u1 - u2);
        let d2 = (u2 - u0) * (u2 - u1);
        let mut coef = [vec![0.0; n * n], vec![0.0; n * n], vec![0.0; n * n]];
        for i in 0..n * n {
            let (y0, y1, y2) = (vals[0][i] / d0, vals[1][i] / d1, vals[2][i] / d2);
            coef[2][i] = y0 + y1 + y2;
            coef[1][i] = -(y0 * (u1 + u2) + y1 * (u0 + u2) + y2 * (u0 + u1));
            coef[0][i] = y0 * u1 * u2 + y1 * u0 * u2 + y2 * u0 * u1;
        }
        let q = QuadraticJacobian { n, coef };
        let direct = jac(check)?;
        let scale = direct.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut fitted = vec![0.0; n * n];
        q.at(check, &mut fitted);
        let exact = direct
            .iter()
            .zip(&fitted)
            .all(|(a, b)| (a - b).abs() <= 1e-8 * scale);
        Ok(exact.then_some(q))
    }

    /// dA/dU = A₁ + 2U A₂ into `a` (n × n row-major).
    pub(crate) fn derivative_at(&self, u: f64, a: &mut [f64]) {
        for (i, v) in a.iter_mut().enumerate().take(self.n * self.n) {
            *v = self.coef[1][i] + 2.0 * u * self.coef[2][i];
        }
    }

    /// A(U) into `a` (n × n row-major).
    pub(crate) fn at(&self, u: f64, a: &mut [f64]) {
        for (i, v) in a.iter_mut().enumerate().take(self.n * self.n) {
            *v = self.coef[0][i] + u * (self.coef[1][i] + u * self.coef[2][i]);
        }
    }
}

/// The bialternate product 2A⊙I of an n × n matrix with the identity, as the list of its
/// non-zero entries: eigenvalues λ_i + λ_j (i < j), so det(2A⊙I) vanishes where a complex
/// pair of A crosses the imaginary axis (Hopf) and not where a real eigenvalue crosses zero
/// (Govaerts 2000, Kuznetsov §10.2). Rows and columns are the pairs (p, q), p > q.
struct Bialternate {
    /// Order m = n(n − 1)/2.
    m: usize,
    /// (row · m + column, sign, first entry of A, second entry of A or usize::MAX).
    entries: Vec<(usize, f64, usize, usize)>,
}

impl Bialternate {
    fn new(n: usize) -> Self {
        let pairs: Vec<(usize, usize)> = (1..n).flat_map(|p| (0..p).map(move |q| (p, q))).collect();
        let m = pairs.len();
        let at = |r: usize, c: usize| r * n + c;
        let mut entries = Vec::new();
        for (i, &(p, q)) in pairs.iter().enumerate() {
            for (j, &(r, s)) in pairs.iter().enumerate() {
                let e = if r == q {
                    Some((-1.0, at(p, s), usize::MAX))
                } else if r != p && s == q {
                    Some((1.0, at(p, r), usize::MAX))
                } else if r == p && s == q {
                    Some((1.0, at(p, p), at(q, q)))
                } else if r == p && s != q {
                    Some((1.0, at(q, s), usize::MAX))
                } else if s == p {
                    Some((-1.0, at(q, r), usize::MAX))
                } else {
                    None
                };
                if let Some((sign, a1, a2)) = e {
                    entries.push((i * m + j, sign, a1, a2));
                }
            }
        }
        Bialternate { m, entries }
    }

    /// det(2A⊙I) for `a` (row-major) by Gaussian elimination with partial pivoting in
    /// `work` (m × m).
    fn determinant(&self, a: &[f64], work: &mut Vec<f64>) -> f64 {
        let m = self.m;
        work.clear();
        work.resize(m * m, 0.0);
        for &(k, sign, a1, a2) in &self.entries {
            work[k] = sign * a[a1] + if a2 == usize::MAX { 0.0 } else { a[a2] };
        }
        let b = work;
        let mut det = 1.0;
        for k in 0..m {
            let mut piv = k;
            for i in k + 1..m {
                if b[i * m + k].abs() > b[piv * m + k].abs() {
                    piv = i;
                }
            }
            if b[piv * m + k] == 0.0 {
                return 0.0;
            }
            if piv != k {
                for c in 0..m {
                    b.swap(k * m + c, piv * m + c);
                }
                det = -det;
            }
            let d = b[k * m + k];
            det *= d;
            let (top, rest) = b.split_at_mut((k + 1) * m);
            let pivot_row = &top[k * m + k + 1..(k + 1) * m];
            for row in rest.chunks_exact_mut(m) {
                let f = row[k] / d;
                if f != 0.0 {
                    for (x, p) in row[k + 1..].iter_mut().zip(pivot_row) {
                        *x -= f * p;
                    }
                }
            }
        }
        det
    }
}

impl Section {
    /// Jacobian of [`SectionDynamics::rate`] at the origin at speed `u` (central
    /// differences; consistent with the nonlinear rate, including regularised friction).
    ///
    /// # Errors
    /// As [`SectionDynamics::new`].
    pub fn equilibrium_jacobian(&self, u: f64) -> Result<DMatrix<f64>> {
        let d = SectionDynamics::new(self, u)?;
        let n = d.dim();
        let mut j = vec![0.0; n * n];
        d.jacobian(&vec![0.0; n], &mut j, &mut vec![0.0; 3 * n]);
        Ok(DMatrix::from_row_slice(n, n, &j))
    }

    /// Largest real part of the oscillatory eigenvalues (|Im| > 1e-6 ω_α) of the
    /// equilibrium at `u`, and the eigenvalue.
    pub(super) fn oscillatory_growth(&self, u: f64) -> Result<(f64, Complex64)> {
        let jac = self.equilibrium_jacobian(u)?;
        let ev = match jac.nrows() {
            6 => eigenvalues6(&jac)?,
            _ => eigenvalues(&jac)?,
        };
        let floor = 1e-6 * self.structure.omega_alpha();
        ev.into_iter()
            .filter(|l| l.im > floor)
            .map(|l| (l.re, l))
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .ok_or_else(|| Error::numerical("hopf", format!("no oscillatory mode at U = {u}")))
    }

    /// The speed in [a, b] where the growth rate, of opposite signs `ga` and `gb` at the
    /// ends, vanishes: regula falsi with the Illinois modification (superlinear on the
    /// smooth growth rate, the bracket kept), to a bracket of 1e-12 U or a growth rate
    /// below 1e-15 ω_α.
    fn growth_root(&self, mut a: f64, mut ga: f64, mut b: f64, mut gb: f64) -> Result<f64> {
        let tiny = 1e-15 * self.structure.omega_alpha();
        let mut side = 0;
        for _ in 0..200 {
            if b - a <= 1e-12 * b {
                break;
            }
            let mut m = (a * gb - b * ga) / (gb - ga);
            if !(m > a && m < b) {
                m = 0.5 * (a + b);
            }
            let gm = self.oscillatory_growth(m)?.0;
            if gm.abs() <= tiny {
                return Ok(m);
            }
            if (gm < 0.0) == (ga < 0.0) {
                (a, ga) = (m, gm);
                if side == -1 {
                    gb *= 0.5;
                }
                side = -1;
            } else {
                (b, gb) = (m, gm);
                if side == 1 {
                    ga *= 0.5;
                }
                side = 1;
            }
        }
        Ok(if ga.abs() < gb.abs() { a } else { b })
    }

    /// Hopf points of the equilibrium in [`u_min`, `u_max`] [m/s]: the largest real part
    /// of the oscillatory eigenvalues of [`Section::equilibrium_jacobian`] is scanned at
    /// `n_scan` speeds and each sign change solved to 1e-12 U (Illinois regula falsi).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a bad range; as [`Section::equilibrium_jacobian`].
    pub fn hopf_points(&self, u_min: f64, u_max: f64, n_scan: usize) -> Result<Vec<HopfPoint>> {
        crate::error::positive("u_min", u_min)?;
        if !(u_max.is_finite() && u_max > u_min) {
            return Err(Error::param(
                "u_max",
                u_max,
                format!("must be > u_min = {u_min}"),
            ));
        }
        let n_scan = n_scan.max(2);
        let us: Vec<f64> = (0..n_scan)
            .map(|i| u_min + (u_max - u_min) * i as f64 / (n_scan - 1) as f64)
            .collect();
        // Scan the sign of det(2A⊙I) = Π_{i<j}(λ_i + λ_j), which changes where a complex
        // pair crosses the imaginary axis; the growth rate (eigenvalues) only at the ends of
        // brackets where it does. Its n(n − 1)/2 rows outgrow an eigenvalue problem beyond
        // n = 8 states: there the growth rate itself is scanned.
        let n = self.n_states();
        let (mut a, mut work, origin) = (vec![0.0; n * n], vec![0.0; 3 * n], vec![0.0; n]);
        let mut b = Vec::new();
        let bialternate = Bialternate::new(n);
        let mut psi = Vec::with_capacity(n_scan);
        let quadratic = if n <= 8 {
            QuadraticJacobian::fit(
                self,
                [u_min, 0.5 * (u_min + u_max), u_max],
                0.3 * u_min + 0.7 * u_max,
            )?
        } else {
            None
        };
        for &u in &us {
            psi.push(if n <= 8 {
                match &quadratic {
                    Some(q) => q.at(u, &mut a),
                    None => SectionDynamics::new(self, u)?.jacobian(&origin, &mut a, &mut work),
                }
                bialternate.determinant(&a, &mut b)
            } else {
                self.oscillatory_growth(u)?.0
            });
        }
        let mut out = Vec::new();
        for i in 1..n_scan {
            if (psi[i - 1] < 0.0) == (psi[i] < 0.0) && psi[i - 1] != 0.0 {
                continue;
            }
            let g = [
                self.oscillatory_growth(us[i - 1])?.0,
                self.oscillatory_growth(us[i])?.0,
            ];
            if (g[0] < 0.0) == (g[1] < 0.0) {
                continue;
            }
            let u = self.growth_root(us[i - 1], g[0], us[i], g[1])?;
            let (_, lam) = self.oscillatory_growth(u)?;
            let jac = self.equilibrium_jacobian(u)?;
            let v = eigenvector(&jac, lam);
            if v[1].norm() < 1e-8 * v.norm() {
                return Err(Error::numerical(
                    "hopf",
                    format!("Hopf mode at U = {u} m/s has no pitch motion"),
                ));
            }
            let v1 = v[1];
            let du = 1e-6 * u;
            let dsig = (self.oscillatory_growth(u + du)?.0 - self.oscillatory_growth(u - du)?.0)
                / (2.0 * du);
            out.push(HopfPoint {
                u,
                omega: lam.im,
                dsigma_du: dsig,
                eigenvector: v.iter().map(|c| c / v1).collect(),
            });
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flutter::{FlutterMethod, FlutterOptions};
    use crate::reference::hp1_cubic_pitch;

    /// det(2A⊙I) = Π_{i<j}(λ_i + λ_j) on a non-symmetric matrix with complex eigenvalues.
    #[test]
    fn bialternate_determinant_is_the_product_of_eigenvalue_pair_sums() {
        let a = DMatrix::from_fn(6, 6, |i, j| {
            ((i * 7 + j * 3) % 11) as f64 * 0.3 - 1.1 + (i == j) as u8 as f64 * 0.2 * i as f64
        });
        let ev = eigenvalues(&a).unwrap();
        let mut prod = Complex64::new(1.0, 0.0);
        for i in 0..6 {
            for j in 0..i {
                prod *= ev[i] + ev[j];
            }
        }
        let d = Bialternate::new(6).determinant(a.transpose().as_slice(), &mut Vec::new());
        assert!(prod.im.abs() < 1e-9 * prod.norm(), "{prod}");
        assert!((d - prod.re).abs() < 1e-9 * prod.norm(), "{d} vs {prod}");
        assert!(ev.iter().any(|l| l.im.abs() > 1e-3), "{ev:?}");
    }

    /// Theodorsen's A(U) is exactly quadratic in U: the fit reproduces the central-difference
    /// Jacobian at other speeds; a K-dependent law is not, and gets no fit.
    #[test]
    fn linear_models_have_a_quadratic_equilibrium_jacobian() {
        let s = hp1_cubic_pitch();
        let q = QuadraticJacobian::fit(&s, [1.0, 2.0, 3.0], 2.4)
            .unwrap()
            .expect("Theodorsen is quadratic in U");
        let n = s.n_states();
        let mut a = vec![0.0; n * n];
        for u in [0.7, 1.7, 3.9] {
            q.at(u, &mut a);
            let direct = s.equilibrium_jacobian(u).unwrap();
            let scale = direct.amax();
            for r in 0..n {
                for c in 0..n {
                    assert!(
                        (a[r * n + c] - direct[(r, c)]).abs() < 1e-8 * scale,
                        "U {u}: A[{r}][{c}] {} vs {}",
                        a[r * n + c],
                        direct[(r, c)]
                    );
                }
            }
        }
    }

    #[test]
    fn hopf_point_is_the_linear_flutter_speed() {
        let s = hp1_cubic_pitch();
        let h = s.hopf_points(1.0, 3.0, 50).unwrap();
        let fo = FlutterOptions {
            u_min: 0.05,
            u_max: 4.0,
            n_speeds: 80,
            tol_rel: 1e-10,
        };
        let f = s.flutter(FlutterMethod::P, &fo).unwrap().flutter.unwrap();
        assert_eq!(h.len(), 1, "{h:?}");
        assert!((h[0].u - f.u).abs() < 1e-6 * f.u, "{} vs {}", h[0].u, f.u);
        assert!((h[0].omega - f.omega).abs() < 1e-5 * f.omega);
        assert!(h[0].dsigma_du > 0.0);
    }
}
