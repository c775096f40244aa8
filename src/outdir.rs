//! Complete-or-absent output folders.
//!
//! A command that writes a folder of results (`run`, `tunnel …`, `diagnose`) writes it
//! as a whole:
//!
//! 1. it takes the lock `P/.NAME.aeroform-lock` (its PID inside) next to `--out P/NAME`;
//!    the lock of a dead process is taken over with a message, a live one is an error;
//! 2. it removes work folders of dead processes in `P` (`P/.X.aeroform-staging.PID`,
//!    `P/.X.aeroform-old.PID`, never following a symbolic link) and refuses to replace an
//!    existing `P/NAME` that aeroform did not write (no [`COMPLETE_MARKER`]) unless
//!    `--force`;
//! 3. everything is written into the staging folder `P/.NAME.aeroform-staging.PID`, which
//!    holds [`INCOMPLETE_MARKER`] from its first byte;
//! 4. [`OutDir::commit`] writes [`COMPLETE_MARKER`], removes the incomplete-marker and
//!    swaps the staging folder with `P/NAME` in one `renameat2(RENAME_EXCHANGE)` (two
//!    renames where the file system cannot), then deletes the previous results.
//!
//! A failure (an error, SIGINT, SIGTERM) before the swap removes the staging folder and
//! leaves `P/NAME` as it was; a SIGKILL leaves a staging folder that readers refuse
//! (`identify::io::check_complete_folder`) and the next command removes.
//!
//! Commands that write one file into a shared folder (`identify`, `flutter`, `lco`) use
//! [`SharedDir`]: the file is written atomically (`identify::io::write_atomic`) and the
//! temporary files of dead processes in that folder are removed.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

pub use identify::io::{COMPLETE_MARKER, INCOMPLETE_MARKER};

use crate::exit::Usage;

/// What an interrupted process must clean up ([`interrupt_cleanup`]).
enum Active {
    /// A staging folder and its lock.
    Staging {
        out: PathBuf,
        staging: PathBuf,
        lock: PathBuf,
    },
    /// Temporary files of this process in a shared folder, and the folder's lock.
    Shared { dir: PathBuf, lock: PathBuf },
}

/// The current output of this process. The signal handler and [`OutDir::commit`] both
/// hold this mutex, so an interrupt never lands in the middle of the swap.
static ACTIVE: Mutex<Option<Active>> = Mutex::new(None);

fn set_active(a: Option<Active>) {
    *ACTIVE.lock().unwrap_or_else(|p| p.into_inner()) = a;
    // the lock being taken is now registered with its owner (or released)
    *PENDING_LOCK.lock().unwrap_or_else(|p| p.into_inner()) = None;
}

/// The shared folder whose temporary files [`after_park`] removes once more.
static AFTER_PARK: Mutex<Option<PathBuf>> = Mutex::new(None);

/// Called by the interrupt handler once every other thread is parked: removes this
/// process's temporary files of the shared folder again (a writer may have created one
/// between [`interrupt_cleanup`] and the parking: the kill campaign saw `.lco.json.PID.tmp`).
pub fn after_park() {
    if let Some(dir) = &*AFTER_PARK.lock().unwrap_or_else(|p| p.into_inner()) {
        remove_temp_files(dir, |pid| pid == std::process::id());
    }
}

/// A lock being taken and not yet registered in [`ACTIVE`]: its private PID file and the
/// lock path. An interrupt in that window removes both (the kill campaign found
/// `.o.aeroform-lock.PID.tmp` left by a SIGINT while `flutter` took its folder's lock).
static PENDING_LOCK: Mutex<Option<(PathBuf, PathBuf)>> = Mutex::new(None);

/// Called by the SIGINT/SIGTERM handler: removes the staging folder and the lock (or this
/// process's temporary files in a shared folder) and returns a sentence for the user and
/// the file that blocks the staging path, for the handler to remove just before it exits.
/// Holds the state mutex until the process exits.
pub fn interrupt_cleanup() -> (String, Option<PathBuf>) {
    let guard = ACTIVE.lock().unwrap_or_else(|p| p.into_inner());
    let mut blocker = None;
    let msg = match &*guard {
        Some(Active::Staging { out, staging, lock }) => {
            blocker = remove_staging_while_written(staging);
            let _ = std::fs::remove_file(lock);
            format!(
                "interrupted: {} left as it was (the unfinished results were removed)",
                out.display()
            )
        }
        Some(Active::Shared { dir, lock }) => {
            remove_temp_files(dir, |pid| pid == std::process::id());
            *AFTER_PARK.lock().unwrap_or_else(|p| p.into_inner()) = Some(dir.clone());
            let _ = std::fs::remove_file(lock);
            format!(
                "interrupted: {} holds only complete result files",
                dir.display()
            )
        }
        None => "interrupted".to_string(),
    };
    let pending = PENDING_LOCK.lock().unwrap_or_else(|p| p.into_inner());
    if let Some((pid_file, lock)) = &*pending {
        let _ = std::fs::remove_file(pid_file);
        let ours =
            std::fs::read_to_string(lock).is_ok_and(|t| t.trim() == std::process::id().to_string());
        if ours {
            let _ = std::fs::remove_file(lock);
        }
    }
    std::mem::forget(pending);
    // keep the guard: the main thread must not start a swap before the process exits
    std::mem::forget(guard);
    (msg, blocker)
}

