//! Files read whole, within a cap decided before the read: a mesh file, a checkpoint, a run's
//! output files read back by `plot`, a verification case, `/proc/meminfo`
//! ([`available_memory`]). [`read_capped`] refuses what is not a
//! regular file (a FIFO, a device such as `/dev/zero`, a folder) before opening it, refuses a
//! file whose size is over the cap, and reads through [`std::io::Read::take`] so that a file
//! growing while it is read (or lying about its size) still stops at the cap. Host-side only.

use std::io::Read as _;
use std::path::Path;

/// The bytes of the regular file `path`, at most `cap` of them.
///
/// # Errors
/// A sentence (to be prefixed with the file's name): the file cannot be opened or read, is not
/// a regular file, or has more than `cap` bytes.
pub fn read_capped(path: &Path, cap: u64) -> Result<Vec<u8>, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read it: {e}"))?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a folder"
        } else {
            "not a regular file (a device, a FIFO or a socket)"
        };
        return Err(format!(
            "it is {kind}: only regular files are read, so that the size is known before the read"
        ));
    }
    let too_big = |n: u64| format!("it has {n} bytes, more than the {} read at most", show(cap));
    if meta.len() > cap {
        return Err(too_big(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)
        .and_then(|f| f.take(cap + 1).read_to_end(&mut bytes))
        .map_err(|e| format!("cannot read it: {e}"))?;
    if bytes.len() as u64 > cap {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// The memory this machine has available (`MemAvailable` of `/proc/meminfo`), if known.
pub fn available_memory() -> Option<u64> {
    let text = read_capped(Path::new("/proc/meminfo"), 1 << 20)
        .ok()
        .and_then(|b| String::from_utf8(b).ok())?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// A byte count in the largest binary unit that divides it (`64 MiB`, `1 GiB`, `100 bytes`).
pub fn show(bytes: u64) -> String {
    for (shift, unit) in [(40, "TiB"), (30, "GiB"), (20, "MiB"), (10, "KiB")] {
        if bytes >= 1 << shift && bytes.is_multiple_of(1 << shift) {
            return format!("{} {unit}", bytes >> shift);
        }
    }
    format!("{bytes} bytes")
}
