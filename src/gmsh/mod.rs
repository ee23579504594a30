//! Gmsh meshes: the elements of one physical surface of an MSH 4.1 file (ASCII or binary) as a
//! body's nodes and counter-clockwise quads and triangles (a triangle as the collapsed quad
//! `[a, b, c, c]`, see [`crate::element`]), and the file's physical curves and points on that
//! body. The file is read whole within [`MAX_FILE_BYTES`] ([`read_bytes`]) and its sections by
//! `msh.rs`, which checks every count and tag it gives (nodes are found by their tags, which
//! must be unique and within the `$Nodes` header's range). A physical group is found by its
//! name in `$PhysicalNames` or by its number (`5` or `"5"`: Gmsh's tutorials number groups
//! without naming them). Every problem is reported as a sentence naming the group and, for an
//! element, its Gmsh tag and nodes; the scene parser puts it in an [`crate::Error::Invalid`]
//! with the scene file, the key and the mesh file. Host-side only, no GPU twin.

mod msh;

use std::collections::{BTreeSet, HashMap, HashSet};
use std::path::Path;

pub use msh::type_name;

/// Mesh files larger than this are refused before they are read (no unbounded allocation).
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// Gmsh element types read as elements: 3-node triangles and 4-node quads.
const TRI3: i32 = 2;
const QUA4: i32 = 3;
/// Gmsh element types read as boundaries: 2-node lines and points.
const LIN2: i32 = 1;
const PNT: i32 = 15;

/// The elements of one physical surface, ready to be a body.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceMesh {
    /// Node coordinates (x, y), in the order of their Gmsh tags.
    pub nodes: Vec<[f64; 2]>,
    /// Gmsh tag of each node.
    pub node_tags: Vec<u64>,
    /// Quads and triangles (`[a, b, c, c]`) as indices into `nodes`, counter-clockwise.
    pub quads: Vec<[u32; 4]>,
    /// Gmsh tag of each element.
    pub element_tags: Vec<u64>,
    /// Quads that were clockwise in the file and were turned counter-clockwise.
    pub reoriented: usize,
    /// The physical curves and points of the file that touch this surface, as node sets and
    /// edges of this surface's nodes (for `region = { group = "..." }`).
    pub groups: Vec<NodeGroup>,
    /// The digest ([`digest`]) of the whole file the surface was read from: a checkpoint keeps
    /// it, and a restart refuses a mesh file that changed since.
    pub digest: u64,
}

/// A physical curve or point of a mesh file, restricted to one surface's nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeGroup {
    /// Its name in `$PhysicalNames` (empty for a group that has only a number).
    pub name: String,
    /// Its physical tag (number).
    pub tag: i32,
    /// 1 for a curve, 0 for a point.
    pub dim: i32,
    /// Indices into [`SurfaceMesh::nodes`], ascending.
    pub nodes: Vec<u32>,
    /// The curve's 2-node line elements whose two nodes are in the surface, as indices into
    /// [`SurfaceMesh::nodes`] (none for a point).
    pub edges: Vec<[u32; 2]>,
}

impl NodeGroup {
    /// Whether `group` (a name, or a number as text) names this group: by its name, else by its
    /// number ([`group_number`]).
    pub fn is(&self, group: &str) -> bool {
        (!self.name.is_empty() && self.name == group) || group_number(group) == Some(self.tag)
    }

    /// The group as a message lists it: `"clamp" (5)`, or `5` without a name.
    pub fn label(&self) -> String {
        label(&self.name, self.tag)
    }
}

fn label(name: &str, tag: i32) -> String {
    if name.is_empty() {
        tag.to_string()
    } else {
        format!("{name:?} ({tag})")
    }
}

/// The physical tag that `group` gives as a number (`"5"`): a positive integer, else `None`.
pub fn group_number(group: &str) -> Option<i32> {
    group.parse::<i32>().ok().filter(|&n| n > 0)
}

/// A physical group named in `$PhysicalNames`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PhysicalName {
    /// Dimension: 0 point, 1 curve, 2 surface, 3 volume.
    pub dim: i32,
    /// Physical tag.
    pub tag: i32,
    /// Name.
    pub name: String,
}

impl SurfaceMesh {
    /// The number of triangles among the elements (collapsed quads `[a, b, c, c]`).
    pub fn triangles(&self) -> usize {
        self.quads.iter().filter(|q| q[2] == q[3]).count()
    }

