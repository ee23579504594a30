//! Reading a run's output folder back: `history.csv`, `fields.pvd` and the VTU files it lists
//! (the formats `crate::output` writes).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|source| Error::Read {
        file: path.to_path_buf(),
        source,
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
    /// [`Error::Read`] when the file cannot be read, [`Error::Parse`] when it is malformed.
    pub fn read(path: &Path) -> Result<Self> {
        let text = read_text(path)?;
        let mut lines = text.lines();
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
/// [`Error::Read`] when the file cannot be read, [`Error::Parse`] when an entry lacks its time or
/// file.
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

/// Reads an ASCII VTU file as `crate::output::fields` writes it.
///
/// # Errors
/// [`Error::Read`] when the file cannot be read, [`Error::Parse`] when it is not such a file
/// (another encoding, arrays of the wrong length, a cell that names a missing point).
pub fn vtu(path: &Path) -> Result<Piece> {
    let text = read_text(path)?;
    let bad = |m: String| parse_error(path, m);
    let mut piece = Piece::default();
    let mut at = 0;
    while let Some(found) = text[at..].find("<DataArray") {
        let start = at + found;
        let head_end = start
            + text[start..]
                .find('>')
                .ok_or_else(|| bad("unterminated DataArray tag".into()))?;
        let tag = &text[start..head_end];
        let body_end = head_end
            + text[head_end..]
                .find("</DataArray>")
                .ok_or_else(|| bad("DataArray without its end tag".into()))?;
        let name = attribute(tag, "Name").unwrap_or("").to_string();
        let format = attribute(tag, "format").unwrap_or("ascii");
        if format != "ascii" {
            return Err(bad(format!(
                "DataArray `{name}`: format `{format}` is not read (ascii only)"
            )));
        }
        let components: usize = attribute(tag, "NumberOfComponents")
            .map(|c| {
                c.parse()
                    .map_err(|_| bad(format!("`{name}`: bad NumberOfComponents")))
            })
            .transpose()?
            .unwrap_or(1)
            .max(1);
        let values: Vec<f64> = text[head_end + 1..body_end]
            .split_ascii_whitespace()
            .map(|v| v.parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| bad(format!("DataArray `{name}`: a value is not a number")))?;
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
        at = body_end;
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
