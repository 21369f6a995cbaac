//! Output folders as transactions: what a command writes appears whole or not at all, a
//! second writer of the same folder is refused, a folder holding anything else is never
//! touched, and a command killed at any moment leaves a folder that the next run into it
//! either completes or cleans.
//!
//! A [`Transaction`] on a folder `DIR`:
//!
//! 1. **Validate** (before anything is written): `DIR` is a folder or can be made one (a file
//!    or a dangling link in the way is named as such).
//! 2. **Lock**: an advisory lock on `DIR/.shadowbench-lock` ([`LOCK`]) taken without waiting
//!    (`flock`, through `std::fs::File::try_lock`), whose content names the holder (process,
//!    command, start). A second writer is refused with [`PublishError::Busy`] naming it. The
//!    kernel drops the lock of a killed process, so a lock never outlives its holder but for
//!    a moment: a helper the holder had just started (`git`, asked for the run's provenance)
//!    keeps a copy of the lock's descriptor until it runs its own program. A lock held while
//!    the process that named itself in it has exited is waited for, up to
//!    [`EXITED_HOLDER_WAIT`], before the folder is called busy (a report killed and run again
//!    at once was refused so on a loaded machine, naming the killed process). A holder on
//!    another machine (a folder shared between nodes) looks exited here, so its refusal comes
//!    after that wait.
//! 3. **Recover**: a staging folder left by a killed writer (`DIR/.shadowbench-staging`,
//!    [`STAGING`]) is finished when it was complete (its manifest written: the kill came while
//!    publishing) and removed otherwise (the kill came while computing): the folder is then as
//!    the last finished command left it.
//! 4. **Check ownership**: every file in `DIR` must be listed by its manifest ([`MANIFEST`],
//!    or the text manifest of earlier versions, [`LEGACY_MANIFEST`]), else
//!    [`PublishError::Foreign`] names the first one in path order; a manifest of another kind
//!    of output (a report's folder given to `render`) is [`PublishError::OtherKind`]. Nothing
//!    has been removed: the earlier output stays until the new one replaces it.
//! 5. **Stage**: the command writes every file under [`Transaction::staging`].
//! 6. **Commit** ([`Transaction::commit`]): the staged files' manifest (path, size, SHA-256)
//!    is written into the staging folder (renamed into place: its presence marks the staging
//!    as complete); the earlier manifest's list is kept in the staging folder ([`REPLACES`]) and
//!    the earlier manifest removed; the earlier files the new output does not have are removed;
//!    each staged file is renamed over its final name; the manifest is renamed into `DIR`
//!    last. A kill between those steps leaves a complete staging folder, which step 3 of the
//!    next run finishes from where it stopped.
//!
//! A transaction dropped without a commit (an error, a refusal) removes its staging folder,
//! its lock file and the folders it created, so a refused or failed command changes no file
//! of `DIR`. Renames within one folder tree are atomic on one file system, so no file ever
//! appears under its final name before it is whole; a full disk fails while staging, before
//! any final name is touched.
//!
//! Readers check what they read against the manifest ([`verify`]): every listed file present
//! with its size and hash (`report merge` verifies every shard this way).
//!
//! The default reference cache of a report folder (`cache/`, [`CACHE_DIR`]) is
//! outside the transaction: its entries are content-addressed, written by rename and verified
//! on read (`crate::cache`), and it outlives the reports written beside it.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::fs::File;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// The manifest of an output folder: JSON, a [`Manifest`].
pub const MANIFEST: &str = ".shadowbench-manifest";

/// The manifest of report folders written by earlier versions: one path a line after a
/// comment line. Read to know which files of such a folder are a report's; never written.
pub const LEGACY_MANIFEST: &str = ".shadowbench-report";

/// The staging folder, inside the output folder.
pub const STAGING: &str = ".shadowbench-staging";

/// The lock file, inside the output folder; it exists while a command writes the folder.
pub const LOCK: &str = ".shadowbench-lock";

/// Inside a complete staging folder being published: the files of the output it replaces
/// (JSON list of paths), so that a publish interrupted by a kill can be finished.
pub const REPLACES: &str = ".shadowbench-replaces";

/// The default reference cache's folder in a report folder (`report --cache`): outside every
/// transaction, never an output's file, kept from report to report.
pub const CACHE_DIR: &str = "cache";

