//! Run outputs: `history.csv`, `summary.json`, and VTK fields (`fields/*.vtu`, `fields.pvd`).

pub mod fields;
pub mod history;
pub mod summary;

use std::path::Path;

use crate::error::{Error, Result};

pub(crate) fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Write {
        path: dir.to_path_buf(),
        source,
    })
}

pub(crate) fn write_file(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|source| Error::Write {
        path: path.to_path_buf(),
        source,
    })
}