/// Removes a staging folder that other threads of this process may still be writing
/// into (the interrupt does not stop them). The folder is renamed to a work-folder trash
/// name and an empty *file* takes its place, so that no writer can recreate it
/// (`create_dir_all` of a subfolder fails on a file), then the trash is removed; the
/// caller removes the blocking file (returned) as its last act before the exit. Removing
/// in place lost the race: writers recreated the folder during or after the walk
/// (issue 27, row 8).
fn remove_staging_while_written(staging: &Path) -> Option<PathBuf> {
    let name = staging.file_name().unwrap_or_default().to_string_lossy();
    let mut blocker = None;
    for round in 0..100 {
        match std::fs::symlink_metadata(staging) {
            Err(_) => {
                // nothing there: block it
                if std::fs::File::create_new(staging).is_ok() {
                    blocker = Some(staging.to_path_buf());
                    break;
                }
            }
            Ok(m) if m.is_file() && blocker.is_some() => break,
            Ok(_) => {
                // a work-folder name (".NAME.trashN.aeroform-old.PID"): a leftover of it
                // is removed by the next run like any dead process's work folder
                let trash = staging.with_file_name(name.replace(
                    ".aeroform-staging.",
                    &format!(".trash{round}.aeroform-old."),
                ));
                match std::fs::rename(staging, &trash) {
                    Ok(()) => {
                        if std::fs::File::create_new(staging).is_ok() {
                            blocker = Some(staging.to_path_buf());
                        }
                        remove_entry(&trash);
                        if blocker.is_some() {
                            break;
                        }
                    }
                    Err(_) => remove_entry(staging),
                }
            }
        }
    }
    blocker
}

/// Removes a file, a symbolic link (the link only) or a folder tree without following
/// symbolic links (`std::fs::remove_dir_all` removes links, never their targets).
fn remove_entry(p: &Path) {
    match std::fs::symlink_metadata(p) {
        Ok(m) if m.is_dir() => {
            let _ = std::fs::remove_dir_all(p);
        }
        Ok(_) => {
            let _ = std::fs::remove_file(p);
        }
        Err(_) => {}
    }
}

/// Creates `dir` and its missing parents; returns the folders this call created, deepest
/// first, for [`remove_created`] to take back when the command fails before it writes
/// its results (issue 27, row 17: a failed command left an empty `--out` folder).
fn create_dirs(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut missing = Vec::new();
    let mut p = Some(dir);
    while let Some(d) = p.filter(|d| !d.as_os_str().is_empty()) {
        if std::fs::symlink_metadata(d).is_ok() {
            break;
        }
        missing.push(d.to_path_buf());
        p = d.parent();
    }
    std::fs::create_dir_all(dir)?;
    Ok(missing)
}

/// Removes the folders of [`create_dirs`] that are still empty, deepest first (an empty
/// folder only: anything written into one, by this or another process, keeps it and its
/// parents; a folder that existed before the command is never in the list).
fn remove_created(created: &[PathBuf]) {
    for d in created {
        if std::fs::remove_dir(d).is_err() {
            break;
        }
    }
}

