//! VTK field output: one `.vtu` per body and snapshot under `fields/`, and `fields.pvd` listing
//! them with their times, for ParaView.
//!
//! Three encodings (`run.field_format`), all holding the same arrays (the deformed points,
//! connectivity, offsets and types, the nodal displacement and velocity, and the element stress
//! tensor, von Mises stress and equivalent strain):
//! - `binary` (the default): the VTK XML format with raw appended data compressed by zlib block by
//!   block (`compressor="vtkZLibDataCompressor"`, `header_type="UInt64"`), real numbers as
//!   Float32 (single precision, as explicit codes write their plot files), indices as Int32;
//! - `binary64`: the same with real numbers as Float64;
//! - `ascii`: text, real numbers in their shortest round-trip form (the Float64 values exactly),
//!   indices as Int64.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::element::plastic::{j2_elastic, PlasticState};
use crate::error::Result;
use crate::geometry::is_triangle;
use crate::model::Model;
use crate::scene::{FieldFormat, Formulation, MaterialModel};
use crate::step::Snapshot;

use super::{create_dir, write_file, write_pieces};

/// Stress and strain measures of one element, for output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementFields {
    /// Cauchy stress xx, yy, xy, zz.
    pub stress: [f64; 4],
    /// Von Mises stress.
    pub von_mises: f64,
    /// Equivalent (von Mises) strain of the small strain or of the Green-Lagrange strain.
    pub equivalent_strain: f64,
    /// Equivalent plastic strain (0 for the elastic models).
    pub plastic_strain: f64,
    /// Pressure -tr(sigma) / 3.
    pub pressure: f64,
}

/// Stress and strain of element `e` for displacements `u` (a J2 plastic element as if virgin:
/// see [`element_fields_state`]).
pub fn element_fields(model: &Model, u: &[[f64; 2]], e: usize) -> ElementFields {
    element_fields_state(model, u, e, &PlasticState::VIRGIN)
}

/// Stress and strain of element `e` for displacements `u` and its plastic state `plastic` (the
/// state the solver reached at u; elastic models ignore it).
pub fn element_fields_state(
    model: &Model,
    u: &[[f64; 2]],
    e: usize,
    plastic: &PlasticState,
) -> ElementFields {
    let p = model.params(e);
    let out = model.element_at(e, u, plastic);
    // A J2 element at the state the solver reached at u: its elastic response (evaluating it as
    // a step would return again, without the rate of the step that got there).
    let (stress, plastic_strain) = if p.model == MaterialModel::J2Plastic {
        let f = out.def_grad;
        let j2 = j2_elastic(p, &f, f[0] * f[3] - f[1] * f[2], out.hoop_stretch, plastic);
        (j2.cauchy, plastic.alpha)
    } else {
        (out.stress, 0.0)
    };
    let [sxx, syy, sxy, szz] = stress;
    let von_mises = (0.5
        * ((sxx - syy).powi(2) + (syy - szz).powi(2) + (szz - sxx).powi(2) + 6.0 * sxy * sxy))
        .sqrt();
    let f = out.def_grad;
    let (exx, eyy, exy) = match p.model {
        MaterialModel::LinearElastic => (f[0] - 1.0, f[3] - 1.0, 0.5 * (f[1] + f[2])),
        MaterialModel::NeoHookean | MaterialModel::J2Plastic => (
            0.5 * (f[0] * f[0] + f[2] * f[2] - 1.0),
            0.5 * (f[1] * f[1] + f[3] * f[3] - 1.0),
            0.5 * (f[0] * f[1] + f[2] * f[3]),
        ),
    };
    let h = out.hoop_stretch;
    let ezz = match p.formulation {
        Formulation::PlaneStrain => 0.0,
        Formulation::Axisymmetric => match p.model {
            MaterialModel::LinearElastic => h - 1.0,
            _ => 0.5 * (h * h - 1.0),
        },
        Formulation::PlaneStress => -p.lambda / (p.lambda + 2.0 * p.mu) * (exx + eyy),
    };
    let m = (exx + eyy + ezz) / 3.0;
    let (dx, dy, dz) = (exx - m, eyy - m, ezz - m);
    let equivalent_strain = (2.0 / 3.0 * (dx * dx + dy * dy + dz * dz + 2.0 * exy * exy)).sqrt();
    ElementFields {
        stress,
        von_mises,
        equivalent_strain,
        plastic_strain,
        pressure: -(sxx + syy + szz) / 3.0,
    }
}

