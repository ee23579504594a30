//! VTK field output: one ASCII `.vtu` per body and snapshot under `fields/`, and `fields.pvd`
//! listing them with their times, for ParaView.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::Result;
use crate::model::Model;
use crate::scene::{Formulation, MaterialModel};
use crate::step::element::{evaluate, Dissipation};
use crate::step::Snapshot;

use super::{create_dir, write_file};

/// Stress and strain measures of one element, for output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementFields {
    /// Cauchy stress xx, yy, xy, zz.
    pub stress: [f64; 4],
    /// Von Mises stress.
    pub von_mises: f64,
    /// Equivalent (von Mises) strain of the small strain or of the Green-Lagrange strain.
    pub equivalent_strain: f64,
}

/// Stress and strain of element `e` for displacements `u`.
pub fn element_fields(model: &Model, u: &[[f64; 2]], e: usize) -> ElementFields {
    let p = model.params(e);
    let q = model.quads[e];
    let ue = q.map(|i| u[i as usize]);
    let out = evaluate(
        p,
        &model.corners[e],
        &ue,
        &[[0.0; 2]; 4],
        &Dissipation::default(),
        0.0,
    );
    let [sxx, syy, sxy, szz] = out.stress;
    let von_mises = (0.5
        * ((sxx - syy).powi(2) + (syy - szz).powi(2) + (szz - sxx).powi(2) + 6.0 * sxy * sxy))
        .sqrt();
    let f = out.def_grad;
    let (exx, eyy, exy) = match p.model {
        MaterialModel::LinearElastic => (f[0] - 1.0, f[3] - 1.0, 0.5 * (f[1] + f[2])),
        MaterialModel::NeoHookean => (
            0.5 * (f[0] * f[0] + f[2] * f[2] - 1.0),
            0.5 * (f[1] * f[1] + f[3] * f[3] - 1.0),
            0.5 * (f[0] * f[1] + f[2] * f[3]),
        ),
    };
    let ezz = match p.formulation {
        Formulation::PlaneStrain => 0.0,
        Formulation::PlaneStress => -p.lambda / (p.lambda + 2.0 * p.mu) * (exx + eyy),
    };
    let m = (exx + eyy + ezz) / 3.0;
    let (dx, dy, dz) = (exx - m, eyy - m, ezz - m);
    let equivalent_strain = (2.0 / 3.0 * (dx * dx + dy * dy + dz * dz + 2.0 * exy * exy)).sqrt();
    ElementFields {
        stress: out.stress,
        von_mises,
        equivalent_strain,
    }
}

/// Writes snapshots as VTU files and keeps the PVD collection up to date.
#[derive(Debug)]
pub struct FieldWriter {
    dir: PathBuf,
    entries: Vec<(f64, String, String)>,
}

impl FieldWriter {
    /// Output under `out_dir` (`fields/` and `fields.pvd`).
    ///
    /// # Errors
    /// [`crate::Error::Write`] when the folder cannot be created.
    pub fn new(out_dir: &Path) -> Result<Self> {
        create_dir(&out_dir.join("fields"))?;
        Ok(Self {
            dir: out_dir.to_path_buf(),
            entries: Vec::new(),
        })
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
            let text = vtu(model, snap, body);
            write_file(&self.dir.join("fields").join(&name), &text)?;
            self.entries
                .push((snap.time, body.name.clone(), format!("fields/{name}")));
        }
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
        write_file(&self.dir.join("fields.pvd"), &pvd)
    }
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn vtu(model: &Model, snap: &Snapshot, body: &crate::model::BodyModel) -> String {
    let nodes = body.nodes.clone();
    let elems = body.elements.clone();
    let mut s = String::new();
    let _ = write!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
        nodes.len(),
        elems.len()
    );
    // Deformed geometry.
    s.push_str("      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for i in nodes.clone() {
        let p = model.position[i];
        let u = snap.displacement[i];
        let _ = writeln!(s, "          {:e} {:e} 0", p[0] + u[0], p[1] + u[1]);
    }
    s.push_str("        </DataArray>\n      </Points>\n      <Cells>\n");
    s.push_str("        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for e in elems.clone() {
        let q = model.quads[e].map(|i| i as usize - nodes.start);
        let _ = writeln!(s, "          {} {} {} {}", q[0], q[1], q[2], q[3]);
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for (k, _) in elems.clone().enumerate() {
        let _ = writeln!(s, "          {}", 4 * (k + 1));
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in elems.clone() {
        s.push_str("          9\n");
    }
    s.push_str(
        "        </DataArray>\n      </Cells>\n      <PointData Vectors=\"displacement\">\n",
    );
    for (name, data) in [
        ("displacement", &snap.displacement),
        ("velocity", &snap.velocity),
    ] {
        let _ = writeln!(
            s,
            "        <DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"3\" format=\"ascii\">"
        );
        for i in nodes.clone() {
            let _ = writeln!(s, "          {:e} {:e} 0", data[i][0], data[i][1]);
        }
        s.push_str("        </DataArray>\n");
    }
    s.push_str("      </PointData>\n      <CellData>\n");
    let fields: Vec<ElementFields> = elems
        .clone()
        .map(|e| element_fields(model, &snap.displacement, e))
        .collect();
    s.push_str("        <DataArray type=\"Float64\" Name=\"stress\" NumberOfComponents=\"4\" ComponentName0=\"xx\" ComponentName1=\"yy\" ComponentName2=\"xy\" ComponentName3=\"zz\" format=\"ascii\">\n");
    for f in &fields {
        let _ = writeln!(
            s,
            "          {:e} {:e} {:e} {:e}",
            f.stress[0], f.stress[1], f.stress[2], f.stress[3]
        );
    }
    s.push_str("        </DataArray>\n");
    for (name, get) in [
        (
            "von_mises",
            (|f: &ElementFields| f.von_mises) as fn(&ElementFields) -> f64,
        ),
        ("equivalent_strain", |f: &ElementFields| f.equivalent_strain),
    ] {
        let _ = writeln!(
            s,
            "        <DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        );
        for f in &fields {
            let _ = writeln!(s, "          {:e}", get(f));
        }
        s.push_str("        </DataArray>\n");
    }
    s.push_str("      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    s
}