/// True when a process with this PID exists (signal 0; EPERM means it exists).
pub fn pid_alive(pid: u32) -> bool {
    if pid == 0 || pid > i32::MAX as u32 {
        return false;
    }
    // SAFETY: kill with signal 0 only checks for the process; it sends nothing.
    let r = unsafe { libc::kill(pid as libc::pid_t, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

/// Removes the regular files `.NAME.PID.tmp` of `identify::io::write_atomic` directly in
/// `dir` (not in sub-folders) whose PID satisfies `remove`. Uses `symlink_metadata`: a
/// symbolic link is never followed (a link named like a temporary file is removed as a
/// link). Returns the number removed.
pub fn remove_temp_files(dir: &Path, remove: impl Fn(u32) -> bool) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    let mut n = 0;
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = temp_file_pid(&name) else {
            continue;
        };
        let p = e.path();
        let is_file_or_link = std::fs::symlink_metadata(&p).is_ok_and(|m| !m.is_dir());
        if is_file_or_link && remove(pid) && std::fs::remove_file(&p).is_ok() {
            n += 1;
        }
    }
    n
}

/// The PID of a `write_atomic` temporary file name `.NAME.PID.tmp`.
fn temp_file_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (_, pid) = rest.rsplit_once('.')?;
    if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    pid.parse().ok()
}

/// Parent and final name of an output folder; refuses `/`, `..` endings and folders that
/// contain the working directory (replacing them would delete the user's work).
fn split_out(out: &Path, check_cwd: bool) -> anyhow::Result<(PathBuf, String)> {
    let abs = std::path::absolute(out)
        .map_err(|e| anyhow::anyhow!("cannot create output folder {}: {e}", out.display()))?;
    let name = match abs.components().next_back() {
        Some(std::path::Component::Normal(n)) => n.to_string_lossy().into_owned(),
        _ => {
            return Err(Usage(format!(
                "--out {}: give a folder with a name (not `/`, `.` or `..`)",
                out.display()
            ))
            .into())
        }
    };
    let parent = abs.parent().map(Path::to_path_buf).unwrap_or_default();
    if !check_cwd {
        return Ok((parent, name));
    }
    if let (Ok(real), Ok(cwd)) = (
        std::fs::canonicalize(&abs),
        std::env::current_dir().and_then(std::fs::canonicalize),
    ) {
        if cwd.starts_with(&real) {
            return Err(Usage(format!(
                "--out {}: contains the working directory; results replace the output \
                 folder as a whole, so give a folder of its own",
                out.display()
            ))
            .into());
        }
    }
    Ok((parent, name))
}

/// A file or folder a command reads, with the flag or key that named it (for messages).
#[derive(Debug, Clone, Copy)]
pub struct Input<'a> {
    /// The flag, argument or study key that gave the path (`FORCED`, `--free`, `data.dataset`).
    pub what: &'a str,
    /// The path as the user gave it.
    pub path: &'a Path,
}

impl<'a> Input<'a> {
    /// An input named by `what`.
    pub fn new(what: &'a str, path: &'a Path) -> Input<'a> {
        Input { what, path }
    }
}

/// Where `p` is on the file system: absolute, with the symbolic links of its existing part
/// resolved and the `.` and `..` of the part that does not exist yet applied by name.
fn real_path(p: &Path) -> Option<PathBuf> {
    let abs = std::path::absolute(p).ok()?;
    let mut base = abs.as_path();
    let mut rest = Vec::new();
    loop {
        if let Ok(real) = std::fs::canonicalize(base) {
            let mut out = real;
            for c in rest.iter().rev() {
                match c {
                    std::path::Component::ParentDir => {
                        out.pop();
                    }
                    std::path::Component::Normal(n) => out.push(n),
                    _ => {}
                }
            }
            return Some(out);
        }
        rest.push(base.components().next_back()?);
        base = base.parent()?;
    }
}