    /// The element of smallest area: its index, area and shortest edge.
    pub fn smallest(&self) -> Option<(usize, f64, f64)> {
        let mut best: Option<(usize, f64, f64)> = None;
        for (i, q) in self.quads.iter().enumerate() {
            let c = q.map(|n| self.nodes[n as usize]);
            let area = 0.5
                * ((c[2][0] - c[0][0]) * (c[3][1] - c[1][1])
                    - (c[3][0] - c[1][0]) * (c[2][1] - c[0][1]));
            let edge = (0..4)
                .filter(|&k| q[k] != q[(k + 1) % 4])
                .map(|k| {
                    let (a, b) = (c[k], c[(k + 1) % 4]);
                    (b[0] - a[0]).hypot(b[1] - a[1])
                })
                .fold(f64::INFINITY, f64::min);
            if best.is_none_or(|b| area < b.1) {
                best = Some((i, area, edge));
            }
        }
        best
    }
}

/// The digest of a file's bytes (64-bit XXH3): what a checkpoint keeps of a mesh file, to find
/// it changed at a restart.
pub fn digest(bytes: &[u8]) -> u64 {
    xxhash_rust::xxh3::xxh3_64(bytes)
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

/// The text of the section `$name` ... `$Endname` (sections that are ASCII in both encodings:
/// `$MeshFormat`'s first line, `$PhysicalNames`).
fn section<'a>(bytes: &'a [u8], name: &str) -> Option<&'a [u8]> {
    let start = find(bytes, format!("${name}").as_bytes())? + name.len() + 1;
    let end = start + find(&bytes[start..], format!("$End{name}").as_bytes())?;
    Some(&bytes[start..end])
}

/// The MSH version written in `$MeshFormat` (as text, e.g. `4.1` or `2.2`).
///
/// # Errors
/// A sentence when the file has no `$MeshFormat` section.
pub fn version(bytes: &[u8]) -> Result<String, String> {
    let s = section(bytes, "MeshFormat")
        .ok_or("not a Gmsh mesh file: it has no $MeshFormat section")?;
    let line = s
        .split(|&b| b == b'\n')
        .find(|l| !l.trim_ascii().is_empty());
    let v = line
        .and_then(|l| std::str::from_utf8(l).ok())
        .and_then(|l| l.split_whitespace().next())
        .ok_or("its $MeshFormat section has no version")?;
    Ok(v.chars().take(40).collect())
}

/// The physical groups named in `$PhysicalNames` (none when the section is absent).
///
/// # Errors
/// A sentence naming the malformed line.
pub fn physical_names(bytes: &[u8]) -> Result<Vec<PhysicalName>, String> {
    let Some(s) = section(bytes, "PhysicalNames") else {
        return Ok(Vec::new());
    };
    Ok(msh::physical_names(s)?
        .into_iter()
        .map(|(dim, tag, name)| PhysicalName { dim, tag, name })
        .collect())
}

fn dim_word(dim: i32) -> &'static str {
    match dim {
        0 => "point",
        1 => "curve",
        2 => "surface",
        _ => "volume",
    }
}

/// The file's bytes, refusing what cannot be a mesh file this program should read whole:
/// anything but a regular file (a FIFO, `/dev/zero`, a folder) before it is opened, a file over
/// [`MAX_FILE_BYTES`] (checked on its size, and again on what is read, through
/// [`std::io::Read::take`]).
///
/// # Errors
/// A sentence when the file cannot be read, is not a regular file or is larger than
/// [`MAX_FILE_BYTES`].
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, String> {
    crate::input::read_capped(path, MAX_FILE_BYTES)
        .map_err(|e| format!("cannot read the mesh file: {e}"))
}

/// The physical groups of dimension `dim` of `file`: (tag, name), the named ones first in the
/// order of `$PhysicalNames`, then those that only entities number, ascending (empty names).
fn groups_of(file: &msh::MshFile, dim: i32) -> Vec<(i32, String)> {
    let mut out: Vec<(i32, String)> = file
        .names
        .iter()
        .filter(|n| n.0 == dim)
        .map(|n| (n.1, n.2.clone()))
        .collect();
    let mut numbered: BTreeSet<i32> = BTreeSet::new();
    if let Some(list) = file.entities.get(dim as usize) {
        for e in list {
            numbered.extend(e.physical.iter().map(|p| p.abs()));
        }
    }
    for t in numbered {
        if !out.iter().any(|o| o.0 == t) {
            out.push((t, String::new()));
        }
    }
    out
}

