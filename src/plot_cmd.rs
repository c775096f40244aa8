//! `aeroform plot OUTDIR`: redraws the figures and the report of a finished study from its
//! result files (`study.toml`, `identification.json`, `series/`, `flutter.json`,
//! `lco.json`, …) without recomputing anything.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;

use plots::study_report::render_all_from;
use study::run::names;
use study::Study;

/// Flags of `aeroform plot`.
#[derive(Debug, Args)]
pub struct PlotArgs {
    /// Output folder of an earlier `aeroform run`.
    pub outdir: PathBuf,
}

/// Redraws figures and report. The folder is rewritten as a whole (issue 27, row 7): its
/// files are copied into a staging folder, redrawn there and moved into place in one
/// rename, so an interrupted or failed redraw leaves the previous folder as it was.
pub fn run(args: &PlotArgs) -> anyhow::Result<()> {
    crate::outdir::check_complete(&args.outdir)?;
    let path = args.outdir.join(names::STUDY);
    let text = identify::io::read_text(&path).with_context(|| {
        format!(
            "{}: {} is not a study output folder",
            path.display(),
            args.outdir.display()
        )
    })?;
    // the folder is the user's named target and every file of it is carried over; its
    // completion marker keeps the command that computed the results (`plot` only redraws)
    let command = std::fs::read_to_string(args.outdir.join(crate::outdir::COMPLETE_MARKER))
        .ok()
        .and_then(|t| {
            t.lines().find_map(|l| {
                l.strip_prefix("command = \"")?
                    .strip_suffix('"')
                    .map(String::from)
            })
        })
        .unwrap_or_else(|| "plot".to_string());
    // what `plot` rewrites must be of its kind: a folder in place of `figures.json` would
    // fail in the staging copy, under a name gone when the message is read
    for (name, folder) in [
        (names::FIGURE_LIST, false),
        (names::REPORT, false),
        (names::FIGURES, true),
    ] {
        let p = args.outdir.join(name);
        if std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_dir() != folder || m.is_symlink()) {
            crate::exit::refuse!(
                "{}: not a {}; `plot` rewrites it (remove it or run the study again)",
                p.display(),
                if folder { "folder" } else { "regular file" }
            );
        }
    }
    let dir = crate::outdir::OutDir::begin(&args.outdir, &command, true, &[])?;
    copy_tree(&args.outdir, dir.path())
        .with_context(|| format!("copying {} to redraw it", args.outdir.display()))?;
    let staged = dir.path().to_path_buf();
    // relative data paths are not needed: nothing is recomputed. The result files are read
    // from the folder the user named (copied byte for byte into the staging folder), so a
    // refusal names a file that exists when the message is read, not the staging copy
    // (issue 39, row 7); the figures and the report are written into the staging folder.
    let study = Study::parse(&text, &path, &staged)?;
    let figs = render_all_from(&study, &args.outdir, &staged, &crate::version()).map_err(|e| {
        if e.is_data() {
            // the figures are drawn from the folder's result files: they do not fit
            // together (edited or damaged), an input error naming the folder
            let mut why = e.to_string();
            let mut cause = std::error::Error::source(&e);
            while let Some(c) = cause {
                why = format!("{why}: {c}");
                cause = c.source();
            }
            anyhow::Error::from(crate::exit::Usage(format!(
                "{}: the result files do not fit together: {why}; run the study again",
                args.outdir.display()
            )))
        } else {
            e.into()
        }
    })?;
    let out = dir.commit()?;
    crate::ui::say!(
        "redrew {} figures and {}",
        figs.len(),
        out.join(names::REPORT).display()
    );
    crate::ui::document(&figs)
}

/// Carries the files and folders of `src` into `dst` (which exists), without the folder
/// markers (the staging folder has its own). What `plot` rewrites (the figure list, the
/// report, the figures folder) is copied; every other regular file is hard-linked (no
/// byte is copied: a sparse 2-GB file stays sparse and a large series costs no disk; a
/// copy only where the file system refuses the link), and a symbolic link is carried as a
/// link to the same target, not dropped (issue 39, row 5, round 29). Every writer of a
/// study folder replaces a file by rename, so no write reaches a linked file in place.
fn copy_tree(src: &Path, dst: &Path) -> std::io::Result<()> {
    carry_tree(src, dst, false)
}

fn carry_tree(src: &Path, dst: &Path, copy: bool) -> std::io::Result<()> {
    for e in std::fs::read_dir(src)? {
        let e = e?;
        let name = e.file_name();
        if name == crate::outdir::COMPLETE_MARKER || name == crate::outdir::INCOMPLETE_MARKER {
            continue;
        }
        let to = dst.join(&name);
        let t = e.file_type()?;
        let rewritten = copy
            || [names::FIGURE_LIST, names::REPORT, names::FIGURES]
                .contains(&name.to_str().unwrap_or(""));
        if t.is_symlink() {
            std::os::unix::fs::symlink(std::fs::read_link(e.path())?, &to)?;
        } else if t.is_dir() {
            std::fs::create_dir(&to)?;
            carry_tree(&e.path(), &to, rewritten)?;
        } else if t.is_file() && (rewritten || std::fs::hard_link(e.path(), &to).is_err()) {
            std::fs::copy(e.path(), &to)?;
        }
    }
    Ok(())
}
