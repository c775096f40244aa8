//! Real FFT plans for the whole workspace: forward (real → complex) and inverse (complex
//! → real) transforms of `f64` signals, planned once per process and length and shared.
//!
//! Why a crate of its own: rustfft's planner is generic, so every crate that calls
//! `RealFftPlanner::<f64>::new()` compiles its whole algorithm tree (every butterfly, for
//! its SSE and AVX paths) again: a third of `identify`'s code before optimisation, paid
//! again by each library's unit-test copy. The functions here are not generic; callers
//! hold the plans as trait objects and compile none of it (docs/DECISIONS.md, "rustfft
//! compiled once", round 41).
//!
//! Plans are the ones a fresh `realfft::RealFftPlanner` makes: the planner chooses the
//! algorithm from the length (and the CPU's instruction sets) alone, so a shared plan is
//! the same transform, bit for bit. Conventions are realfft's: the forward transform of n
//! real samples gives n/2 + 1 bins X_k = Σ_j x_j e^{−2πijk/n}, unnormalised; the inverse
//! gives n·x (no 1/n), and needs real DC (and, for even n, Nyquist) bins.

use std::sync::{Arc, Mutex, OnceLock};

use realfft::RealFftPlanner;
pub use realfft::{ComplexToReal, RealToComplex};

/// The shared planner (poisoned: a fresh planner per call, which plans the same).
fn with_planner<R>(plan: impl FnOnce(&mut RealFftPlanner<f64>) -> R) -> R {
    static PLANNER: OnceLock<Mutex<RealFftPlanner<f64>>> = OnceLock::new();
    let planner = PLANNER.get_or_init(|| Mutex::new(RealFftPlanner::new()));
    match planner.lock() {
        Ok(mut p) => plan(&mut p),
        Err(_) => plan(&mut RealFftPlanner::new()),
    }
}

/// Forward real FFT of length `n` (samples): n real inputs → n/2 + 1 complex bins
/// X_k = Σ_j x_j e^{−2πijk/n} (unnormalised). `n` = 0 gives a plan that refuses every
/// buffer (realfft's own behaviour).
pub fn forward(n: usize) -> Arc<dyn RealToComplex<f64>> {
    with_planner(|p| p.plan_fft_forward(n))
}

/// Inverse real FFT of length `n`: n/2 + 1 complex bins → n real samples, unnormalised
/// (the forward then inverse of x gives n·x). The DC bin's, and for even `n` the Nyquist
/// bin's, imaginary parts must be zero; realfft's `process` returns an error otherwise.
pub fn inverse(n: usize) -> Arc<dyn ComplexToReal<f64>> {
    with_planner(|p| p.plan_fft_inverse(n))
}

/// [`forward`] and [`inverse`] of one length from one lock of the planner.
pub fn forward_and_inverse(n: usize) -> (Arc<dyn RealToComplex<f64>>, Arc<dyn ComplexToReal<f64>>) {
    with_planner(|p| (p.plan_fft_forward(n), p.plan_fft_inverse(n)))
}