/// Writes snapshots as VTU files and keeps the PVD collection up to date.
#[derive(Debug)]
pub struct FieldWriter {
    dir: PathBuf,
    format: FieldFormat,
    entries: Vec<(f64, String, String)>,
}

impl FieldWriter {
    /// Output under `out_dir` (`fields/` and `fields.pvd`) in `format`.
    ///
    /// # Errors
    /// [`crate::Error::Write`] when the folder cannot be created.
    pub fn new(out_dir: &Path, format: FieldFormat) -> Result<Self> {
        create_dir(&out_dir.join("fields"))?;
        Ok(Self {
            dir: out_dir.to_path_buf(),
            format,
            entries: Vec::new(),
        })
    }

    /// Continues the output of a checkpointed run under `out_dir`, whose snapshots so far were
    /// `entries` (see [`FieldWriter::entries`]).
    ///
    /// # Errors
    /// [`crate::Error::Write`] when the folder cannot be created.
    pub fn resume(
        out_dir: &Path,
        format: FieldFormat,
        model: &Model,
        entries: Vec<(f64, String, String)>,
    ) -> Result<Self> {
        let mut w = Self::new(out_dir, format)?;
        w.entries = entries;
        // `fields.pvd` lists no snapshot taken after the checkpoint.
        w.write_pvd(model)?;
        Ok(w)
    }

    /// The snapshots written: (time, body, file relative to the output folder).
    pub fn entries(&self) -> &[(f64, String, String)] {
        &self.entries
    }

    /// Number of snapshots written.
    pub fn count(&self) -> usize {
        let mut times: Vec<u64> = self.entries.iter().map(|e| e.0.to_bits()).collect();
        times.dedup();
        times.len()
    }

    /// Writes one snapshot: a `.vtu` per body, and rewrites `fields.pvd`.
    ///
    /// # Errors
    /// [`crate::Error::Write`] on I/O failure.
    pub fn write(&mut self, model: &Model, snap: &Snapshot) -> Result<()> {
        let k = self.count();
        for body in &model.bodies {
            let name = format!("{}_{:05}.vtu", body.name, k);
            let pieces = vtu(model, snap, body, self.format);
            write_pieces(&self.dir.join("fields").join(&name), &pieces)?;
            self.entries
                .push((snap.time, body.name.clone(), format!("fields/{name}")));
        }
        self.write_pvd(model)
    }

    fn write_pvd(&self, model: &Model) -> Result<()> {
        let mut pvd = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
        );
        for (t, part, file) in &self.entries {
            let _ = writeln!(
                pvd,
                "    <DataSet timestep=\"{t:e}\" group=\"\" part=\"{}\" name=\"{}\" file=\"{file}\"/>",
                model.bodies.iter().position(|b| &b.name == part).unwrap_or(0),
                xml_escape(part)
            );
        }
        pvd.push_str("  </Collection>\n</VTKFile>\n");
        write_file(&self.dir.join("fields.pvd"), pvd.as_bytes())
    }
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// One array of a VTU piece, before encoding.
enum Values {
    F64(Vec<f64>),
    F32(Vec<f32>),
    I32(Vec<i32>),
    U8(Vec<u8>),
}