/// What an output folder holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A report (`report`, `report merge`).
    Report,
    /// One shard of a report (`report --shard K/N`).
    Shard,
    /// One run's files (`render`, `compare`).
    Run,
    /// A frame for another renderer (`frame`).
    Frame,
}

impl Kind {
    /// The name used in messages.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Report => "report",
            Kind::Shard => "report shard",
            Kind::Run => "run (render or compare)",
            Kind::Frame => "frame (frame)",
        }
    }

    /// Whether an output of this kind may replace one of `earlier`'s: reports and shards
    /// replace each other (a folder reused for a sharded run of the same suite), runs replace
    /// runs, frames frames.
    fn replaces(self, earlier: Kind) -> bool {
        matches!(
            (self, earlier),
            (Kind::Report | Kind::Shard, Kind::Report | Kind::Shard)
                | (Kind::Run, Kind::Run)
                | (Kind::Frame, Kind::Frame)
        )
    }
}

/// One file of a manifest.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Entry {
    /// Path relative to the folder, `/` between names.
    pub path: String,
    /// Size in bytes.
    pub size: u64,
    /// SHA-256 of the content, lower-case hex.
    pub sha256: String,
}

/// An output folder's manifest ([`MANIFEST`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Manifest {
    /// What the folder holds.
    pub kind: Kind,
    /// The version of the workbench that wrote it.
    pub version: String,
    /// Every file the output has, in path order.
    pub files: Vec<Entry>,
}

/// An output folder could not be used, or a folder's files do not match its manifest. The
/// messages of the first four name no folder: the caller names it with its flag.
#[derive(Debug, thiserror::Error)]
pub enum PublishError {
    /// Something that is not a folder is where the folder should be.
    #[error("{why}")]
    NotAFolder {
        /// The path.
        dir: PathBuf,
        /// What is there.
        why: String,
    },
    /// Another command is writing the folder.
    #[error(
        "another shadowbench is writing this folder ({holder}); wait for it to finish, or \
         choose another folder"
    )]
    Busy {
        /// The folder.
        dir: PathBuf,
        /// Who holds it, from the lock file.
        holder: String,
    },
    /// The folder holds a file no earlier output listed.
    #[error(
        "holds {file}, which shadowbench did not write; an output folder holds only its own \
         files (remove them, or choose another folder)"
    )]
    Foreign {
        /// The first such file, in path order.
        file: PathBuf,
    },
    /// The folder holds another kind of output.
    #[error("holds a {found}, which a {wanted} does not replace (choose another folder)", found = .found.name(), wanted = .wanted.name())]
    OtherKind {
        /// The folder.
        dir: PathBuf,
        /// What it holds.
        found: Kind,
        /// What was to be written.
        wanted: Kind,
    },
    /// The folder has no manifest: it was not written whole by this version.
    #[error("{dir}: no {MANIFEST} (the folder was not written whole, or by an earlier version: write it again)")]
    NoManifest {
        /// The folder.
        dir: PathBuf,
    },
    /// A file does not match the manifest.
    #[error("{path}: {why}")]
    Mismatch {
        /// The file.
        path: PathBuf,
        /// How it differs.
        why: String,
    },
    /// Reading or writing failed.
    #[error("{path}: {message}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

impl PublishError {
    /// Whether the error is the user's input (a folder that cannot be used, or files that
    /// do not match their manifest) rather than a failure of the machine.
    pub fn is_input(&self) -> bool {
        !matches!(self, PublishError::Io { .. })
    }
}

fn io_err(path: &Path, e: &std::io::Error) -> PublishError {
    PublishError::Io { path: path.to_owned(), message: e.to_string() }
}

/// Lower-case hex of `bytes`.
fn hex(bytes: &[u8]) -> String {
    use std::fmt::Write as _;
    bytes.iter().fold(String::with_capacity(2 * bytes.len()), |mut s, b| {
        let _ = write!(s, "{b:02x}");
        s
    })
}

/// The size and SHA-256 of the file at `path`, read in blocks.
fn digest(path: &Path) -> Result<(u64, String), PublishError> {
    let mut f = File::open(path).map_err(|e| io_err(path, &e))?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    let mut size = 0u64;
    loop {
        let n = f.read(&mut buf).map_err(|e| io_err(path, &e))?;
        if n == 0 {
            break;
        }
        size += n as u64;
        h.update(&buf[..n]);
    }
    Ok((size, hex(&h.finalize())))
}

/// `rel`'s components joined by `/`.
fn slash_path(rel: &Path) -> String {
    let names: Vec<String> =
        rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    names.join("/")
}

