//! Reading a run's output folder back: `history.csv`, `fields.pvd` and the VTU files it lists
//! (the formats `crate::output` writes).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The largest output file read back (`history.csv`, `fields.pvd`, a VTU file).
pub const MAX_FILE_BYTES: u64 = 16 << 30;

/// The bytes of the regular file `path`, within [`MAX_FILE_BYTES`] ([`crate::input::read_capped`]).
fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    crate::input::read_capped(path, MAX_FILE_BYTES).map_err(|message| parse_error(path, message))
}

fn read_text(path: &Path) -> Result<String> {
    String::from_utf8(read_bytes(path)?).map_err(|e| {
        parse_error(
            path,
            format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        )
    })
}

fn parse_error(file: &Path, message: String) -> Error {
    Error::Parse {
        file: file.to_path_buf(),
        message,
    }
}

/// `history.csv`: its header and its rows.
#[derive(Debug, Clone)]
pub struct History {
    /// Column names.
    pub columns: Vec<String>,
    /// Rows, each with one value per column.
    pub rows: Vec<Vec<f64>>,
}

impl History {
    /// Reads `path`. A last row cut short (a run interrupted while writing it) is dropped; any
    /// other row with the wrong number of values or a value that is not a number is an error
    /// naming the line.
    ///
    /// # Errors
    /// [`Error::Parse`] when the file cannot be read (missing, not a regular file, over
    /// [`MAX_FILE_BYTES`]) or is malformed.
    pub fn read(path: &Path) -> Result<Self> {
        let text = read_text(path)?;
        // Comment lines (`#`, such as the axisymmetric note) before the header.
        let mut lines = text.lines().skip_while(|l| l.starts_with('#'));
        let header = lines
            .next()
            .ok_or_else(|| parse_error(path, "empty file: no header".into()))?;
        let columns: Vec<String> = header.split(',').map(str::to_string).collect();
        if columns.first().map(String::as_str) != Some("time") {
            return Err(parse_error(
                path,
                format!("the header does not start with `time`: {:.80}", header),
            ));
        }
        let lines: Vec<&str> = lines.filter(|l| !l.trim().is_empty()).collect();
        let mut rows = Vec::with_capacity(lines.len());
        for (k, line) in lines.iter().enumerate() {
            let values: std::result::Result<Vec<f64>, _> =
                line.split(',').map(|v| v.trim().parse::<f64>()).collect();
            match values {
                Ok(v) if v.len() == columns.len() => rows.push(v),
                _ if k + 1 == lines.len() && !text.ends_with('\n') => {}
                _ => {
                    return Err(parse_error(
                        path,
                        format!(
                            "line {}: expected {} numbers (one per column): {:.80}",
                            k + 2,
                            columns.len(),
                            line
                        ),
                    ))
                }
            }
        }
        Ok(Self { columns, rows })
    }

    /// Index of the column called `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// The values of column `k` (time is column 0).
    pub fn values(&self, k: usize) -> Vec<f64> {
        self.rows.iter().map(|r| r[k]).collect()
    }
}

/// One snapshot of `fields.pvd`: its time and one VTU file per body.
#[derive(Debug, Clone, PartialEq)]
pub struct SnapshotFiles {
    /// Simulated time (s).
    pub time: f64,
    /// (body name, VTU file) in the order listed.
    pub parts: Vec<(String, PathBuf)>,
}

fn attribute<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = tag.find(&key)? + key.len();
    let len = tag[start..].find('"')?;
    Some(&tag[start..start + len])
}

