//! Small numerical helpers: Brent's root finder, Nelder–Mead minimiser, natural cubic
//! spline.

/// Brent's method (Brent 1973, "zeroin") for a root of `f` in `[a, b]` with
/// `f(a) f(b) ≤ 0`, to absolute tolerance `tol` in x. Returns `None` when the bracket does
/// not change sign or `f` returns a non-finite value.
pub fn brent<F: FnMut(f64) -> f64>(
    mut f: F,
    a: f64,
    b: f64,
    tol: f64,
    max_iter: usize,
) -> Option<f64> {
    let (mut a, mut b) = (a, b);
    let mut fa = f(a);
    let mut fb = f(b);
    if !(fa.is_finite() && fb.is_finite()) || fa * fb > 0.0 {
        return None;
    }
    if fa == 0.0 {
        return Some(a);
    }
    if fb == 0.0 {
        return Some(b);
    }
    let mut c = a;
    let mut fc = fa;
    let mut d = b - a;
    let mut e = d;
    for _ in 0..max_iter {
        if fb * fc > 0.0 {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol1 = 2.0 * f64::EPSILON * b.abs() + 0.5 * tol;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol1 || fb == 0.0 {
            return Some(b);
        }
        if e.abs() >= tol1 && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            }
            p = p.abs();
            let min1 = 3.0 * xm * q - (tol1 * q).abs();
            let min2 = (e * q).abs();
            if 2.0 * p < min1.min(min2) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol1 { d } else { tol1.copysign(xm) };
        fb = f(b);
        if !fb.is_finite() {
            return None;
        }
    }
    Some(b)
}

/// Nelder–Mead simplex minimisation of `f` from `x0` with initial step `step`, at most
/// `max_eval` evaluations; returns the best point and value.
pub fn nelder_mead<F: FnMut(&[f64]) -> f64>(
    mut f: F,
    x0: &[f64],
    step: f64,
    max_eval: usize,
) -> (Vec<f64>, f64) {
    let n = x0.len();
    let mut simplex: Vec<Vec<f64>> = vec![x0.to_vec()];
    for i in 0..n {
        let mut x = x0.to_vec();
        x[i] += step;
        simplex.push(x);
    }
    let mut vals: Vec<f64> = simplex.iter().map(|x| f(x)).collect();
    let mut evals = n + 1;
    let nan_big = |v: f64| if v.is_finite() { v } else { f64::MAX };
    while evals < max_eval {
        let mut idx: Vec<usize> = (0..=n).collect();
        idx.sort_by(|&a, &b| nan_big(vals[a]).total_cmp(&nan_big(vals[b])));
        simplex = idx.iter().map(|&i| simplex[i].clone()).collect();
        vals = idx.iter().map(|&i| vals[i]).collect();
        if (nan_big(vals[n]) - nan_big(vals[0])).abs() <= 1e-12 * nan_big(vals[0]).abs() + 1e-300 {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|j| simplex[..n].iter().map(|x| x[j]).sum::<f64>() / n as f64)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            (0..n)
                .map(|j| centroid[j] + t * (simplex[n][j] - centroid[j]))
                .collect()
        };
        let xr = along(-1.0);
        let fr = nan_big(f(&xr));
        evals += 1;
        if fr < nan_big(vals[0]) {
            let xe = along(-2.0);
            let fe = nan_big(f(&xe));
            evals += 1;
            if fe < fr {
                simplex[n] = xe;
                vals[n] = fe;
            } else {
                simplex[n] = xr;
                vals[n] = fr;
            }
        } else if fr < nan_big(vals[n - 1]) {
            simplex[n] = xr;
            vals[n] = fr;
        } else {
            let xc = along(0.5);
            let fc = nan_big(f(&xc));
            evals += 1;
            if fc < nan_big(vals[n]) {
                simplex[n] = xc;
                vals[n] = fc;
            } else {
                let best = simplex[0].clone();
                for i in 1..=n {
                    for (v, b) in simplex[i].iter_mut().zip(&best) {
                        *v = b + 0.5 * (*v - b);
                    }
                    vals[i] = f(&simplex[i]);
                    evals += 1;
                }
            }
        }
    }
    let best = (0..=n)
        .min_by(|&a, &b| nan_big(vals[a]).total_cmp(&nan_big(vals[b])))
        .unwrap_or(0);
    (simplex[best].clone(), vals[best])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brent_finds_cos_root() {
        let r = brent(f64::cos, 0.0, 3.0, 1e-14, 100).unwrap();
        assert!((r - std::f64::consts::FRAC_PI_2).abs() < 1e-13);
        assert!(brent(|x| x * x + 1.0, -1.0, 1.0, 1e-12, 100).is_none());
    }

    #[test]
    fn nelder_mead_minimises_rosenbrock() {
        let (x, v) = nelder_mead(
            |p| (1.0 - p[0]).powi(2) + 100.0 * (p[1] - p[0] * p[0]).powi(2),
            &[-1.2, 1.0],
            0.5,
            4000,
        );
        assert!(v < 1e-10 && (x[0] - 1.0).abs() < 1e-4, "{x:?} {v}");
    }
}
