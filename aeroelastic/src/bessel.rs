//! Bessel functions of the first and second kind, orders 0 and 1, of real positive
//! argument: J0, J1, Y0, Y1 to about 1e-14 absolute (1e-13 relative away from zeros).
//!
//! Method (no rational approximations):
//! - `x < 25`: Miller's backward recurrence for J_n (normalised by
//!   J0 + 2 Σ J_2k = 1, Abramowitz & Stegun 9.1.46), then the Neumann series
//!   Y0 = (2/π)(ln(x/2)+γ) J0 − (4/π) Σ_{k≥1} (−1)^k J_2k / k (A&S 9.1.88) and its
//!   derivative Y1 = −Y0' = −(2/π) J0/x + (2/π)(ln(x/2)+γ) J1
//!   + (2/π) Σ_{k≥1} (−1)^k (J_{2k−1} − J_{2k+1}) / k.
//! - `x ≥ 25`: Hankel's asymptotic expansion (A&S 9.2.5–9.2.10) summed until the terms
//!   fall below 1e-17 (the smallest term is of order e^{−2x} < 1e-21 there).

/// Euler–Mascheroni constant γ.
const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;
/// Argument from which the asymptotic expansion is used.
const X_ASYMPTOTIC: f64 = 25.0;
/// Largest start order of the backward recurrence (x < 25 needs at most 78).
const N_MAX: usize = 128;

/// The four values J0(x), J1(x), Y0(x), Y1(x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bessel01 {
    /// J0(x).
    pub j0: f64,
    /// J1(x).
    pub j1: f64,
    /// Y0(x).
    pub y0: f64,
    /// Y1(x).
    pub y1: f64,
}

/// J0, J1, Y0, Y1 at `x`.
///
/// `x` must be finite and `> 0` (Y0, Y1 are singular at 0); for `x <= 0` or a non-finite
/// `x` every field is NaN — callers in this crate guard the argument.
pub fn bessel01(x: f64) -> Bessel01 {
    if !(x.is_finite() && x > 0.0) {
        return Bessel01 {
            j0: f64::NAN,
            j1: f64::NAN,
            y0: f64::NAN,
            y1: f64::NAN,
        };
    }
    if x >= X_ASYMPTOTIC {
        asymptotic(x)
    } else {
        miller_neumann(x)
    }
}

fn miller_neumann(x: f64) -> Bessel01 {
    // Start order: J_N(x) ~ (e x / 2N)^N / sqrt(2πN) is below 1e-25 for N = 1.5x + 40.
    let mut n_start = (1.5 * x + 40.0) as usize;
    if n_start % 2 == 1 {
        n_start += 1;
    }
    let n_start = n_start.min(N_MAX - 2);
    let mut j = [0.0_f64; N_MAX];
    j[n_start] = 1e-30;
    j[n_start + 1] = 0.0;
    let two_over_x = 2.0 / x;
    for n in (1..=n_start).rev() {
        j[n - 1] = (n as f64) * two_over_x * j[n] - j[n + 1];
        if j[n - 1].abs() > 1e200 {
            for v in j[n - 1..=n_start].iter_mut() {
                *v *= 1e-200;
            }
        }
    }
    let mut norm = j[0];
    let mut k = 2;
    while k <= n_start {
        norm += 2.0 * j[k];
        k += 2;
    }
    for v in j[..=n_start].iter_mut() {
        *v /= norm;
    }
    let lg = (0.5 * x).ln() + EULER_GAMMA;
    let mut s0 = 0.0;
    let mut s1 = 0.0;
    let mut kk = 1;
    while 2 * kk < n_start {
        let sign = if kk % 2 == 0 { 1.0 } else { -1.0 };
        s0 += sign * j[2 * kk] / kk as f64;
        s1 += sign * (j[2 * kk - 1] - j[2 * kk + 1]) / kk as f64;
        kk += 1;
    }
    let two_pi = std::f64::consts::FRAC_2_PI;
    Bessel01 {
        j0: j[0],
        j1: j[1],
        y0: two_pi * lg * j[0] - 2.0 * two_pi * s0,
        y1: -two_pi * j[0] / x + two_pi * lg * j[1] + two_pi * s1,
    }
}

/// Hankel's P and Q of order ν (μ = 4ν²).
fn hankel_pq(nu: f64, x: f64) -> (f64, f64) {
    let mu = 4.0 * nu * nu;
    let mut p = 1.0;
    let mut q = 0.0;
    let mut t = 1.0_f64;
    let mut last = f64::INFINITY;
    for k in 1..200 {
        let odd = (2 * k - 1) as f64;
        t *= (mu - odd * odd) / (k as f64 * 8.0 * x);
        if t.abs() > last {
            break; // the asymptotic series starts diverging
        }
        last = t.abs();
        match k % 4 {
            1 => q += t,
            2 => p -= t,
            3 => q -= t,
            _ => p += t,
        }
        if t.abs() < 1e-17 {
            break;
        }
    }
    (p, q)
}