/// Whether `rel` (relative to an output folder; `is_dir` when it is a folder) is one of the
/// folder's own bookkeeping entries or the reference cache's folder, which are never an
/// output's files.
fn is_bookkeeping(rel: &Path, is_dir: bool) -> bool {
    if rel.components().count() != 1 {
        return false;
    }
    let name = rel.as_os_str().to_string_lossy();
    matches!(name.as_ref(), MANIFEST | LEGACY_MANIFEST | LOCK | STAGING)
        || (is_dir && name == CACHE_DIR)
}

/// Walks the files under `dir` in path order (links count as files and are not followed,
/// bookkeeping entries are skipped), calling `visit` with each path relative to `dir` until
/// it returns `false`. A folder that does not exist has no files.
fn walk(dir: &Path, visit: &mut dyn FnMut(&Path) -> bool) -> Result<(), PublishError> {
    fn go(
        root: &Path,
        rel: &Path,
        visit: &mut dyn FnMut(&Path) -> bool,
    ) -> Result<bool, PublishError> {
        let here = root.join(rel);
        let entries = match std::fs::read_dir(&here) {
            Ok(e) => e,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && rel.as_os_str().is_empty() => {
                return Ok(true)
            }
            Err(e) => return Err(io_err(&here, &e)),
        };
        let mut names = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|e| io_err(&here, &e))?;
            let kind = entry.file_type().map_err(|e| io_err(&entry.path(), &e))?;
            names.push((rel.join(entry.file_name()), kind.is_dir()));
        }
        names.sort();
        for (name, is_dir) in names {
            if is_bookkeeping(&name, is_dir) {
                continue;
            }
            let more = if is_dir { go(root, &name, visit)? } else { visit(&name) };
            if !more {
                return Ok(false);
            }
        }
        Ok(true)
    }
    go(dir, Path::new(""), visit).map(|_| ())
}

/// Every file under `dir` but the bookkeeping, relative and in path order.
fn files_under(dir: &Path) -> Result<Vec<PathBuf>, PublishError> {
    let mut files = Vec::new();
    walk(dir, &mut |rel| {
        files.push(rel.to_owned());
        true
    })?;
    Ok(files)
}

/// Reads `dir`'s manifest: the JSON one, else the earlier versions' list of paths (as a
/// report's, without sizes: [`Entry::size`] and [`Entry::sha256`] empty), else `None`.
pub fn read_manifest(dir: &Path) -> Result<Option<Manifest>, PublishError> {
    let path = dir.join(MANIFEST);
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            return serde_json::from_str(&text).map(Some).map_err(|e| PublishError::Mismatch {
                path: path.clone(),
                why: format!("not a manifest: {e}"),
            })
        }
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io_err(&path, &e)),
        Err(_) => {}
    }
    let legacy = dir.join(LEGACY_MANIFEST);
    match std::fs::read_to_string(&legacy) {
        Ok(text) => Ok(Some(Manifest {
            kind: Kind::Report,
            version: String::new(),
            files: text
                .lines()
                .filter(|l| !l.is_empty() && !l.starts_with('#'))
                .map(|l| Entry { path: l.to_owned(), size: 0, sha256: String::new() })
                .collect(),
        })),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(io_err(&legacy, &e)),
    }
}

/// Checks every file `dir`'s manifest lists: present, of its size, with its hash. Returns the
/// manifest; a folder without one is [`PublishError::NoManifest`], and a file that differs is
/// [`PublishError::Mismatch`] naming it.
pub fn verify(dir: &Path) -> Result<Manifest, PublishError> {
    let path = dir.join(MANIFEST);
    if !path.is_file() {
        return Err(PublishError::NoManifest { dir: dir.to_owned() });
    }
    let Some(manifest) = read_manifest(dir)? else {
        return Err(PublishError::NoManifest { dir: dir.to_owned() });
    };
    for e in &manifest.files {
        let file = dir.join(&e.path);
        let (size, sha) = match digest(&file) {
            Ok(d) => d,
            Err(_) if !file.exists() => {
                return Err(PublishError::Mismatch {
                    path: file,
                    why: "listed in the folder's manifest, but missing".into(),
                })
            }
            Err(err) => return Err(err),
        };
        if size != e.size {
            return Err(PublishError::Mismatch {
                path: file,
                why: format!("{size} bytes, but {} when it was written", e.size),
            });
        }
        if sha != e.sha256 {
            return Err(PublishError::Mismatch {
                path: file,
                why: "its content changed since it was written (SHA-256 differs)".into(),
            });
        }
    }
    Ok(manifest)
}