/// The quads and triangles of physical surface `group` (its name, or its number as text) of the
/// MSH 4.1 file `bytes`.
///
/// # Errors
/// A sentence naming the group and the problem: another MSH version, a file `msh.rs` refuses
/// (a bad header, a count larger than the file, a node tag that is 0, out of range or given
/// twice), a group that does not exist (the message lists the file's surfaces by name and
/// number) or is not a surface, elements other than 4-node quads and 3-node triangles in it
/// (type and count), a node off the xy-plane, an element whose corners do not make a convex
/// element of positive area (its Gmsh tag and nodes).
pub fn read_surface(bytes: &[u8], group: &str) -> Result<SurfaceMesh, String> {
    let v = version(bytes)?;
    if v != "4.1" {
        return Err(format!(
            "MSH format version {v}: ricochet reads version 4.1 (in Gmsh: \
             Mesh.MshFileVersion = 4.1, or `gmsh -format msh41`)"
        ));
    }
    let file = msh::parse(bytes)?;
    let surfaces = groups_of(&file, 2);
    let by_name = |list: &[(i32, String)]| {
        list.iter()
            .find(|g| !g.1.is_empty() && g.1 == group)
            .or_else(|| list.iter().find(|g| Some(g.0) == group_number(group)))
            .map(|g| g.0)
    };
    let tag = match by_name(&surfaces) {
        Some(t) => t,
        None => {
            for dim in [1, 0, 3] {
                if by_name(&groups_of(&file, dim)).is_some() {
                    return Err(format!(
                        "group `{group}` is a physical {}, not a surface: a body is the \
                         elements of a physical surface",
                        dim_word(dim)
                    ));
                }
            }
            let listed: Vec<String> = surfaces.iter().map(|g| label(&g.1, g.0)).collect();
            let how = if group_number(group).is_some() {
                "named or numbered"
            } else {
                "named"
            };
            return Err(format!(
                "no physical surface {how} `{group}` (the file's surfaces by name and number: {})",
                if listed.is_empty() {
                    "none".to_string()
                } else {
                    listed.join(", ")
                }
            ));
        }
    };
    let entities: HashSet<i32> = file.entities[2]
        .iter()
        .filter(|s| s.physical.iter().any(|&p| p.abs() == tag))
        .map(|s| s.tag)
        .collect();
    if entities.is_empty() {
        return Err(format!(
            "group `{group}` (physical tag {tag}) holds no surface of the file's $Entities"
        ));
    }
    let mut raw: Vec<(u64, [u64; 4])> = Vec::new();
    let mut other: Vec<(i32, usize)> = Vec::new();
    for b in &file.elements {
        if b.dim != 2 || !entities.contains(&b.entity) {
            continue;
        }
        if b.kind == QUA4 || b.kind == TRI3 {
            for (k, &etag) in b.tags.iter().enumerate() {
                let n = &b.nodes[k * b.per..(k + 1) * b.per];
                // A triangle is a collapsed quad [a, b, c, c] (see ricochet::element).
                raw.push((etag, [n[0], n[1], n[2], n[b.per - 1]]));
            }
        } else {
            match other.iter_mut().find(|o| o.0 == b.kind) {
                Some(o) => o.1 += b.tags.len(),
                None => other.push((b.kind, b.tags.len())),
            }
        }
    }
    if !other.is_empty() {
        let list: Vec<String> = other
            .iter()
            .map(|(t, n)| format!("{n} x {} (Gmsh type {t})", type_name(*t)))
            .collect();
        let hint = "ricochet reads first-order elements, 4-node quads and 3-node triangles \
                    (Mesh.ElementOrder = 1)";
        return Err(format!(
            "group `{group}` has elements ricochet cannot use: {}; {hint}",
            list.join(", ")
        ));
    }
    if raw.is_empty() {
        return Err(format!(
            "group `{group}` has no elements (was the mesh generated?)"
        ));
    }
    // Node coordinates by tag (each tag once: `msh.rs` refuses a tag given twice).
    let mut coords: HashMap<u64, [f64; 3]> = HashMap::new();
    for b in &file.nodes {
        coords.extend(b.tags.iter().copied().zip(b.coords.iter().copied()));
    }
    let used: BTreeSet<u64> = raw.iter().flat_map(|(_, q)| q.iter().copied()).collect();
    let mut index = HashMap::with_capacity(used.len());
    let mut nodes = Vec::with_capacity(used.len());
    let mut node_tags = Vec::with_capacity(used.len());
    let mut extent: f64 = 0.0;
    for &t in &used {
        let p = coords.get(&t).ok_or_else(|| {
            format!("group `{group}` uses node {t}, which the file's $Nodes does not define")
        })?;
        if !(p[0].is_finite() && p[1].is_finite() && p[2].is_finite()) {
            return Err(format!(
                "node {t} has a coordinate that is not finite: {p:?}"
            ));
        }
        extent = extent.max(p[0].abs()).max(p[1].abs());
        index.insert(t, nodes.len() as u32);
        nodes.push([p[0], p[1]]);
        node_tags.push(t);
    }
    for &t in &used {
        let z = coords[&t][2];
        if z.abs() > 1e-9 * extent.max(f64::MIN_POSITIVE) {
            return Err(format!(
                "node {t} of group `{group}` has z = {z:e}: a 2D mesh lies in the xy-plane"
            ));
        }
    }
    let mut quads = Vec::with_capacity(raw.len());
    let mut element_tags = Vec::with_capacity(raw.len());
    let mut reoriented = 0;
    for (etag, q) in &raw {
        let tri = q[2] == q[3];
        let mut l = q.map(|t| index[&t]);
        let p = |k: usize| nodes[l[k] as usize];
        let area2: f64 = (0..4)
            .map(|k| {
                let (a, b) = (p(k), p((k + 1) % 4));
                a[0] * b[1] - b[0] * a[1]
            })
            .sum();
        if area2 < 0.0 {
            l = if tri {
                [l[0], l[2], l[1], l[1]]
            } else {
                [l[0], l[3], l[2], l[1]]
            };
            reoriented += 1;
        }
        let p = |k: usize| nodes[l[k] as usize];
        // Corner Jacobians (cross products of the two edges at each corner), all positive for
        // a convex quad of positive area; a triangle has the one (its corner 0).
        let scale = (0..4)
            .map(|k| {
                let (a, b) = (p(k), p((k + 1) % 4));
                (b[0] - a[0]).hypot(b[1] - a[1])
            })
            .fold(0.0f64, f64::max);
        let worst = (0..if tri { 1 } else { 4 })
            .map(|k| {
                let (a, b, c) = (p((k + 3) % 4), p(k), p((k + 1) % 4));
                let (e1, e2) = ([c[0] - b[0], c[1] - b[1]], [a[0] - b[0], a[1] - b[1]]);
                e1[0] * e2[1] - e1[1] * e2[0]
            })
            .fold(f64::INFINITY, f64::min);
        if worst.is_nan() || worst <= 1e-12 * scale * scale {
            let tags: Vec<String> = q[..if tri { 3 } else { 4 }]
                .iter()
                .map(|t| t.to_string())
                .collect();
            return Err(format!(
                "element {etag} of group `{group}` (nodes {}) is inverted or has zero area: its \
                 smallest corner Jacobian is {worst:e} (edges up to {scale:e})",
                tags.join(" ")
            ));
        }
        quads.push(l);
        element_tags.push(*etag);
    }
    let groups = node_groups(&file, &index);
    Ok(SurfaceMesh {
        nodes,
        node_tags,
        quads,
        element_tags,
        reoriented,
        groups,
        digest: digest(bytes),
    })
}