fn asymptotic(x: f64) -> Bessel01 {
    let amp = (std::f64::consts::FRAC_2_PI / x).sqrt();
    let quarter = std::f64::consts::FRAC_PI_4;
    let (p0, q0) = hankel_pq(0.0, x);
    let (p1, q1) = hankel_pq(1.0, x);
    let chi0 = x - quarter;
    let chi1 = x - 3.0 * quarter;
    let (s0, c0) = chi0.sin_cos();
    let (s1, c1) = chi1.sin_cos();
    Bessel01 {
        j0: amp * (p0 * c0 - q0 * s0),
        y0: amp * (p0 * s0 + q0 * c0),
        j1: amp * (p1 * c1 - q1 * s1),
        y1: amp * (p1 * s1 + q1 * c1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values: Abramowitz & Stegun Table 9.1 (10 digits) and, for the extra
    /// digits, scipy.special (independent Cephes/AMOS implementation).
    const REFS: &[(f64, f64, f64, f64, f64)] = &[
        // x, J0, J1, Y0, Y1
        (
            1.0,
            0.765_197_686_557_966_6,
            0.440_050_585_744_933_5,
            0.088_256_964_215_676_96,
            -0.781_212_821_300_288_7,
        ),
        (
            10.0,
            -0.245_935_764_451_348_3,
            0.043_472_746_168_861_41,
            0.055_671_167_283_599_61,
            0.249_015_424_206_953_9,
        ),
        (
            3.7,
            -0.399_230_203_371_191_2,
            0.053_833_987_745_461_81,
            0.106_074_315_320_354_33,
            0.416_674_372_683_807_75,
        ),
        (
            24.9,
            0.083_245_968_353_015_36,
            -0.134_855_699_531_408_8,
            -0.136_499_183_996_765_3,
            -0.086_002_557_595_554_4,
        ),
        (
            25.1,
            0.108_275_671_499_949_38,
            -0.114_634_784_134_422_46,
            -0.116_767_707_638_037_07,
            -0.110_622_233_227_831_09,
        ),
        (
            60.0,
            -0.091_471_804_089_062_01,
            0.046_598_383_758_166_224,
            0.047_358_952_209_449_155,
            0.091_869_609_369_866_93,
        ),
    ];

    #[test]
    fn matches_tabulated_values() {
        for &(x, j0, j1, y0, y1) in REFS {
            let b = bessel01(x);
            for (name, got, want) in [
                ("J0", b.j0, j0),
                ("J1", b.j1, j1),
                ("Y0", b.y0, y0),
                ("Y1", b.y1, y1),
            ] {
                assert!(
                    (got - want).abs() < 1e-13,
                    "{name}({x}) = {got}, want {want}"
                );
            }
        }
    }

    #[test]
    fn wronskian_holds_everywhere() {
        // J1 Y0 − J0 Y1 = 2/(π x) (A&S 9.1.16), across both methods and the crossover.
        let mut x = 1e-3;
        while x < 200.0 {
            let b = bessel01(x);
            let w = b.j1 * b.y0 - b.j0 * b.y1;
            let want = std::f64::consts::FRAC_2_PI / x;
            assert!(
                ((w - want) / want).abs() < 1e-12,
                "x = {x}: W = {w}, want {want}"
            );
            x *= 1.07;
        }
    }

    #[test]
    fn continuous_across_method_crossover() {
        let a = miller_neumann(X_ASYMPTOTIC);
        let b = asymptotic(X_ASYMPTOTIC);
        for (p, q) in [(a.j0, b.j0), (a.j1, b.j1), (a.y0, b.y0), (a.y1, b.y1)] {
            assert!((p - q).abs() < 1e-14, "{p} vs {q}");
        }
    }

    #[test]
    fn small_argument_limits() {
        let x = 1e-6;
        let b = bessel01(x);
        assert!((b.j0 - 1.0).abs() < 1e-12);
        assert!((b.j1 - 0.5 * x).abs() < 1e-15);
        let y0 = std::f64::consts::FRAC_2_PI * ((0.5 * x).ln() + EULER_GAMMA);
        assert!((b.y0 - y0).abs() < 1e-10);
        assert!(((b.y1 + std::f64::consts::FRAC_2_PI / x) / b.y1).abs() < 1e-10);
    }

    #[test]
    fn invalid_argument_is_nan_not_panic() {
        assert!(bessel01(0.0).j0.is_nan());
        assert!(bessel01(-1.0).y1.is_nan());
        assert!(bessel01(f64::NAN).y0.is_nan());
    }
}
