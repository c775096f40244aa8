//! SIGINT/SIGTERM: clean up this process's unfinished output, then exit with 130.
//!
//! What is cleaned is recorded by `outdir`: the staging folder and the lock of a command
//! that writes a whole folder (the previous results stay as they were), or the temporary
//! files of `identify::io::write_atomic` in a shared folder. Nothing outside those is
//! touched and no symbolic link is followed.

/// Installs the handler (once per process, at start-up; a second call is a no-op).
pub fn install() {
    let _ = ctrlc::set_handler(move || {
        let (msg, blocker) = crate::outdir::interrupt_cleanup();
        eprintln!("{msg}");
        if let Some(b) = blocker {
            let _ = std::fs::remove_file(b);
        }
        std::process::exit(130);
    });
}