/// Writes `text` to `path` through a temporary file in the same folder, renamed over it.
fn write_atomic(path: &Path, text: &[u8]) -> Result<(), PublishError> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut f = File::create(&tmp)?;
        f.write_all(text)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io_err(path, &e));
    }
    Ok(())
}

/// Removes the folders of `rel` paths under `dir` that are left empty, deepest first.
fn remove_empty_folders(dir: &Path, rel: &[String]) {
    let mut folders: Vec<&Path> = rel
        .iter()
        .flat_map(|f| Path::new(f).ancestors().skip(1))
        .filter(|a| !a.as_os_str().is_empty())
        .collect();
    folders.sort_by(|a, b| b.components().count().cmp(&a.components().count()).then(a.cmp(b)));
    folders.dedup();
    for f in folders {
        let _ = std::fs::remove_dir(dir.join(f));
    }
}

/// Publishes the complete staging folder of `dir` (its manifest written), from wherever an
/// earlier publish stopped: steps 6's second half in the module documentation.
fn publish(dir: &Path) -> Result<(), PublishError> {
    let staging = dir.join(STAGING);
    let new: Manifest = {
        let path = staging.join(MANIFEST);
        let text = std::fs::read_to_string(&path).map_err(|e| io_err(&path, &e))?;
        serde_json::from_str(&text).map_err(|e| PublishError::Mismatch {
            path: path.clone(),
            why: format!("not a manifest: {e}"),
        })?
    };
    // The earlier output's files, kept in the staging folder before its manifest goes.
    let replaces_path = staging.join(REPLACES);
    let mut replaced: Vec<String> = match std::fs::read_to_string(&replaces_path) {
        Ok(text) => serde_json::from_str(&text).unwrap_or_default(),
        Err(_) => Vec::new(),
    };
    if let Some(earlier) = read_manifest(dir)? {
        replaced.extend(earlier.files.into_iter().map(|e| e.path));
        replaced.sort();
        replaced.dedup();
        let json = serde_json::to_vec(&replaced).map_err(|e| PublishError::Io {
            path: replaces_path.clone(),
            message: e.to_string(),
        })?;
        write_atomic(&replaces_path, &json)?;
    }
    for m in [MANIFEST, LEGACY_MANIFEST] {
        let path = dir.join(m);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io_err(&path, &e)),
            _ => {}
        }
    }
    let keep: std::collections::HashSet<&str> = new.files.iter().map(|e| e.path.as_str()).collect();
    for rel in replaced.iter().filter(|r| !keep.contains(r.as_str())) {
        let path = dir.join(rel);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io_err(&path, &e)),
            _ => {}
        }
    }
    for e in &new.files {
        let from = staging.join(&e.path);
        if !from.exists() {
            continue; // moved by the publish that was interrupted
        }
        let to = dir.join(&e.path);
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent).map_err(|err| io_err(parent, &err))?;
        }
        std::fs::rename(&from, &to).map_err(|err| io_err(&to, &err))?;
    }
    let manifest = dir.join(MANIFEST);
    std::fs::rename(staging.join(MANIFEST), &manifest).map_err(|e| io_err(&manifest, &e))?;
    remove_empty_folders(dir, &replaced);
    std::fs::remove_dir_all(&staging).map_err(|e| io_err(&staging, &e))
}

/// Step 4 of the module documentation: refuses `dir` when its manifest is of an output that
/// `kind` does not replace ([`check_kind`]), or when it holds a file its manifest does not
/// list (the first in path order, found without listing the rest).
fn check_contents(dir: &Path, kind: Kind) -> Result<(), PublishError> {
    let earlier = check_kind(dir, kind)?;
    let listed: std::collections::HashSet<String> =
        earlier.iter().flat_map(|m| m.files.iter().map(|e| e.path.clone())).collect();
    let mut foreign = None;
    walk(dir, &mut |rel| {
        if listed.contains(&slash_path(rel)) {
            true
        } else {
            foreign = Some(dir.join(rel));
            false
        }
    })?;
    match foreign {
        Some(file) => Err(PublishError::Foreign { file }),
        None => Ok(()),
    }
}