impl Values {
    fn type_name(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::F32(_) => "Float32",
            Values::I32(_) => "Int32",
            Values::U8(_) => "UInt8",
        }
    }

    /// The values as little-endian bytes (a view on little-endian machines).
    fn bytes(&self) -> std::borrow::Cow<'_, [u8]> {
        #[cfg(target_endian = "little")]
        {
            std::borrow::Cow::Borrowed(match self {
                Values::F64(v) => bytemuck::cast_slice(v),
                Values::F32(v) => bytemuck::cast_slice(v),
                Values::I32(v) => bytemuck::cast_slice(v),
                Values::U8(v) => v,
            })
        }
        #[cfg(not(target_endian = "little"))]
        {
            std::borrow::Cow::Owned(match self {
                Values::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
                Values::F32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
                Values::I32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
                Values::U8(v) => v.clone(),
            })
        }
    }

    fn ascii(&self, components: usize, out: &mut String) {
        let per = components.max(1);
        let mut line = |k: usize, item: &dyn Fn(&mut String)| {
            if k.is_multiple_of(per) {
                out.push_str("          ");
            }
            item(out);
            out.push(if k % per == per - 1 { '\n' } else { ' ' });
        };
        match self {
            Values::F64(v) => {
                for (k, x) in v.iter().enumerate() {
                    line(k, &|o: &mut String| {
                        let _ = if *x == 0.0 {
                            write!(o, "0")
                        } else {
                            write!(o, "{x:e}")
                        };
                    });
                }
            }
            Values::F32(v) => {
                for (k, x) in v.iter().enumerate() {
                    line(k, &|o: &mut String| {
                        let _ = write!(o, "{x:e}");
                    });
                }
            }
            Values::I32(v) => {
                for (k, x) in v.iter().enumerate() {
                    line(k, &|o: &mut String| {
                        let _ = write!(o, "{x}");
                    });
                }
            }
            Values::U8(v) => {
                for (k, x) in v.iter().enumerate() {
                    line(k, &|o: &mut String| {
                        let _ = write!(o, "{x}");
                    });
                }
            }
        }
    }
}

/// A named array with its section and component names.
struct Array {
    name: &'static str,
    components: usize,
    extra: &'static str,
    values: Values,
}

/// Uncompressed bytes per zlib block (VTK reads any block size from the header).
const BLOCK: usize = 1 << 16;

