//! Captures the commit at build time: `AEROFORM_GIT` = `git describe --always --dirty` of
//! the checkout being built (`commit unknown` outside a git checkout), read by `--version` and the
//! reports, so a binary names the commit it was built from, not the checkout it runs in.

use std::path::PathBuf;
use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()?;
    let s = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (out.status.success() && !s.is_empty()).then_some(s)
}

fn main() {
    let describe =
        git(&["describe", "--always", "--dirty"]).unwrap_or_else(|| "commit unknown".into());
    println!("cargo:rustc-env=AEROFORM_GIT={describe}");
    // Re-run when HEAD moves, the branch's ref changes or the index changes (dirty state).
    for (flag, file) in [
        ("--git-dir", "HEAD"),
        ("--git-dir", "index"),
        ("--git-common-dir", "packed-refs"),
    ] {
        if let Some(dir) = git(&["rev-parse", flag]) {
            let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join(dir)
                .join(file);
            println!("cargo:rerun-if-changed={}", p.display());
        }
    }
    if let (Some(dir), Some(head)) = (
        git(&["rev-parse", "--git-common-dir"]),
        git(&["symbolic-ref", "-q", "HEAD"]),
    ) {
        let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join(dir)
            .join(head);
        println!("cargo:rerun-if-changed={}", p.display());
    }
    println!("cargo:rerun-if-changed=build.rs");
}