/// Refuses `dir` when its manifest is of an output that `kind` does not replace; returns the
/// manifest.
fn check_kind(dir: &Path, kind: Kind) -> Result<Option<Manifest>, PublishError> {
    let earlier = read_manifest(dir)?;
    match &earlier {
        Some(m) if !kind.replaces(m.kind) => {
            Err(PublishError::OtherKind { dir: dir.to_owned(), found: m.kind, wanted: kind })
        }
        _ => Ok(earlier),
    }
}

/// How long [`Lock::take`] waits for a lock whose named holder has exited (see the module
/// documentation).
pub const EXITED_HOLDER_WAIT: std::time::Duration = std::time::Duration::from_secs(2);

/// Whether the holder named by a lock file's `text` ("process N", first line) has exited, as
/// far as this system can tell (Linux: `/proc/N` is gone); `false` when it cannot tell.
fn holder_exited(text: &str) -> bool {
    let proc = Path::new("/proc");
    let pid = text.strip_prefix("process ").and_then(|t| {
        let digits: String = t.chars().take_while(char::is_ascii_digit).collect();
        digits.parse::<u32>().ok()
    });
    match pid {
        Some(pid) => proc.join("self").exists() && !proc.join(pid.to_string()).exists(),
        None => false,
    }
}

/// Who holds the lock of `path`, from its content; a holder that has just taken it may not
/// have written it yet, so an empty file is read again for a moment.
fn holder(path: &Path) -> String {
    for _ in 0..25 {
        if let Some(text) = std::fs::read_to_string(path).ok().filter(|t| !t.trim().is_empty()) {
            return text.trim().replace('\n', ", ");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    "a process that has not said who it is".into()
}

/// The lock of an output folder: the open lock file, locked.
struct Lock {
    file: File,
    path: PathBuf,
}

impl Lock {
    /// Takes the lock of `dir` without waiting for a holder that is running, or says who
    /// holds it; a holder that has exited is waited for (see the module documentation).
    fn take(dir: &Path) -> Result<Self, PublishError> {
        let path = dir.join(LOCK);
        let start = std::time::Instant::now();
        // The lock file is removed by its holder when it finishes, so a file opened just
        // before that is locked after it only in appearance: the lock counts when the path
        // still names the locked file.
        let mut replaced = 0;
        while replaced < 16 {
            let file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(|e| io_err(&path, &e))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    let holder = holder(&path);
                    if holder_exited(&holder) && start.elapsed() < EXITED_HOLDER_WAIT {
                        std::thread::sleep(std::time::Duration::from_millis(10));
                        continue;
                    }
                    return Err(PublishError::Busy { dir: dir.to_owned(), holder });
                }
                Err(std::fs::TryLockError::Error(e)) => return Err(io_err(&path, &e)),
            }
            if same_file(&file, &path) {
                let mut lock = Lock { file, path };
                lock.say_who()?;
                return Ok(lock);
            }
            replaced += 1;
        }
        Err(PublishError::Io {
            path: path.clone(),
            message: "the lock file kept being replaced while it was taken".into(),
        })
    }

    /// Writes the holder's process, command and start time into the lock file.
    fn say_who(&mut self) -> Result<(), PublishError> {
        let p =
            instrumentation::Provenance::capture(instrumentation::Provenance::command_line(), None);
        let text = format!(
            "process {}\ncommand `{}`\nsince {}\n",
            std::process::id(),
            p.command,
            p.timestamp
        );
        (|| {
            self.file.set_len(0)?;
            self.file.write_all(text.as_bytes())?;
            self.file.flush()
        })()
        .map_err(|e| io_err(&self.path, &e))
    }
}

