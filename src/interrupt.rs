//! SIGINT/SIGTERM: clean up this process's unfinished output, then exit with 130.
//!
//! What is cleaned is recorded by `outdir`: the staging folder and the lock of a command
//! that writes a whole folder (the previous results stay as they were), or the temporary
//! files of `identify::io::write_atomic` in a shared folder. Nothing outside those is
//! touched and no symbolic link is followed.
//!
//! The cleanup leaves a file at the staging path while other threads may still write (a
//! writer's `create_dir_all` cannot recreate the folder through it). Before that file is
//! removed, every other thread of the process is parked in a signal handler, so that none
//! can recreate the folder between the removal and the exit (the window in which the
//! interrupt test saw a staging folder survive, issue 28).

#[cfg(target_os = "linux")]
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;
#[cfg(target_os = "linux")]
use std::time::Instant;

/// Installs the handler (once per process, at start-up; a second call is a no-op).
pub fn install() {
    let _ = ctrlc::set_handler(move || {
        let (msg, blocker) = crate::outdir::interrupt_cleanup();
        eprintln!("{msg}");
        let blocker = blocker.and_then(|b| {
            std::ffi::CString::new(std::os::unix::ffi::OsStrExt::as_bytes(b.as_os_str())).ok()
        });
        park_other_threads(Duration::from_secs(2));
        crate::outdir::after_park();
        if let Some(b) = blocker {
            // SAFETY: a valid NUL-terminated path; unlink only removes the name.
            unsafe { libc::unlink(b.as_ptr()) };
        }
        // SAFETY: _exit ends the process at once; nothing here relies on destructors or
        // at-exit handlers (the other threads are parked, possibly holding locks).
        unsafe { libc::_exit(130) }
    });
}

/// Threads that entered [`park`].
#[cfg(target_os = "linux")]
static PARKED: AtomicUsize = AtomicUsize::new(0);

/// The parking signal's handler: counts itself and waits for the exit (async-signal-safe:
/// an atomic add and `pause`).
#[cfg(target_os = "linux")]
extern "C" fn park(_: libc::c_int) {
    PARKED.fetch_add(1, Ordering::SeqCst);
    loop {
        // SAFETY: pause only waits for a signal.
        unsafe { libc::pause() };
    }
}

/// Sends every other thread of the process (`/proc/self/task`) a real-time signal whose
/// handler parks it, and waits until all have parked or `timeout` has passed (a thread
/// in an uninterruptible write parks when the write returns). Threads that appear
/// meanwhile are signalled too. Without `/proc` this does nothing.
#[cfg(target_os = "linux")]
fn park_other_threads(timeout: Duration) {
    let sig = libc::SIGRTMIN() + 3;
    // SAFETY: installs a handler that only touches an atomic and calls pause; the
    // sigaction struct is zeroed (empty mask, no flags) before the handler is set.
    unsafe {
        let mut sa: libc::sigaction = std::mem::zeroed();
        sa.sa_sigaction = park as *const () as libc::sighandler_t;
        libc::sigemptyset(&mut sa.sa_mask);
        if libc::sigaction(sig, &sa, std::ptr::null_mut()) != 0 {
            return;
        }
    }
    // SAFETY: plain system calls without pointers.
    let (pid, me) = unsafe { (libc::getpid(), libc::gettid()) };
    let mut signalled: Vec<libc::pid_t> = Vec::new();
    let start = Instant::now();
    loop {
        let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
            return;
        };
        for tid in dir.filter_map(|e| e.ok()?.file_name().to_str()?.parse::<libc::pid_t>().ok()) {
            if tid != me && !signalled.contains(&tid) {
                // SAFETY: tgkill to a thread of this process.
                if unsafe { libc::syscall(libc::SYS_tgkill, pid, tid, sig) } == 0 {
                    signalled.push(tid);
                }
            }
        }
        if PARKED.load(Ordering::SeqCst) >= signalled.len() || start.elapsed() > timeout {
            return;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Elsewhere than Linux the other threads are not parked (the window stays).
#[cfg(not(target_os = "linux"))]
fn park_other_threads(_: Duration) {}