fn xml_unescape(s: &str) -> String {
    s.replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

/// Reads `fields.pvd` (in `dir`): its snapshots in time order, file paths resolved against `dir`.
///
/// # Errors
/// [`Error::Parse`] when the file cannot be read (missing, not a regular file, over
/// [`MAX_FILE_BYTES`]) or an entry lacks its time or file.
pub fn snapshots(dir: &Path) -> Result<Vec<SnapshotFiles>> {
    let path = dir.join("fields.pvd");
    let text = read_text(&path)?;
    let mut out: Vec<SnapshotFiles> = Vec::new();
    for (k, chunk) in text.split("<DataSet").skip(1).enumerate() {
        let tag = &chunk[..chunk.find("/>").unwrap_or(chunk.len())];
        let bad = |what: &str| parse_error(&path, format!("DataSet {k}: {what}"));
        let time: f64 = attribute(tag, "timestep")
            .ok_or_else(|| bad("no timestep"))?
            .parse()
            .map_err(|_| bad("timestep is not a number"))?;
        let file = attribute(tag, "file").ok_or_else(|| bad("no file"))?;
        let name = attribute(tag, "name").map(xml_unescape).unwrap_or_default();
        let part = (name, dir.join(xml_unescape(file)));
        match out.last_mut() {
            Some(s) if s.time.to_bits() == time.to_bits() => s.parts.push(part),
            _ => out.push(SnapshotFiles {
                time,
                parts: vec![part],
            }),
        }
    }
    out.sort_by(|a, b| a.time.total_cmp(&b.time));
    Ok(out)
}

/// One named data array of a VTU piece.
#[derive(Debug, Clone)]
pub struct DataArray {
    /// Name.
    pub name: String,
    /// Components per tuple.
    pub components: usize,
    /// Values, tuple after tuple.
    pub values: Vec<f64>,
}

/// One VTU piece: the deformed mesh of a body and its data.
#[derive(Debug, Clone, Default)]
pub struct Piece {
    /// Point coordinates (x, y).
    pub points: Vec<[f64; 2]>,
    /// Cell connectivity, all cells after each other.
    pub connectivity: Vec<u32>,
    /// End of each cell in `connectivity`.
    pub offsets: Vec<u32>,
    /// Point data arrays.
    pub point_data: Vec<DataArray>,
    /// Cell data arrays.
    pub cell_data: Vec<DataArray>,
}

impl Piece {
    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.offsets.len()
    }

    /// The point indices of cell `c`.
    pub fn cell(&self, c: usize) -> &[u32] {
        let start = if c == 0 {
            0
        } else {
            self.offsets[c - 1] as usize
        };
        &self.connectivity[start..self.offsets[c] as usize]
    }

    /// The point data array `name`.
    pub fn point_array(&self, name: &str) -> Option<&DataArray> {
        self.point_data.iter().find(|a| a.name == name)
    }

    /// The cell data array `name`.
    pub fn cell_array(&self, name: &str) -> Option<&DataArray> {
        self.cell_data.iter().find(|a| a.name == name)
    }
}

/// The raw appended block of a VTU file and how its arrays are framed.
struct Appended<'a> {
    data: &'a [u8],
    /// Header words are UInt64 (else UInt32).
    wide: bool,
    /// Arrays are zlib-compressed in blocks.
    zlib: bool,
}

impl Appended<'_> {
    fn word(&self, at: usize) -> Option<u64> {
        if self.wide {
            let b = self.data.get(at..at + 8)?;
            Some(u64::from_le_bytes(b.try_into().ok()?))
        } else {
            let b = self.data.get(at..at + 4)?;
            Some(u32::from_le_bytes(b.try_into().ok()?) as u64)
        }
    }

    /// The bytes of the array at `offset`, decompressed.
    fn array(&self, offset: usize) -> std::result::Result<Vec<u8>, String> {
        let w = if self.wide { 8 } else { 4 };
        let short = || "appended data cut short".to_string();
        if !self.zlib {
            let n = self.word(offset).ok_or_else(short)? as usize;
            let start = offset + w;
            return self
                .data
                .get(start..start.checked_add(n).ok_or_else(short)?)
                .map(<[u8]>::to_vec)
                .ok_or_else(short);
        }
        use std::io::Read as _;
        let blocks = self.word(offset).ok_or_else(short)? as usize;
        let block = self.word(offset + w).ok_or_else(short)? as usize;
        let last = self.word(offset + 2 * w).ok_or_else(short)? as usize;
        if blocks > self.data.len() / w {
            return Err(short());
        }
        let total = blocks.saturating_mul(block).saturating_sub(if last > 0 {
            block - last.min(block)
        } else {
            0
        });
        let mut out = Vec::with_capacity(total.min(self.data.len().saturating_mul(64)));
        let mut at = offset + (3 + blocks) * w;
        for k in 0..blocks {
            let n = self.word(offset + (3 + k) * w).ok_or_else(short)? as usize;
            let bytes = self
                .data
                .get(at..at.checked_add(n).ok_or_else(short)?)
                .ok_or_else(short)?;
            let want = if k + 1 == blocks && last > 0 {
                last
            } else {
                block
            };
            let before = out.len();
            flate2::read::ZlibDecoder::new(bytes)
                .take(want as u64)
                .read_to_end(&mut out)
                .map_err(|e| format!("zlib block {k}: {e}"))?;
            if out.len() - before != want {
                return Err(format!(
                    "zlib block {k}: {} bytes, expected {want}",
                    out.len() - before
                ));
            }
            at += n;
        }
        Ok(out)
    }
}