/// The one rule of every writer (issue 39, row 1): no output may be, contain or lie inside
/// an input. An output folder replaced as a whole (`replaces` true, [`OutDir`]) that is or
/// contains an input would delete it; an output inside an input folder would change a data
/// set someone else may be reading. `out_flag` names the output in the message.
///
/// # Errors
/// [`Usage`] naming the output, the input and its flag.
pub fn refuse_overlap(out: &Path, out_flag: &str, inputs: &[Input<'_>]) -> anyhow::Result<()> {
    let Some(o) = real_path(out) else {
        return Ok(());
    };
    for input in inputs {
        let Some(i) = real_path(input.path) else {
            continue;
        };
        let relation = if o == i {
            "is"
        } else if i.starts_with(&o) {
            "contains"
        } else if o.starts_with(&i) {
            "lies inside"
        } else {
            continue;
        };
        return Err(Usage(format!(
            "{out_flag} {}: {relation} the input {} ({}); an output may not be, contain or lie \
             inside an input (writing it would replace or change what is read), so give \
             another {}",
            out.display(),
            input.what,
            input.path.display(),
            if out_flag == "--out" {
                "output"
            } else {
                "path"
            }
        ))
        .into());
    }
    Ok(())
}

/// Refuses an output the user named (`--out` of the single-file writers `identify`,
/// `flutter`, `lco`, `diagnose --blind --shard`; the output file of `sweep` and `merge`)
/// when it is a symbolic link: writing through it would put the results wherever the link
/// points, as [`OutDir::begin`] refuses for the folder writers (issue 39, row 7).
///
/// # Errors
/// [`Usage`] naming the flag and the path.
pub fn refuse_symlink(out: &Path, flag: &str) -> anyhow::Result<()> {
    match std::fs::symlink_metadata(out) {
        Ok(m) if m.file_type().is_symlink() => Err(Usage(format!(
            "{flag} {}: is a symbolic link; give the {} itself",
            out.display(),
            if m.is_dir() || out.is_dir() {
                "folder"
            } else {
                "file"
            }
        ))
        .into()),
        _ => Ok(()),
    }
}

/// The lock `P/.NAME.aeroform-lock` of an output folder, held until dropped.
pub struct Lock {
    path: PathBuf,
}

impl Lock {
    /// Takes the lock of `parent/name`, taking over the lock of a dead process (with a
    /// message on stderr).
    ///
    /// # Errors
    /// Another live process holds the lock (its PID and the lock file are named), or the
    /// lock file cannot be created.
    pub fn acquire(parent: &Path, name: &str) -> anyhow::Result<Lock> {
        let path = parent.join(format!(".{name}.aeroform-lock"));
        // The PID is written to a private file first and the lock appears by a hard link
        // (atomic, fails when the lock exists): no process ever sees an empty lock, so two
        // runs started in the same instant cannot both take it for a stale one (issue 27,
        // row 9).
        let pid_file = parent.join(format!(".{name}.aeroform-lock.{}.tmp", std::process::id()));
        *PENDING_LOCK.lock().unwrap_or_else(|p| p.into_inner()) =
            Some((pid_file.clone(), path.clone()));
        let write_pid = || -> std::io::Result<()> {
            use std::io::Write;
            let _ = std::fs::remove_file(&pid_file);
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&pid_file)?;
            writeln!(f, "{}", std::process::id())?;
            f.sync_all()
        };
        write_pid().map_err(|e| {
            anyhow::anyhow!(
                "cannot create output folder {}: lock {}: {e}",
                parent.join(name).display(),
                pid_file.display()
            )
        })?;
        let result = Self::link_lock(parent, name, &pid_file, path);
        let mut pending = PENDING_LOCK.lock().unwrap_or_else(|p| p.into_inner());
        let _ = std::fs::remove_file(&pid_file);
        if result.is_err() {
            *pending = None;
        }
        result
    }

    fn link_lock(
        parent: &Path,
        name: &str,
        pid_file: &Path,
        path: PathBuf,
    ) -> anyhow::Result<Lock> {
        for _ in 0..5 {
            match std::fs::hard_link(pid_file, &path) {
                Ok(()) => return Ok(Lock { path }),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let text = std::fs::read_to_string(&path).unwrap_or_default();
                    let pid: Option<u32> = text.trim().parse().ok();
                    match pid {
                        Some(p) if p != std::process::id() && pid_alive(p) => {
                            anyhow::bail!(
                                "{} is being written by another aeroform process (PID {p}, \
                                 lock {}); wait for it to finish",
                                parent.join(name).display(),
                                path.display()
                            );
                        }
                        _ => {
                            eprintln!(
                                "note: taking over the stale lock {} of {}",
                                path.display(),
                                match pid {
                                    Some(p) => format!("process {p}, which no longer runs"),
                                    None => "an unknown process (unreadable PID)".into(),
                                }
                            );
                            // only the lock read above: another process may have taken
                            // over the stale lock in between (then this one retries)
                            let again = std::fs::read_to_string(&path).unwrap_or_default();
                            if again == text {
                                remove_entry(&path);
                            }
                        }
                    }
                }
                Err(e) => anyhow::bail!(
                    "cannot create output folder {}: lock {}: {e}",
                    parent.join(name).display(),
                    path.display()
                ),
            }
        }
        anyhow::bail!("cannot take the lock {}", path.display())
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        let mut pending = PENDING_LOCK.lock().unwrap_or_else(|p| p.into_inner());
        let _ = std::fs::remove_file(&self.path);
        if pending.as_ref().is_some_and(|(_, l)| *l == self.path) {
            *pending = None;
        }
    }
}