/// zlib-compresses `data` in blocks of [`BLOCK`] bytes behind the UInt64 header VTK expects:
/// block count, block size, size of the last partial block (0 when the last block is full),
/// then each block's compressed size. Compression is used where it pays: when the first block
/// does not shrink below 90 % (noisy floating-point data), the blocks are stored (zlib level 0,
/// a plain copy). Blocks are compressed on up to as many threads as the machine has cores; the
/// output does not depend on how many.
fn compress(data: &[u8]) -> Vec<Vec<u8>> {
    use std::io::Write as _;
    let deflate = |b: &[u8], level: flate2::Compression| {
        let mut z = flate2::write::ZlibEncoder::new(Vec::with_capacity(b.len() / 2 + 64), level);
        // Writing into a Vec cannot fail.
        let _ = z.write_all(b);
        z.finish().unwrap_or_default()
    };
    let blocks: Vec<&[u8]> = data.chunks(BLOCK).collect();
    let level = match blocks.first() {
        Some(b) if deflate(b, flate2::Compression::fast()).len() * 10 >= b.len() * 9 => {
            flate2::Compression::none()
        }
        _ => flate2::Compression::fast(),
    };
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .clamp(1, 8)
        .min(blocks.len().max(1));
    let per = blocks.len().div_ceil(threads).max(1);
    let packed: Vec<Vec<u8>> = std::thread::scope(|s| {
        let handles: Vec<_> = blocks
            .chunks(per)
            .map(|group| {
                s.spawn(move || group.iter().map(|b| deflate(b, level)).collect::<Vec<_>>())
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_default())
            .collect()
    });
    let mut header = Vec::with_capacity(24 + 8 * packed.len());
    header.extend((packed.len() as u64).to_le_bytes());
    header.extend((BLOCK as u64).to_le_bytes());
    header.extend(((data.len() % BLOCK) as u64).to_le_bytes());
    for p in &packed {
        header.extend((p.len() as u64).to_le_bytes());
    }
    let mut out = Vec::with_capacity(1 + packed.len());
    out.push(header);
    out.extend(packed);
    out
}

/// [`element_fields`] of `elems`, on up to as many threads as the machine has cores (each
/// element is computed alone, so the result does not depend on how many).
fn all_element_fields(
    model: &Model,
    u: &[[f64; 2]],
    plastic: &[PlasticState],
    elems: std::ops::Range<usize>,
) -> Vec<ElementFields> {
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .clamp(1, 8);
    let ids: Vec<usize> = elems.collect();
    let per = ids.len().div_ceil(threads).max(4096);
    std::thread::scope(|s| {
        let handles: Vec<_> = ids
            .chunks(per)
            .map(|chunk| {
                s.spawn(move || {
                    chunk
                        .iter()
                        .map(|&e| match plastic.get(e) {
                            Some(st) => element_fields_state(model, u, e, st),
                            None => element_fields(model, u, e),
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_default())
            .collect()
    })
}

/// The arrays of one body's snapshot, by section.
fn arrays(model: &Model, snap: &Snapshot, body: &crate::model::BodyModel) -> [Vec<Array>; 4] {
    let nodes = body.nodes.clone();
    let elems = body.elements.clone();
    let vec3 = |f: &dyn Fn(usize) -> [f64; 2]| {
        Values::F64(
            nodes
                .clone()
                .flat_map(|i| {
                    let v = f(i);
                    [v[0], v[1], 0.0]
                })
                .collect(),
        )
    };
    let points = vec![Array {
        name: "",
        components: 3,
        extra: "",
        values: vec3(&|i| {
            let (p, u) = (model.position[i], snap.displacement[i]);
            [p[0] + u[0], p[1] + u[1]]
        }),
    }];
    // Quads as VTK_QUAD (9); triangles, the collapsed quads [a, b, c, c], as VTK_TRIANGLE (5)
    // with their three nodes.
    let tri = |e: usize| is_triangle(&model.quads[e]);
    let mut offsets = Vec::with_capacity(elems.len());
    let mut end = 0i32;
    for e in elems.clone() {
        end += if tri(e) { 3 } else { 4 };
        offsets.push(end);
    }
    let cells = vec![
        Array {
            name: "connectivity",
            components: 1,
            extra: "",
            values: Values::I32(
                elems
                    .clone()
                    .flat_map(|e| {
                        let q = model.quads[e];
                        q[..if tri(e) { 3 } else { 4 }]
                            .iter()
                            .map(|&i| (i as usize - nodes.start) as i32)
                            .collect::<Vec<_>>()
                    })
                    .collect(),
            ),
        },
        Array {
            name: "offsets",
            components: 1,
            extra: "",
            values: Values::I32(offsets),
        },
        Array {
            name: "types",
            components: 1,
            extra: "",
            values: Values::U8(elems.clone().map(|e| if tri(e) { 5 } else { 9 }).collect()),
        },
    ];
    let point_data = vec![
        Array {
            name: "displacement",
            components: 3,
            extra: "",
            values: vec3(&|i| snap.displacement[i]),
        },
        Array {
            name: "velocity",
            components: 3,
            extra: "",
            values: vec3(&|i| snap.velocity[i]),
        },
    ];
    let mut fields = all_element_fields(model, &snap.displacement, &snap.plastic, elems.clone());
    // An eroded element carries no stress: its stress fields are 0 (its plastic strain is the
    // one it failed at).
    let eroded = |e: usize| snap.eroded.get(e) == Some(&true);
    for (f, e) in fields.iter_mut().zip(elems.clone()) {
        if eroded(e) {
            *f = ElementFields {
                stress: [0.0; 4],
                von_mises: 0.0,
                pressure: 0.0,
                ..*f
            };
        }
    }
    let mut cell_data = vec![
        Array {
            name: "stress",
            components: 4,
            extra: " ComponentName0=\"xx\" ComponentName1=\"yy\" ComponentName2=\"xy\" ComponentName3=\"zz\"",
            values: Values::F64(fields.iter().flat_map(|f| f.stress).collect()),
        },
        Array {
            name: "von_mises",
            components: 1,
            extra: "",
            values: Values::F64(fields.iter().map(|f| f.von_mises).collect()),
        },
        Array {
            name: "equivalent_strain",
            components: 1,
            extra: "",
            values: Values::F64(fields.iter().map(|f| f.equivalent_strain).collect()),
        },
    ];
    if body.params.model == MaterialModel::J2Plastic {
        cell_data.push(Array {
            name: "plastic_strain",
            components: 1,
            extra: "",
            values: Values::F64(fields.iter().map(|f| f.plastic_strain).collect()),
        });
        cell_data.push(Array {
            name: "pressure",
            components: 1,
            extra: "",
            values: Values::F64(fields.iter().map(|f| f.pressure).collect()),
        });
    }
    if body.params.has_thermal() && !snap.plastic.is_empty() {
        // Johnson-Cook thermal softening: T = T_r + the element's temperature rise (K).
        let room = body.params.room_temperature;
        cell_data.push(Array {
            name: "temperature",
            components: 1,
            extra: "",
            values: Values::F64(elems.clone().map(|e| room + snap.plastic[e].heat).collect()),
        });
    }
    if body.params.failure.is_some() && !snap.eroded.is_empty() {
        cell_data.push(Array {
            name: "eroded",
            components: 1,
            extra: "",
            values: Values::U8(elems.clone().map(|e| u8::from(eroded(e))).collect()),
        });
    }
    if body
        .params
        .failure
        .is_some_and(|f| f.johnson_cook.is_some())
        && !snap.damage.is_empty()
    {
        cell_data.push(Array {
            name: "damage",
            components: 1,
            extra: "",
            values: Values::F64(elems.clone().map(|e| snap.damage[e]).collect()),
        });
    }
    [points, cells, point_data, cell_data]
}

/// The VTU file of one body's snapshot in `format`.
fn vtu(
    model: &Model,
    snap: &Snapshot,
    body: &crate::model::BodyModel,
    format: FieldFormat,
) -> Vec<Vec<u8>> {
    let [points, cells, point_data, cell_data] = arrays(model, snap, body);
    let binary = format != FieldFormat::Ascii;
    let mut s = String::new();
    let _ = write!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"{}\" byte_order=\"LittleEndian\"{}>\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
        if binary { "1.0" } else { "0.1" },
        if binary {
            " header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\""
        } else {
            ""
        },
        body.nodes.len(),
        body.elements.len()
    );
    let mut appended: Vec<Vec<u8>> = Vec::new();
    let mut offset = 0usize;
    let mut section = |s: &mut String, open: &str, close: &str, list: &[Array]| {
        s.push_str(open);
        for a in list {
            let name = if a.name.is_empty() {
                String::new()
            } else {
                format!(" Name=\"{}\"", a.name)
            };
            let comps = if a.components > 1 {
                format!(" NumberOfComponents=\"{}\"", a.components)
            } else {
                String::new()
            };
            let ty = match (a.values.type_name(), format) {
                // ASCII keeps the historical Int64 index type.
                ("Int32", FieldFormat::Ascii) => "Int64",
                ("Float64", FieldFormat::Binary) => "Float32",
                (ty, _) => ty,
            };
            if binary {
                let _ = writeln!(
                    s,
                    "        <DataArray type=\"{ty}\"{name}{comps}{} format=\"appended\" offset=\"{}\"/>",
                    a.extra,
                    offset
                );
                let pieces = match (&a.values, format) {
                    (Values::F64(v), FieldFormat::Binary) => {
                        compress(&Values::F32(v.iter().map(|&x| x as f32).collect()).bytes())
                    }
                    _ => compress(&a.values.bytes()),
                };
                offset += pieces.iter().map(Vec::len).sum::<usize>();
                appended.extend(pieces);
            } else {
                let _ = writeln!(
                    s,
                    "        <DataArray type=\"{ty}\"{name}{comps}{} format=\"ascii\">",
                    a.extra
                );
                a.values.ascii(a.components, s);
                s.push_str("        </DataArray>\n");
            }
        }
        s.push_str(close);
    };
    section(&mut s, "      <Points>\n", "      </Points>\n", &points);
    section(&mut s, "      <Cells>\n", "      </Cells>\n", &cells);
    section(
        &mut s,
        "      <PointData Vectors=\"displacement\">\n",
        "      </PointData>\n",
        &point_data,
    );
    section(
        &mut s,
        "      <CellData>\n",
        "      </CellData>\n",
        &cell_data,
    );
    s.push_str("    </Piece>\n  </UnstructuredGrid>\n");
    let mut out = vec![s.into_bytes()];
    if binary {
        out.push(b"  <AppendedData encoding=\"raw\">\n   _".to_vec());
        out.extend(appended);
        out.push(b"\n  </AppendedData>\n".to_vec());
    }
    out.push(b"</VTKFile>\n".to_vec());
    out
}
