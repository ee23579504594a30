//! The lock of an output folder in use: a run (or a restart) holds an advisory `flock` on
//! `<out>/ricochet.lock`, which holds its process id, from before it writes anything there until
//! it ends; a second run into the same folder is refused naming the folder and that process.
//! The kernel drops the lock when the process ends, however it ends (a crash, `kill -9`), so a
//! lock file left behind by a dead process is taken over; the file is removed when the run
//! ends. `ricochet plot` reads a folder without it. Host-side only, no GPU twin.

use std::fs::File;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Name of the lock file in the output folder.
pub const FILE: &str = "ricochet.lock";

/// The lock of an output folder, held until dropped.
#[derive(Debug)]
pub struct OutputLock {
    path: PathBuf,
    _file: File,
}

impl OutputLock {
    /// Takes the lock of the output folder `dir` (which exists) for this process.
    ///
    /// # Errors
    /// [`Error::InUse`] when another process holds it, naming the folder and that process;
    /// [`Error::Write`] when the lock file cannot be created or written.
    pub fn acquire(dir: &Path) -> Result<Self> {
        let path = dir.join(FILE);
        let write_err = |source| Error::Write {
            path: path.clone(),
            source,
        };
        // A run that ends removes the file while it holds the lock: one that opened the file
        // before then finds, once it has the lock, that the path names another file (or none),
        // and tries again.
        for _ in 0..100 {
            let file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .map_err(write_err)?;
            if !lock(&file) {
                let holder = crate::input::read_capped(&path, 64)
                    .ok()
                    .map(|b| String::from_utf8_lossy(&b).trim().to_string())
                    .filter(|s| !s.is_empty())
                    .unwrap_or_else(|| "unknown".into());
                return Err(Error::InUse {
                    dir: dir.to_path_buf(),
                    holder,
                });
            }
            if !same_file(&file, &path) {
                continue;
            }
            use std::io::Write as _;
            file.set_len(0).map_err(write_err)?;
            (&file)
                .write_all(format!("{}\n", std::process::id()).as_bytes())
                .map_err(write_err)?;
            return Ok(Self { path, _file: file });
        }
        Err(Error::InUse {
            dir: dir.to_path_buf(),
            holder: "unknown (its lock file kept changing)".into(),
        })
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Removed while still held (the file closes after this), see `acquire`.
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Takes an exclusive `flock` on `file` without waiting: false when another process holds one.
/// On a file system without locks (or off unix) the folder is used unlocked.
#[cfg(unix)]
fn lock(file: &File) -> bool {
    use std::os::unix::io::AsRawFd as _;
    // SAFETY: flock on a descriptor this function's caller owns; no memory is passed.
    let r = unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::EWOULDBLOCK)
}

#[cfg(not(unix))]
fn lock(_file: &File) -> bool {
    true
}

/// Whether `path` still names the file `file` is open on.
#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt as _;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_file: &File, path: &Path) -> bool {
    path.is_file()
}