/// Removes work folders (`.X.aeroform-staging.PID`, `.X.aeroform-old.PID`) and lock PID
/// files (`.X.aeroform-lock.PID.tmp`) of dead processes in `parent`, without following
/// symbolic links; says so on stderr.
fn clean_dead_work_folders(parent: &Path) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        // the private PID file a killed process left while taking a lock
        // (`.X.aeroform-lock.PID.tmp`, see `Lock::acquire`)
        let lock_pid = temp_file_pid(&name).filter(|_| name.contains(".aeroform-lock."));
        let Some(pid) = identify::io::work_folder_pid(&name)
            .map(|(_, p)| p)
            .or(lock_pid)
        else {
            continue;
        };
        if pid == std::process::id() || pid_alive(pid) {
            continue;
        }
        eprintln!(
            "note: removing {}, left by process {pid}, which no longer runs",
            e.path().display()
        );
        remove_entry(&e.path());
    }
}

/// An output folder written as a whole (module documentation).
pub struct OutDir {
    out: PathBuf,
    staging: PathBuf,
    command: String,
    /// `--force`: replace a folder holding files aeroform did not write.
    force: bool,
    lock: Option<Lock>,
    /// Parent folders of `out` this command created (removed again, when empty, if it
    /// fails before the swap).
    created: Vec<PathBuf>,
}

