//! SIGINT/SIGTERM during a run: remove this process's temporary files, then exit.
//!
//! Every result file is written to `.<name>.<pid>.tmp` and renamed into place
//! (`identify::io::write_atomic`), so an interrupted run leaves complete files or none; the
//! handler removes the temporary files of writes that were in flight.

use std::path::{Path, PathBuf};

/// Installs the handler for the output folder `dir` (once per process; a second call is a
/// no-op).
pub fn install_cleanup(dir: PathBuf) {
    let suffix = format!(".{}.tmp", std::process::id());
    let _ = ctrlc::set_handler(move || {
        remove_temp_files(&dir, &suffix);
        eprintln!(
            "interrupted: {} holds only complete result files",
            dir.display()
        );
        std::process::exit(130);
    });
}

fn remove_temp_files(dir: &Path, suffix: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            remove_temp_files(&p, suffix);
        } else if p
            .file_name()
            .is_some_and(|n| n.to_string_lossy().ends_with(suffix))
        {
            let _ = std::fs::remove_file(&p);
        }
    }
}