/// Decodes little-endian values of VTK type `ty` as f64.
fn decode(ty: &str, bytes: &[u8]) -> std::result::Result<Vec<f64>, String> {
    macro_rules! as_f64 {
        ($t:ty) => {{
            let n = std::mem::size_of::<$t>();
            if !bytes.len().is_multiple_of(n) {
                return Err(format!(
                    "{} bytes are not a whole number of {ty}",
                    bytes.len()
                ));
            }
            bytes
                .chunks_exact(n)
                .map(|c| <$t>::from_le_bytes(c.try_into().unwrap_or_default()) as f64)
                .collect()
        }};
    }
    Ok(match ty {
        "Float64" => as_f64!(f64),
        "Float32" => as_f64!(f32),
        "Int64" => as_f64!(i64),
        "UInt64" => as_f64!(u64),
        "Int32" => as_f64!(i32),
        "UInt32" => as_f64!(u32),
        "Int8" => as_f64!(i8),
        "UInt8" => as_f64!(u8),
        other => return Err(format!("type `{other}` is not read")),
    })
}

/// Reads a VTU file as `crate::output::fields` writes it: ASCII arrays, or raw appended data,
/// zlib-compressed or not, with UInt32 or UInt64 headers.
///
/// # Errors
/// [`Error::Parse`] when the file cannot be read (missing, not a regular file, over
/// [`MAX_FILE_BYTES`]) or is not such a file (another encoding, arrays of the wrong length, a cell that names a missing point).
pub fn vtu(path: &Path) -> Result<Piece> {
    let bytes = read_bytes(path)?;
    let bad = |m: String| parse_error(path, m);
    let xml_end = bytes
        .windows(13)
        .position(|w| w == b"<AppendedData")
        .unwrap_or(bytes.len());
    let text = std::str::from_utf8(&bytes[..xml_end])
        .map_err(|_| bad("the XML part is not UTF-8".into()))?;
    let appended = if xml_end < bytes.len() {
        let tag_end = xml_end
            + bytes[xml_end..]
                .iter()
                .position(|&b| b == b'>')
                .ok_or_else(|| bad("unterminated AppendedData tag".into()))?;
        let tag = std::str::from_utf8(&bytes[xml_end..tag_end]).unwrap_or("");
        if attribute(tag, "encoding") != Some("raw") {
            return Err(bad("AppendedData: only encoding=\"raw\" is read".into()));
        }
        let underscore = tag_end
            + bytes[tag_end..]
                .iter()
                .position(|&b| b == b'_')
                .ok_or_else(|| bad("AppendedData without its `_` mark".into()))?;
        let file_tag = text
            .find("<VTKFile")
            .and_then(|s| text[s..].find('>').map(|e| &text[s..s + e]))
            .unwrap_or("");
        let zlib = match attribute(file_tag, "compressor") {
            None => false,
            Some("vtkZLibDataCompressor") => true,
            Some(other) => return Err(bad(format!("compressor `{other}` is not read"))),
        };
        Some(Appended {
            data: &bytes[underscore + 1..],
            wide: attribute(file_tag, "header_type") == Some("UInt64"),
            zlib,
        })
    } else {
        None
    };
    let mut piece = Piece::default();
    let mut at = 0;
    while let Some(found) = text[at..].find("<DataArray") {
        let start = at + found;
        let head_end = start
            + text[start..]
                .find('>')
                .ok_or_else(|| bad("unterminated DataArray tag".into()))?;
        let tag = &text[start..head_end];
        let name = attribute(tag, "Name").unwrap_or("").to_string();
        let format = attribute(tag, "format").unwrap_or("ascii");
        let components: usize = attribute(tag, "NumberOfComponents")
            .map(|c| {
                c.parse()
                    .map_err(|_| bad(format!("`{name}`: bad NumberOfComponents")))
            })
            .transpose()?
            .unwrap_or(1)
            .max(1);
        let (values, next): (Vec<f64>, usize) = match format {
            "ascii" => {
                let body_end = head_end
                    + text[head_end..]
                        .find("</DataArray>")
                        .ok_or_else(|| bad("DataArray without its end tag".into()))?;
                let values = text[head_end + 1..body_end]
                    .split_ascii_whitespace()
                    .map(|v| v.parse::<f64>())
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| bad(format!("DataArray `{name}`: a value is not a number")))?;
                (values, body_end)
            }
            "appended" => {
                let data = appended.as_ref().ok_or_else(|| {
                    bad(format!("DataArray `{name}`: appended, but no AppendedData"))
                })?;
                let offset: usize = attribute(tag, "offset")
                    .and_then(|o| o.parse().ok())
                    .ok_or_else(|| bad(format!("DataArray `{name}`: no offset")))?;
                let ty = attribute(tag, "type").unwrap_or("");
                let values = data
                    .array(offset)
                    .and_then(|b| decode(ty, &b))
                    .map_err(|m| bad(format!("DataArray `{name}`: {m}")))?;
                (values, head_end)
            }
            other => {
                return Err(bad(format!(
                    "DataArray `{name}`: format `{other}` is not read (ascii or appended)"
                )))
            }
        };
        if !values.len().is_multiple_of(components) {
            return Err(bad(format!(
                "DataArray `{name}`: {} values for {components} components",
                values.len()
            )));
        }
        // Which section holds the array: the last section tag opened before it.
        let before = &text[..start];
        let section = ["<Points>", "<Cells>", "<PointData", "<CellData"]
            .iter()
            .filter_map(|s| before.rfind(s).map(|p| (p, *s)))
            .max()
            .map(|(_, s)| s);
        let ints = || values.iter().map(|&v| v as u32).collect::<Vec<u32>>();
        match (section, name.as_str()) {
            (Some("<Points>"), _) => {
                piece.points = values
                    .chunks_exact(components)
                    .map(|c| [c[0], if components > 1 { c[1] } else { 0.0 }])
                    .collect()
            }
            (Some("<Cells>"), "connectivity") => piece.connectivity = ints(),
            (Some("<Cells>"), "offsets") => piece.offsets = ints(),
            (Some("<Cells>"), _) => {}
            (Some("<PointData"), _) => piece.point_data.push(DataArray {
                name,
                components,
                values,
            }),
            (Some("<CellData"), _) => piece.cell_data.push(DataArray {
                name,
                components,
                values,
            }),
            _ => {}
        }
        at = next.max(head_end);
    }
    let np = piece.points.len();
    let mut prev = 0u32;
    for &o in &piece.offsets {
        if o < prev || o as usize > piece.connectivity.len() {
            return Err(bad(
                "cell offsets out of order or past the connectivity".into()
            ));
        }
        prev = o;
    }
    if let Some(&i) = piece.connectivity.iter().find(|&&i| i as usize >= np) {
        return Err(bad(format!("a cell names point {i} of {np}")));
    }
    for a in &piece.point_data {
        if a.values.len() != np * a.components {
            return Err(bad(format!("point data `{}` has the wrong length", a.name)));
        }
    }
    for a in &piece.cell_data {
        if a.values.len() != piece.cells() * a.components {
            return Err(bad(format!("cell data `{}` has the wrong length", a.name)));
        }
    }
    Ok(piece)
}