impl OutDir {
    /// Prepares to write `out`: lock, cleanup of dead work folders, the check of an
    /// existing folder, and a fresh staging folder holding the incomplete-marker.
    /// `command` is recorded in the completion marker.
    ///
    /// `inputs` are every file and folder the command reads: `out` may not be, contain or
    /// lie inside one of them ([`refuse_overlap`]; `--force` does not lift this).
    ///
    /// # Errors
    /// [`Usage`] when `out` is `/`, contains the working directory, is, contains or lies
    /// inside an input, is a file or a symbolic link, or is a non-empty folder without
    /// [`COMPLETE_MARKER`] and `force` is false; an error naming the folder when it cannot
    /// be created or is locked.
    pub fn begin(
        out: &Path,
        command: &str,
        force: bool,
        inputs: &[Input<'_>],
    ) -> anyhow::Result<OutDir> {
        let (parent, name) = split_out(out, true)?;
        refuse_overlap(out, "--out", inputs)?;
        let created = create_dirs(&parent)
            .map_err(|e| anyhow::anyhow!("cannot create output folder {}: {e}", out.display()))?;
        // a refusal below leaves no folder this command created (the lock, the only
        // file it put there, is gone by then)
        Self::begin_in(out, command, force, &parent, &name, created.clone()).inspect_err(|_| {
            remove_created(&created);
        })
    }

    fn begin_in(
        out: &Path,
        command: &str,
        force: bool,
        parent: &Path,
        name: &str,
        created: Vec<PathBuf>,
    ) -> anyhow::Result<OutDir> {
        let lock = Lock::acquire(parent, name)?;
        let dest = parent.join(name);
        let staging = parent.join(format!(".{name}.aeroform-staging.{}", std::process::id()));
        remove_entry(&staging); // a leftover of an earlier process with our PID
                                // registered before anything is created, so that an interrupt from here on
                                // removes whatever exists of the staging folder and the lock; from here on this
                                // thread removes the staging path only holding the state mutex (an interrupt
                                // blocks the path with a file while it cleans up)
        set_active(Some(Active::Staging {
            out: dest.clone(),
            staging: staging.clone(),
            lock: lock.path.clone(),
        }));
        clean_dead_work_folders(parent);
        let refused = |e: anyhow::Error| {
            set_active(None);
            e
        };
        match std::fs::symlink_metadata(&dest) {
            Err(_) => {}
            Ok(m) if m.file_type().is_symlink() => {
                return Err(refused(
                    Usage(format!(
                        "--out {}: is a symbolic link; give the folder itself",
                        out.display()
                    ))
                    .into(),
                ))
            }
            Ok(m) if !m.is_dir() => {
                return Err(refused(
                    Usage(format!(
                        "cannot create output folder {}: a file of that name exists",
                        out.display()
                    ))
                    .into(),
                ))
            }
            Ok(_) => {
                if !force {
                    if let Some(why) = not_ours(&dest) {
                        return Err(refused(
                            Usage(format!(
                                "--out {}: {why}; the new results replace the folder as a \
                                 whole, so choose another folder or pass --force to replace it",
                                out.display()
                            ))
                            .into(),
                        ));
                    }
                }
            }
        }
        std::fs::create_dir(&staging)
            .and_then(|()| std::fs::write(staging.join(INCOMPLETE_MARKER), command.as_bytes()))
            .map_err(|e| {
                let mut g = ACTIVE.lock().unwrap_or_else(|p| p.into_inner());
                remove_entry(&staging);
                *g = None;
                anyhow::anyhow!(
                    "cannot create output folder {} (staging {}): {e}",
                    out.display(),
                    staging.display()
                )
            })?;
        Ok(OutDir {
            out: dest,
            staging,
            command: command.to_string(),
            force,
            lock: Some(lock),
            created,
        })
    }

    /// The folder to write into (the staging folder).
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Marks the staging folder complete and moves it into place; the previous results
    /// are deleted after the swap.
    ///
    /// # Errors
    /// Writing the marker or the rename fails (the previous results are then kept).
    pub fn commit(mut self) -> anyhow::Result<PathBuf> {
        let guard = ACTIVE.lock().unwrap_or_else(|p| p.into_inner());
        // the check of `begin` again: a file put into the folder while this command ran is
        // not deleted by the swap (issue 39, row 2a)
        if !self.force && std::fs::symlink_metadata(&self.out).is_ok() {
            if let Some(why) = not_ours(&self.out) {
                drop(guard);
                return Err(Usage(format!(
                    "--out {}: {why} (they appeared while this command ran); they are kept and \
                     the new results were not written: run again, into another folder or \
                     with --force",
                    self.out.display()
                ))
                .into());
            }
        }
        let files = toml::Value::Array(
            listing(&self.staging)
                .into_iter()
                .map(toml::Value::String)
                .collect(),
        );
        let marker = format!(
            "format = \"aeroform-output/1\"\ncommand = {}\nfiles = {files}\n",
            toml::Value::String(self.command.clone())
        );
        identify::io::write_atomic(&self.staging.join(COMPLETE_MARKER), marker.as_bytes())?;
        std::fs::remove_file(self.staging.join(INCOMPLETE_MARKER)).map_err(|e| {
            anyhow::anyhow!("{}: {e}", self.staging.join(INCOMPLETE_MARKER).display())
        })?;
        swap_into_place(&self.staging, &self.out)?;
        drop(guard);
        set_active(None);
        self.lock.take();
        Ok(self.out.clone())
    }
}

impl Drop for OutDir {
    /// Not committed (an error or a panic): the staging folder is removed, the previous
    /// results stay, and parent folders this command created are removed when empty.
    fn drop(&mut self) {
        if self.lock.is_some() {
            // the state first: while an interrupt cleans up, this waits for the exit
            let mut g = ACTIVE.lock().unwrap_or_else(|p| p.into_inner());
            remove_entry(&self.staging);
            *g = None;
            drop(g);
            self.lock.take();
            remove_created(&self.created);
        }
    }
}

/// Every file and symbolic link below `dir` (symbolic links not followed), as relative
/// paths with `/`, sorted, without the two folder markers: what a completion marker lists.
fn listing(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(dir.join(&rel)) else {
            continue;
        };
        for e in entries.flatten() {
            let r = rel.join(e.file_name());
            let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
            if is_dir {
                stack.push(r);
            } else {
                let s = r.to_string_lossy().replace('\\', "/");
                if s != COMPLETE_MARKER && s != INCOMPLETE_MARKER {
                    out.push(s);
                }
            }
        }
    }
    out.sort();
    out
}

/// Why an existing output folder may not be replaced without `--force`, or `None` when it
/// may: empty, or holding exactly what its completion marker lists (a marker of an earlier
/// version without a list vouches for the whole folder). Files its marker does not list
/// (another command wrote one into it) are named, at most five.
fn not_ours(dest: &Path) -> Option<String> {
    let empty = std::fs::read_dir(dest).is_ok_and(|mut d| d.next().is_none());
    if empty {
        return None;
    }
    let marker = dest.join(COMPLETE_MARKER);
    let Ok(text) = identify::io::read_text(&marker) else {
        return Some(format!(
            "the folder exists and holds files aeroform did not write (no {COMPLETE_MARKER})"
        ));
    };
    let listed: Option<Vec<String>> = text
        .parse::<toml::Table>()
        .ok()
        .and_then(|t| t.get("files").cloned())
        .and_then(|f| f.try_into().ok());
    let mut listed = listed?;
    listed.sort();
    let foreign: Vec<String> = listing(dest)
        .into_iter()
        .filter(|f| listed.binary_search(f).is_err())
        .collect();
    if foreign.is_empty() {
        return None;
    }
    let shown: Vec<&str> = foreign.iter().take(5).map(String::as_str).collect();
    Some(format!(
        "the folder holds {} file(s) its {COMPLETE_MARKER} does not list ({}{})",
        foreign.len(),
        crate::ui::escape(&shown.join(", ")),
        if foreign.len() > 5 { ", …" } else { "" }
    ))
}

