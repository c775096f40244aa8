//! Interpolation: a polynomial through a few nodes ([`lagrange`]), the 4-point cubic on
//! uniform samples ([`uniform_cubic`], built on it), piecewise-linear with held ends
//! ([`linear_held`]) and the natural cubic spline ([`Spline`]).

/// Value at `x` of the polynomial of degree `nodes.len() − 1` through `nodes` (x_i, y_i)
/// (Lagrange form; the x_i distinct). One node: its value; none: 0.
pub fn lagrange(nodes: &[(f64, f64)], x: f64) -> f64 {
    nodes
        .iter()
        .enumerate()
        .map(|(i, &(xi, yi))| {
            let w: f64 = nodes
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &(xj, _))| (x - xj) / (xi - xj))
                .product();
            yi * w
        })
        .sum()
}

/// Value of the uniformly sampled `x` at fractional index `u` by 4-point cubic Lagrange
/// interpolation (nodes ⌊u⌋−1 … ⌊u⌋+2, shifted inwards at the ends). `u` is clamped to
/// `[0, n−1]`. Error for a sinusoid of ω·dt per sample: ≤ 0.0234 (ω dt)⁴ of its amplitude.
///
/// # Panics
/// When `x` has fewer than 4 samples (a programming error: callers check lengths).
#[track_caller]
pub fn uniform_cubic(x: &[f64], u: f64) -> f64 {
    let n = x.len();
    assert!(n >= 4, "cubic interpolation needs 4 samples, got {n}");
    let u = u.clamp(0.0, (n - 1) as f64);
    let j = (u.floor() as usize).saturating_sub(1).min(n - 4);
    let nodes: [(f64, f64); 4] = std::array::from_fn(|k| (k as f64, x[j + k]));
    lagrange(&nodes, u - j as f64)
}

/// Piecewise-linear interpolation at `x` through the nodes (x_i, y(i)), x strictly
/// increasing, held at the end values outside [x_0, x_{n−1}] (never extrapolated).
///
/// # Panics
/// When `xs` is empty (a programming error: callers hold at least one node).
#[track_caller]
pub fn linear_held(xs: &[f64], y: impl Fn(usize) -> f64, x: f64) -> f64 {
    let n = xs.len();
    assert!(n >= 1, "linear interpolation needs a node");
    if x <= xs[0] {
        y(0)
    } else if x >= xs[n - 1] {
        y(n - 1)
    } else {
        let i = xs.partition_point(|&v| v <= x) - 1;
        let t = (x - xs[i]) / (xs[i + 1] - xs[i]);
        y(i) + t * (y(i + 1) - y(i))
    }
}

/// Natural cubic spline through (x_i, y_i), x strictly increasing; constant extrapolation
/// (the end values) outside [x_0, x_{n−1}].
#[derive(Debug, Clone)]
pub struct Spline {
    x: Vec<f64>,
    y: Vec<f64>,
    m: Vec<f64>,
}

impl Spline {
    /// Builds the spline.
    ///
    /// # Panics
    /// When the lengths differ or there are fewer than 2 knots (a programming error).
    #[track_caller]
    pub fn new(x: &[f64], y: &[f64]) -> Self {
        assert!(
            x.len() == y.len() && x.len() >= 2,
            "spline needs ≥ 2 points of equal length"
        );
        let n = x.len();
        let mut m = vec![0.0; n];
        if n > 2 {
            // Tridiagonal system for the second derivatives (natural ends).
            let mut c = vec![0.0; n];
            let mut d = vec![0.0; n];
            for i in 1..n - 1 {
                let h0 = x[i] - x[i - 1];
                let h1 = x[i + 1] - x[i];
                let a = h0;
                let b = 2.0 * (h0 + h1);
                let cc = h1;
                let r = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
                let denom = b - a * c[i - 1];
                c[i] = cc / denom;
                d[i] = (r - a * d[i - 1]) / denom;
            }
            for i in (1..n - 1).rev() {
                m[i] = d[i] - c[i] * m[i + 1];
            }
        }
        Spline {
            x: x.to_vec(),
            y: y.to_vec(),
            m,
        }
    }

    /// Value at `t` (clamped to the end values outside the knots).
    pub fn eval(&self, t: f64) -> f64 {
        let n = self.x.len();
        if t <= self.x[0] {
            return self.y[0];
        }
        if t >= self.x[n - 1] {
            return self.y[n - 1];
        }
        let i = match self.x.partition_point(|&v| v <= t) {
            0 => 0,
            p => (p - 1).min(n - 2),
        };
        let h = self.x[i + 1] - self.x[i];
        let a = (self.x[i + 1] - t) / h;
        let b = (t - self.x[i]) / h;
        a * self.y[i]
            + b * self.y[i + 1]
            + ((a * a * a - a) * self.m[i] + (b * b * b - b) * self.m[i + 1]) * h * h / 6.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_held_interpolates_inside_and_holds_outside() {
        let xs = [0.5, 1.0, 2.0];
        let ys = [1.0, 3.0, 0.0];
        let f = |x| linear_held(&xs, |i| ys[i], x);
        assert_eq!(f(0.0), 1.0);
        assert_eq!(f(9.0), 0.0);
        assert_eq!(f(1.0), 3.0);
        assert!((f(0.75) - 2.0).abs() < 1e-15);
        assert!((f(1.5) - 1.5).abs() < 1e-15);
        assert_eq!(linear_held(&[2.0], |_| 7.0, -1.0), 7.0);
    }

    #[test]
    fn lagrange_is_exact_for_polynomials_of_its_degree() {
        let p = |x: f64| 2.0 - 3.0 * x + 0.5 * x * x;
        let nodes = [(0.3, p(0.3)), (1.1, p(1.1)), (2.7, p(2.7))];
        for x in [-1.0, 0.3, 0.9, 2.0, 4.5] {
            assert!((lagrange(&nodes, x) - p(x)).abs() < 1e-12, "{x}");
        }
        assert_eq!(lagrange(&[(1.0, 4.0)], 7.0), 4.0);
        assert_eq!(lagrange(&[], 7.0), 0.0);
        let c = |x: f64| x * x * x - x;
        let s: Vec<f64> = (0..6).map(|i| c(i as f64)).collect();
        for u in [0.0, 0.4, 2.5, 4.9, 5.0] {
            assert!((uniform_cubic(&s, u) - c(u)).abs() < 1e-12, "{u}");
        }
    }

    #[test]
    fn spline_reproduces_smooth_function() {
        let x: Vec<f64> = (0..=40).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = x.iter().map(|v| v.sin()).collect();
        let s = Spline::new(&x, &y);
        for t in [0.55, 1.234, 2.9, 3.71] {
            assert!((s.eval(t) - f64::sin(t)).abs() < 2e-5, "{t}");
        }
        assert_eq!(s.eval(-1.0), 0.0);
        assert_eq!(s.eval(10.0), y[40]);
    }
}
