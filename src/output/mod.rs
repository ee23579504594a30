//! Run outputs: `history.csv`, `summary.json`, and VTK fields (`fields/*.vtu`, `fields.pvd`),
//! and the lock of an output folder in use (`lock.rs`). Host-side only, no GPU twin.

pub mod fields;
pub mod history;
pub mod lock;
pub mod summary;

use std::path::Path;

use crate::error::{Error, Result};

pub(crate) fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Write {
        path: dir.to_path_buf(),
        source,
    })
}

/// Writes `text` to `path` through a temporary file in the same folder and a rename, so that a
/// crash or an interruption never leaves `path` empty or cut short (files rewritten during a run:
/// `fields.pvd`, `summary.json`).
pub(crate) fn write_file(path: &Path, text: impl AsRef<[u8]>) -> Result<()> {
    write_pieces(path, &[text.as_ref()])
}

/// [`write_file`] of the concatenation of `pieces`, without concatenating them in memory.
pub(crate) fn write_pieces(path: &Path, pieces: &[impl AsRef<[u8]>]) -> Result<()> {
    use std::io::Write as _;
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = std::path::PathBuf::from(tmp);
    std::fs::File::create(&tmp)
        .and_then(|f| {
            let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
            for p in pieces {
                w.write_all(p.as_ref())?;
            }
            w.flush()
        })
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|source| {
            let _ = std::fs::remove_file(&tmp);
            Error::Write {
                path: path.to_path_buf(),
                source,
            }
        })
}