impl Drop for Lock {
    fn drop(&mut self) {
        // Removed while still held; the lock itself goes with the file handle.
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Whether the open `file` is the file at `path`.
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// A command's output folder, from validation to the commit (see the module documentation).
pub struct Transaction {
    dir: PathBuf,
    staging: PathBuf,
    kind: Kind,
    /// The first folder this transaction created (removed, with what it holds, when the
    /// transaction is dropped uncommitted).
    created: Option<PathBuf>,
    lock: Option<Lock>,
    committed: bool,
}

impl Transaction {
    /// Opens `dir` for a new output of `kind`: steps 1 to 4 of the module documentation, then
    /// a fresh staging folder.
    pub fn begin(dir: &Path, kind: Kind) -> Result<Self, PublishError> {
        let not_a_folder = |why: String| PublishError::NotAFolder { dir: dir.to_owned(), why };
        if let Ok(meta) = std::fs::symlink_metadata(dir) {
            if meta.file_type().is_symlink() && !dir.exists() {
                let target = std::fs::read_link(dir).map(|t| t.display().to_string());
                return Err(not_a_folder(format!(
                    "a link to {}, which does not exist (remove the link, or make the folder it \
                     points to)",
                    target.unwrap_or_else(|_| "an unreadable target".into())
                )));
            }
            if !dir.is_dir() {
                return Err(not_a_folder(
                    "a file is in the way (the output must be a folder)".into(),
                ));
            }
        }
        if let Some(file) = dir.ancestors().skip(1).find(|a| a.exists() && !a.is_dir()) {
            return Err(not_a_folder(format!("{} is a file, not a folder", file.display())));
        }
        let created = dir
            .ancestors()
            .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
            .last()
            .map(Path::to_path_buf);
        // A folder no command is writing (no lock file, no staging) is checked before it is
        // touched at all; one that is being written or was left mid-way is checked under
        // its lock, after recovery. Without a recovery the folder's files are as the first
        // check saw them or another writer's whole output, all listed: it is walked once, and
        // only its manifest's kind is read again.
        let checked = !dir.join(LOCK).exists() && !dir.join(STAGING).exists();
        if checked {
            check_contents(dir, kind)?;
        }
        std::fs::create_dir_all(dir)
            .map_err(|e| not_a_folder(format!("cannot create the folder: {e}")))?;
        let mut t = Transaction {
            dir: dir.to_owned(),
            staging: dir.join(STAGING),
            kind,
            created,
            lock: None,
            committed: false,
        };
        t.lock = Some(match Lock::take(dir) {
            Ok(l) => l,
            Err(PublishError::Io { message, .. }) => {
                return Err(not_a_folder(format!("the folder is not writable: {message}")))
            }
            Err(e) => return Err(e),
        });
        let recovered = t.staging.exists();
        if t.staging.join(MANIFEST).is_file() {
            publish(dir)?;
        } else if recovered {
            std::fs::remove_dir_all(&t.staging).map_err(|e| io_err(&t.staging, &e))?;
        }
        if !checked || recovered {
            check_contents(dir, kind)?;
        } else {
            check_kind(dir, kind)?;
        }
        std::fs::create_dir(&t.staging).map_err(|e| io_err(&t.staging, &e))?;
        Ok(t)
    }

    /// The folder the output is written into until the commit.
    pub fn staging(&self) -> &Path {
        &self.staging
    }

    /// The output folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Publishes the staged files: step 6 of the module documentation.
    pub fn commit(mut self) -> Result<(), PublishError> {
        let mut files = Vec::new();
        for rel in files_under(&self.staging)? {
            let (size, sha256) = digest(&self.staging.join(&rel))?;
            files.push(Entry { path: slash_path(&rel), size, sha256 });
        }
        let manifest =
            Manifest { kind: self.kind, version: env!("CARGO_PKG_VERSION").to_owned(), files };
        let json = serde_json::to_vec_pretty(&manifest).map_err(|e| PublishError::Io {
            path: self.staging.join(MANIFEST),
            message: e.to_string(),
        })?;
        write_atomic(&self.staging.join(MANIFEST), &json)?;
        publish(&self.dir)?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for Transaction {
    fn drop(&mut self) {
        // Only the holder of the lock owns the staging folder: a transaction refused because
        // another command holds the folder leaves that command's staging alone.
        let holder = self.lock.is_some();
        if holder && !self.committed && !self.staging.join(MANIFEST).is_file() {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
        // The lock file goes before the folders it may leave empty.
        self.lock = None;
        if let Some(created) = &self.created {
            if holder && !self.committed {
                remove_created(created, &self.dir);
            }
        }
    }
}

/// Removes the folders from `created` down to `dir`, where nothing else was put in them.
fn remove_created(created: &Path, dir: &Path) {
    for folder in dir.ancestors() {
        if std::fs::remove_dir(folder).is_err() || folder == created {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn put(dir: &Path, rel: &str, text: &str) {
        let p = dir.join(rel);
        std::fs::create_dir_all(p.parent().expect("parent")).expect("mkdir");
        std::fs::write(p, text).expect("write");
    }

    fn tree(dir: &Path) -> Vec<(String, String)> {
        let mut out = Vec::new();
        let mut stack = vec![dir.to_owned()];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).expect("list") {
                let p = e.expect("entry").path();
                if p.is_dir() {
                    stack.push(p);
                } else {
                    let rel = p.strip_prefix(dir).expect("under").display().to_string();
                    out.push((rel, std::fs::read_to_string(&p).unwrap_or_default()));
                }
            }
        }
        out.sort();
        out
    }

    #[test]
    fn a_commit_replaces_the_earlier_output_and_lists_sizes_and_hashes() {
        let tmp = tempfile::tempdir().expect("tmp");
        let dir = tmp.path().join("out");
        let t = Transaction::begin(&dir, Kind::Report).expect("begin");
        put(t.staging(), "a.txt", "one");
        put(t.staging(), "sub/b.txt", "two");
        t.commit().expect("commit");
        let m = verify(&dir).expect("verified");
        assert_eq!(m.files.len(), 2);
        assert_eq!(m.files[0].path, "a.txt");
        assert_eq!(m.files[0].size, 3);
        let t = Transaction::begin(&dir, Kind::Report).expect("again");
        put(t.staging(), "c.txt", "three");
        t.commit().expect("commit");
        assert_eq!(
            tree(&dir),
            vec![
                (MANIFEST.to_owned(), std::fs::read_to_string(dir.join(MANIFEST)).expect("m")),
                ("c.txt".to_owned(), "three".to_owned())
            ]
        );
    }

    #[test]
    fn a_dropped_transaction_leaves_the_folder_as_it_was() {
        let tmp = tempfile::tempdir().expect("tmp");
        let dir = tmp.path().join("out");
        let t = Transaction::begin(&dir, Kind::Run).expect("begin");
        put(t.staging(), "run.json", "{}");
        t.commit().expect("commit");
        let before = tree(&dir);
        let t = Transaction::begin(&dir, Kind::Run).expect("begin");
        put(t.staging(), "run.json", "{\"new\": 1}");
        drop(t);
        assert_eq!(tree(&dir), before);
        // A folder the transaction made is gone again.
        let fresh = tmp.path().join("a/b/c");
        drop(Transaction::begin(&fresh, Kind::Run).expect("begin"));
        assert!(!tmp.path().join("a").exists());
    }

    #[test]
    fn foreign_files_other_kinds_and_busy_folders_are_refused_untouched() {
        let tmp = tempfile::tempdir().expect("tmp");
        let dir = tmp.path().join("out");
        put(&dir, "notes/mine.txt", "keep");
        let before = tree(&dir);
        let e = Transaction::begin(&dir, Kind::Run).err().expect("refused");
        assert!(
            matches!(e, PublishError::Foreign { ref file } if file.ends_with("notes/mine.txt"))
        );
        assert_eq!(tree(&dir), before);

        let runs = tmp.path().join("runs");
        let t = Transaction::begin(&runs, Kind::Run).expect("begin");
        put(t.staging(), "run.json", "{}");
        t.commit().expect("commit");
        let e = Transaction::begin(&runs, Kind::Report).err().expect("refused");
        assert!(matches!(e, PublishError::OtherKind { found: Kind::Run, .. }), "{e}");

        let held = Transaction::begin(&runs, Kind::Run).expect("begin");
        let e = Transaction::begin(&runs, Kind::Run).err().expect("busy");
        let text = e.to_string();
        assert!(matches!(e, PublishError::Busy { .. }), "{text}");
        assert!(text.contains(&format!("process {}", std::process::id())), "{text}");
        drop(held);
        drop(Transaction::begin(&runs, Kind::Run).expect("free again"));
    }

    /// A lock still held after the process named in it has exited (a helper it had started
    /// keeps the descriptor for a moment) is waited for, not called busy; one named by a
    /// running process is refused at once.
    #[test]
    fn a_lock_left_by_an_exited_holder_is_waited_for() {
        let tmp = tempfile::tempdir().expect("tmp");
        let dir = tmp.path().join("out");
        std::fs::create_dir_all(&dir).expect("folder");
        let path = dir.join(LOCK);
        // Above Linux's largest process id: no such process.
        std::fs::write(&path, "process 4294967295\ncommand `killed`\n").expect("lock file");
        assert!(holder_exited("process 4294967295\n") || !Path::new("/proc/self").exists());
        let kept = File::open(&path).expect("open");
        kept.try_lock().expect("held by the helper");
        let release = std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_millis(150));
            drop(kept);
        });
        let start = std::time::Instant::now();
        let t = Transaction::begin(&dir, Kind::Run);
        release.join().expect("released");
        if Path::new("/proc/self").exists() {
            let t = t.expect("taken once the helper let go");
            assert!(start.elapsed() >= std::time::Duration::from_millis(150));
            drop(t);
        }
        assert!(!holder_exited(&format!("process {}\n", std::process::id())));
    }

    #[test]
    fn an_interrupted_staging_is_removed_and_an_interrupted_publish_finished() {
        let tmp = tempfile::tempdir().expect("tmp");
        let dir = tmp.path().join("out");
        let t = Transaction::begin(&dir, Kind::Report).expect("begin");
        put(t.staging(), "old.txt", "old");
        put(t.staging(), "same.txt", "v1");
        t.commit().expect("commit");
        let published = tree(&dir);

        // Killed while computing: a staging folder without a manifest.
        put(&dir, &format!("{STAGING}/half.txt"), "ha");
        drop(Transaction::begin(&dir, Kind::Report).expect("begin"));
        assert_eq!(tree(&dir), published);

        // Killed while publishing: a complete staging folder, the earlier manifest already
        // moved into it and one file already renamed into place.
        let staged = dir.join(STAGING);
        put(&staged, "same.txt", "v2");
        put(&staged, "new.txt", "new");
        let m = Manifest {
            kind: Kind::Report,
            version: "0".into(),
            files: ["new.txt", "same.txt"]
                .iter()
                .map(|p| {
                    let (size, sha256) = digest(&staged.join(p)).expect("digest");
                    Entry { path: (*p).to_owned(), size, sha256 }
                })
                .collect(),
        };
        std::fs::write(staged.join(MANIFEST), serde_json::to_vec(&m).expect("json")).expect("w");
        std::fs::write(staged.join(REPLACES), r#"["old.txt","same.txt"]"#).expect("w");
        std::fs::remove_file(dir.join(MANIFEST)).expect("rm");
        std::fs::rename(staged.join("new.txt"), dir.join("new.txt")).expect("mv");
        drop(Transaction::begin(&dir, Kind::Report).expect("begin"));
        verify(&dir).expect("the finished publish verifies");
        let files: Vec<String> = tree(&dir).into_iter().map(|(p, _)| p).collect();
        assert_eq!(files, vec![MANIFEST.to_owned(), "new.txt".into(), "same.txt".into()]);
        assert_eq!(std::fs::read_to_string(dir.join("same.txt")).expect("r"), "v2");
    }

    #[test]
    fn verify_names_a_missing_or_changed_file() {
        let tmp = tempfile::tempdir().expect("tmp");
        let dir = tmp.path().join("out");
        let t = Transaction::begin(&dir, Kind::Shard).expect("begin");
        put(t.staging(), "runs.json", "[1, 2]");
        put(t.staging(), "visibility/a.exr", "exr");
        t.commit().expect("commit");
        std::fs::write(dir.join("runs.json"), "[1, 3]").expect("w");
        let e = verify(&dir).expect_err("changed");
        assert!(e.to_string().contains("runs.json") && e.to_string().contains("SHA-256"), "{e}");
        std::fs::write(dir.join("runs.json"), "[1]").expect("w");
        assert!(verify(&dir).expect_err("size").to_string().contains("bytes"));
        std::fs::write(dir.join("runs.json"), "[1, 2]").expect("w");
        std::fs::remove_file(dir.join("visibility/a.exr")).expect("rm");
        let e = verify(&dir).expect_err("missing").to_string();
        assert!(e.contains("a.exr") && e.contains("missing"), "{e}");
        assert!(matches!(verify(tmp.path()).expect_err("none"), PublishError::NoManifest { .. }));
    }

    #[test]
    fn a_dangling_link_and_a_file_in_the_way_are_named() {
        let tmp = tempfile::tempdir().expect("tmp");
        let link = tmp.path().join("link");
        std::os::unix::fs::symlink(tmp.path().join("nowhere"), &link).expect("link");
        let e = Transaction::begin(&link, Kind::Run).err().expect("dangling").to_string();
        assert!(e.contains("does not exist") && e.contains("nowhere"), "{e}");
        let file = tmp.path().join("file");
        std::fs::write(&file, "x").expect("w");
        let e = Transaction::begin(&file, Kind::Run).err().expect("file").to_string();
        assert!(e.contains("file is in the way"), "{e}");
        let e = Transaction::begin(&file.join("sub"), Kind::Run).err().expect("under").to_string();
        assert!(e.contains("is a file, not a folder"), "{e}");
    }
}