/// The physical curves and points of the file (named or only numbered) restricted to the nodes
/// in `index` (Gmsh tag to surface index): the nodes of their 2-node lines and points, and the
/// lines with both nodes in.
fn node_groups(file: &msh::MshFile, index: &HashMap<u64, u32>) -> Vec<NodeGroup> {
    let mut out = Vec::new();
    for dim in [1, 0] {
        for (tag, name) in groups_of(file, dim) {
            // The points or curves of the physical group.
            let tags: HashSet<i32> = file.entities[dim as usize]
                .iter()
                .filter(|e| e.physical.iter().any(|&p| p.abs() == tag))
                .map(|e| e.tag)
                .collect();
            let mut nodes = BTreeSet::new();
            let mut edges = Vec::new();
            for b in &file.elements {
                if b.dim != dim || !tags.contains(&b.entity) {
                    continue;
                }
                for e in b.nodes.chunks(b.per) {
                    let local: Vec<u32> = e.iter().filter_map(|t| index.get(t).copied()).collect();
                    match b.kind {
                        LIN2 if local.len() == 2 => {
                            edges.push([local[0], local[1]]);
                            nodes.extend(local);
                        }
                        PNT if local.len() == 1 => {
                            nodes.extend(local);
                        }
                        _ => {}
                    }
                }
            }
            if !nodes.is_empty() {
                out.push(NodeGroup {
                    name,
                    tag,
                    dim,
                    nodes: nodes.into_iter().collect(),
                    edges,
                });
            }
        }
    }
    out
}