/// Moves `staging` to `dest`: a plain rename when `dest` is absent, else an atomic
/// exchange (Linux `renameat2`), else rename `dest` aside, rename `staging` in, and put
/// `dest` back if that fails. Whatever was at `dest` is deleted afterwards.
fn swap_into_place(staging: &Path, dest: &Path) -> anyhow::Result<()> {
    let ctx =
        |e: std::io::Error| anyhow::anyhow!("moving the results into {}: {e}", dest.display());
    if std::fs::symlink_metadata(dest).is_err() {
        return std::fs::rename(staging, dest).map_err(ctx);
    }
    if exchange(staging, dest).is_ok() {
        remove_entry(staging); // now holds the previous results
        return Ok(());
    }
    let name = dest.file_name().unwrap_or_default().to_string_lossy();
    let old = dest.with_file_name(format!(".{name}.aeroform-old.{}", std::process::id()));
    remove_entry(&old);
    std::fs::rename(dest, &old).map_err(ctx)?;
    if let Err(e) = std::fs::rename(staging, dest) {
        let _ = std::fs::rename(&old, dest);
        return Err(ctx(e));
    }
    remove_entry(&old);
    Ok(())
}

#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    let ca = std::ffi::CString::new(a.as_os_str().as_bytes())?;
    let cb = std::ffi::CString::new(b.as_os_str().as_bytes())?;
    // SAFETY: two valid NUL-terminated paths; renameat2 does not keep the pointers.
    let r = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if r == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

