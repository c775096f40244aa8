//! Helpers shared by the end-to-end tests (declared once in tests/main.rs; a file that
//! uses them says `use crate::common;`).

#![allow(dead_code)] // each test binary uses a subset

use std::path::Path;
use std::process::Command;

/// Runs the `aeroform` binary with `args`: (success, stdout, stderr).
pub fn aeroform(args: &[&str]) -> (bool, String, String) {
    run(Command::new(env!("CARGO_BIN_EXE_aeroform")).args(args))
}

/// [`aeroform`] with `dir` as the working directory.
pub fn aeroform_in(dir: &Path, args: &[&str]) -> (bool, String, String) {
    run(Command::new(env!("CARGO_BIN_EXE_aeroform"))
        .current_dir(dir)
        .args(args))
}

fn run(cmd: &mut Command) -> (bool, String, String) {
    let out = cmd.output().expect("run aeroform");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// [`aeroform_in`] with the exit code: (code, stdout, stderr); -1 when a signal ended it.
pub fn aeroform_code_in(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_aeroform"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run aeroform");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Writes, in `dir`, the forced campaign of configuration D of the plate truth
/// (`scenarios/plate-truth.model.toml`) as the data set `out`, records of `duration` s,
/// master seed `seed`; panics unless the command succeeds.
pub fn forced_set(dir: &Path, out: &str, seed: &str, duration: &str) {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/plate-truth.model.toml");
    let (code, o, e) = aeroform_code_in(
        dir,
        &[
            "--quiet",
            "tunnel",
            "forced",
            "--model",
            &model.display().to_string(),
            "--campaign",
            "config=D",
            "--duration",
            duration,
            "--seed",
            seed,
            "--out",
            out,
        ],
    );
    assert_eq!(code, 0, "{o}\n{e}");
}
