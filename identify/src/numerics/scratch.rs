//! Reused scratch buffers: the per-case work of an identification needs a few
//! megabyte-sized temporaries (the library block, the harmonic basis block, the stacked
//! triangles); allocated afresh for each of hundreds of cases they cost more in page
//! faults and zeroing of new memory than in arithmetic (round 33, docs/DECISIONS.md). A
//! [`Scratch`] takes a buffer from its thread's pool and gives it back when dropped.

use std::cell::RefCell;

/// Buffers a thread keeps between uses (the per-case work holds at most six at once).
const POOL_BUFFERS: usize = 8;
/// Largest buffer kept, in values (16 MiB); a larger one is freed when dropped, so the
/// pool holds at most `POOL_BUFFERS` × 16 MiB per thread and, for the paper's records,
/// about 6 MB.
const POOL_MAX_VALUES: usize = 2 << 20;

thread_local! {
    static POOL: RefCell<Vec<Vec<f64>>> = const { RefCell::new(Vec::new()) };
}

/// A zero-filled `f64` buffer from the calling thread's pool (see the module), returned
/// to the pool when dropped. Dereferences to the slice of its values.
#[derive(Debug)]
pub struct Scratch {
    v: Vec<f64>,
}

impl Scratch {
    /// `len` zeros: the smallest pooled buffer that holds them, else the largest grown,
    /// else a new one.
    pub fn zeroed(len: usize) -> Self {
        let mut v = Self::take(len);
        v.clear();
        v.resize(len, 0.0);
        Scratch { v }
    }

    /// `len` values to be overwritten: as [`Scratch::zeroed`] but the values a reused
    /// buffer held are left in place (no zeroing pass); only for a caller that writes
    /// every value before it reads any (otherwise it would read an earlier user's numbers).
    pub fn overwritten(len: usize) -> Self {
        let mut v = Self::take(len);
        if v.len() >= len {
            v.truncate(len);
        } else {
            v.resize(len, 0.0);
        }
        Scratch { v }
    }

    fn take(len: usize) -> Vec<f64> {
        POOL.try_with(|p| {
            let mut p = p.borrow_mut();
            let fit = (0..p.len())
                .filter(|&i| p[i].capacity() >= len)
                .min_by_key(|&i| p[i].capacity())
                .or_else(|| (0..p.len()).max_by_key(|&i| p[i].capacity()));
            fit.map(|i| p.swap_remove(i))
        })
        .ok()
        .flatten()
        .unwrap_or_default()
    }
}

/// Frees the calling thread's pooled buffers (what a long-lived thread calls when its
/// per-case work is done, so the pool does not add to the memory of what follows).
pub fn release() {
    let _ = POOL.try_with(|p| {
        if let Ok(mut p) = p.try_borrow_mut() {
            *p = Vec::new();
        }
    });
}

/// Values held in the calling thread's pool (for tests and measurements).
pub fn pooled_values() -> usize {
    POOL.try_with(|p| {
        p.try_borrow()
            .map_or(0, |p| p.iter().map(Vec::capacity).sum())
    })
    .unwrap_or(0)
}

impl std::ops::Deref for Scratch {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.v
    }
}

impl std::ops::DerefMut for Scratch {
    fn deref_mut(&mut self) -> &mut [f64] {
        &mut self.v
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let v = std::mem::take(&mut self.v);
        if v.capacity() == 0 || v.capacity() > POOL_MAX_VALUES {
            return;
        }
        let _ = POOL.try_with(|p| {
            if let Ok(mut p) = p.try_borrow_mut() {
                if p.len() < POOL_BUFFERS {
                    p.push(v);
                } else if let Some(i) = (0..p.len()).min_by_key(|&i| p[i].capacity()) {
                    // keep the larger buffers
                    if p[i].capacity() < v.capacity() {
                        p[i] = v;
                    }
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A buffer given back is reused (same allocation) and comes back zeroed at the asked
    /// length, whatever was written into it.
    #[test]
    fn buffers_are_reused_and_zeroed() {
        let ptr = {
            let mut a = Scratch::zeroed(1000);
            a.iter_mut().for_each(|v| *v = 7.0);
            a.as_ptr()
        };
        let b = Scratch::zeroed(500);
        assert_eq!(b.as_ptr(), ptr);
        assert_eq!(b.len(), 500);
        assert!(b.iter().all(|&v| v == 0.0));
        // two at once are distinct
        let c = Scratch::zeroed(500);
        assert_ne!(c.as_ptr(), b.as_ptr());
        assert!(c.iter().all(|&v| v == 0.0));
        // an overwritten buffer has the asked length (its values are unspecified)
        let d = Scratch::overwritten(700);
        assert_eq!(d.len(), 700);
        drop(d);
        // an oversized one is not kept
        drop(Scratch::zeroed(POOL_MAX_VALUES + 1));
        assert!(Scratch::zeroed(10).len() == 10);
        drop((b, c));
        assert!(pooled_values() >= 1000);
        release();
        assert_eq!(pooled_values(), 0);
    }
}