#[cfg(not(target_os = "linux"))]
fn exchange(_: &Path, _: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

/// A shared output folder into which a command writes single files atomically
/// (`identify`, `flutter`, `lco`, `diagnose --blind N --shard i/n`): created if missing;
/// temporary files of dead processes in it are removed; an interrupt removes this
/// process's temporary files; dropped while still empty (the command failed before
/// writing), the folders it created are removed again.
pub struct SharedDir {
    /// The folder and its parents this command created, deepest first.
    created: Vec<PathBuf>,
    /// The folder's lock (the one [`OutDir`] takes): no folder writer replaces the folder
    /// while a file is written into it, and two commands never write into it at once
    /// (issue 39, row 2b: `identify` beside `diagnose` on one folder lost its result).
    lock: Option<Lock>,
}

impl SharedDir {
    /// Prepares `dir` for the files `written` (paths inside `dir` or anywhere, e.g.
    /// `--timing-json`): none of them may be or lie inside one of `inputs`
    /// ([`refuse_overlap`]); `dir` itself may hold inputs, since only the named files are
    /// replaced. Takes the folder's lock.
    ///
    /// # Errors
    /// [`Usage`] when a written file is or lies inside an input; the folder cannot be
    /// created or another live aeroform process holds its lock (named in the message).
    pub fn begin(dir: &Path, written: &[&Path], inputs: &[Input<'_>]) -> anyhow::Result<SharedDir> {
        for w in written {
            refuse_overlap(w, "output file", inputs)?;
        }
        let created = create_dirs(dir)
            .map_err(|e| anyhow::anyhow!("cannot create output folder {}: {e}", dir.display()))?;
        let (parent, name) = split_out(dir, false)?;
        let lock = Lock::acquire(&parent, &name).inspect_err(|_| remove_created(&created))?;
        // a lock PID file of a process killed while taking this lock (the kill campaign)
        clean_dead_work_folders(&parent);
        let n = remove_temp_files(dir, |pid| pid != std::process::id() && !pid_alive(pid));
        if n > 0 {
            eprintln!(
                "note: removed {n} temporary file(s) of dead processes in {}",
                dir.display()
            );
        }
        set_active(Some(Active::Shared {
            dir: dir.to_path_buf(),
            lock: lock.path.clone(),
        }));
        Ok(SharedDir {
            created,
            lock: Some(lock),
        })
    }
}

impl Drop for SharedDir {
    /// Unregisters the folder and releases its lock; removes the folders
    /// [`SharedDir::begin`] created if they are still empty (after a success the result file
    /// keeps them).
    fn drop(&mut self) {
        set_active(None);
        self.lock.take();
        remove_created(&self.created);
    }
}

/// Refuses to read an unfinished aeroform folder (`plot`; data-set readers check the same
/// through `identify::dataset::read_dataset`).
///
/// # Errors
/// [`Usage`] with the reason of `identify::io::check_complete_folder`.
pub fn check_complete(dir: &Path) -> anyhow::Result<()> {
    identify::io::check_complete_folder(dir).map_err(|e| Usage(e.to_string()).into())
}

/// Writes the document atomically into its folder, registered as a shared folder: an
/// interrupt removes this process's temporary file, and temporary files of dead processes
/// there are removed first (the kill campaign of tests/campaign.rs found `merge` leaving
/// `.OUT.PID.tmp` after SIGINT).
pub fn write_json(
    path: &std::path::Path,
    v: &serde_json::Value,
    inputs: &[Input<'_>],
) -> anyhow::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    crate::outdir::refuse_symlink(path, "output file")?;
    let _shared = crate::outdir::SharedDir::begin(dir, &[path], inputs)?;
    identify::io::write_atomic(path, format!("{v:#}\n").as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_file_names_are_parsed() {
        assert_eq!(temp_file_pid(".flutter.json.123.tmp"), Some(123));
        assert_eq!(temp_file_pid(".a.1.tmp"), Some(1));
        assert_eq!(temp_file_pid("a.1.tmp"), None);
        assert_eq!(temp_file_pid(".a.x1.tmp"), None);
        assert_eq!(temp_file_pid(".a.1.json"), None);
    }

    /// A SIGKILL while a lock is taken leaves its private PID file (the kill campaign of
    /// tests/campaign.rs found it after a clean run): the next writer removes it, and a live
    /// process's file and other names stay.
    #[test]
    fn a_dead_process_lock_pid_file_is_removed() {
        let dir = tempfile::tempdir().unwrap();
        let dead = dir
            .path()
            .join(format!(".o.aeroform-lock.{}.tmp", u32::MAX));
        let live = dir
            .path()
            .join(format!(".o.aeroform-lock.{}.tmp", std::process::id()));
        let other = dir.path().join(format!(".notes.{}.tmp", u32::MAX));
        for p in [&dead, &live, &other] {
            std::fs::write(p, "1").unwrap();
        }
        clean_dead_work_folders(dir.path());
        assert!(!dead.exists());
        assert!(live.exists() && other.exists());
    }

    /// Issue 27 row 9: the lock is never visible without its PID (a second process would
    /// take an empty lock for a stale one): a reader polling the lock path while it is
    /// taken and released 300 times never reads it empty; no PID file is left behind.
    #[test]
    fn the_lock_never_appears_without_its_pid() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(".x.aeroform-lock");
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let (p, st) = (path.clone(), stop.clone());
        let reader = std::thread::spawn(move || {
            let (mut seen, mut empty) = (0usize, 0usize);
            while !st.load(std::sync::atomic::Ordering::Relaxed) {
                if let Ok(t) = std::fs::read_to_string(&p) {
                    seen += 1;
                    if t.trim().is_empty() {
                        empty += 1;
                    }
                }
            }
            (seen, empty)
        });
        for _ in 0..300 {
            let l = Lock::acquire(dir.path(), "x").unwrap();
            drop(l);
        }
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        let (seen, empty) = reader.join().unwrap();
        assert_eq!(empty, 0, "the lock was read empty {empty} of {seen} times");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().flatten().collect();
        assert!(left.is_empty(), "{left:?}");
    }

    #[test]
    fn own_pid_is_alive_and_pid_zero_is_not() {
        assert!(pid_alive(std::process::id()));
        assert!(!pid_alive(0));
        assert!(!pid_alive(u32::MAX));
    }

    #[test]
    fn temp_cleanup_removes_links_not_their_targets() {
        let dir = tempfile::tempdir().unwrap();
        let outside = dir.path().join("outside.txt");
        std::fs::write(&outside, b"keep").unwrap();
        let d = dir.path().join("d");
        std::fs::create_dir(&d).unwrap();
        std::os::unix::fs::symlink(&outside, d.join(".x.999999.tmp")).unwrap();
        std::fs::create_dir(d.join(".sub.999999.tmp")).unwrap();
        std::fs::write(d.join(".y.999999.tmp"), b"t").unwrap();
        assert_eq!(remove_temp_files(&d, |_| true), 2);
        assert_eq!(std::fs::read(&outside).unwrap(), b"keep");
        assert!(
            d.join(".sub.999999.tmp").is_dir(),
            "folders are not temp files"
        );
    }
}
