//! Gmsh meshes: the elements of one physical surface of an MSH 4.1 file (ASCII or binary), read
//! with the `mshio` crate, as a body's nodes and counter-clockwise quads and triangles (a
//! triangle as the collapsed quad `[a, b, c, c]`, see [`crate::element`]). `mshio` reads the
//! entities, nodes and elements; the names of the physical groups (`$PhysicalNames`) are read
//! here. Every problem is reported as a sentence naming the group and, for an element, its Gmsh
//! tag and nodes; the scene parser puts it in an [`crate::Error::Invalid`] with the scene file,
//! the key and the mesh file.

use std::collections::{BTreeSet, HashMap, HashSet};
use std::path::Path;

use mshio::mshfile::ElementType;

/// Mesh files larger than this are refused before they are read (no unbounded allocation).
pub const MAX_FILE_BYTES: u64 = 1 << 30;

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
}

/// A physical curve or point of a mesh file, restricted to one surface's nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeGroup {
    /// Its name in `$PhysicalNames`.
    pub name: String,
    /// 1 for a curve, 0 for a point.
    pub dim: i32,
    /// Indices into [`SurfaceMesh::nodes`], ascending.
    pub nodes: Vec<u32>,
    /// The curve's 2-node line elements whose two nodes are in the surface, as indices into
    /// [`SurfaceMesh::nodes`] (none for a point).
    pub edges: Vec<[u32; 2]>,
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
    Ok(v.to_string())
}

/// The physical groups named in `$PhysicalNames` (none when the section is absent).
///
/// # Errors
/// A sentence naming the malformed line.
pub fn physical_names(bytes: &[u8]) -> Result<Vec<PhysicalName>, String> {
    let Some(s) = section(bytes, "PhysicalNames") else {
        return Ok(Vec::new());
    };
    let text = std::str::from_utf8(s).map_err(|_| "its $PhysicalNames section is not text")?;
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let count: usize = lines
        .next()
        .and_then(|l| l.parse().ok())
        .ok_or("its $PhysicalNames section does not start with a count")?;
    let mut out = Vec::new();
    for line in lines {
        let mut parts = line.splitn(3, char::is_whitespace);
        let bad = || format!("malformed $PhysicalNames line `{line}`");
        let dim: i32 = parts.next().and_then(|p| p.parse().ok()).ok_or_else(bad)?;
        let tag: i32 = parts.next().and_then(|p| p.parse().ok()).ok_or_else(bad)?;
        let name = parts
            .next()
            .ok_or_else(bad)?
            .trim()
            .trim_matches('"')
            .to_string();
        out.push(PhysicalName { dim, tag, name });
    }
    if out.len() != count {
        return Err(format!(
            "its $PhysicalNames section announces {count} names and has {}",
            out.len()
        ));
    }
    Ok(out)
}

fn dim_word(dim: i32) -> &'static str {
    match dim {
        0 => "point",
        1 => "curve",
        2 => "surface",
        _ => "volume",
    }
}

/// The file's bytes, refusing what cannot be a mesh file this program should read whole.
///
/// # Errors
/// A sentence when the file cannot be read or is larger than [`MAX_FILE_BYTES`].
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read the mesh file: {e}"))?;
    if meta.len() > MAX_FILE_BYTES {
        return Err(format!(
            "the mesh file has {} bytes, more than the {} MiB read at most",
            meta.len(),
            MAX_FILE_BYTES >> 20
        ));
    }
    std::fs::read(path).map_err(|e| format!("cannot read the mesh file: {e}"))
}

/// The quads and triangles of physical surface `group` of the MSH 4.1 file `bytes`.
///
/// # Errors
/// A sentence naming the group and the problem: another MSH version, a group that does not
/// exist or is not a surface, elements other than 4-node quads and 3-node triangles in it (type
/// and count), a node off the xy-plane, an element whose corners do not make a convex element of
/// positive area (its Gmsh tag and nodes).
pub fn read_surface(bytes: &[u8], group: &str) -> Result<SurfaceMesh, String> {
    let v = version(bytes)?;
    if v != "4.1" {
        return Err(format!(
            "MSH format version {v}: ricochet reads version 4.1 (in Gmsh: \
             Mesh.MshFileVersion = 4.1, or `gmsh -format msh41`)"
        ));
    }
    let names = physical_names(bytes)?;
    let tag = match names.iter().find(|n| n.name == group && n.dim == 2) {
        Some(n) => n.tag,
        None => {
            if let Some(n) = names.iter().find(|n| n.name == group) {
                return Err(format!(
                    "group `{group}` is a physical {}, not a surface: a body is the elements \
                     of a physical surface",
                    dim_word(n.dim)
                ));
            }
            let surfaces: Vec<&str> = names
                .iter()
                .filter(|n| n.dim == 2)
                .map(|n| n.name.as_str())
                .collect();
            return Err(format!(
                "no physical surface named `{group}` (the file names {})",
                if surfaces.is_empty() {
                    "none".to_string()
                } else {
                    surfaces.join(", ")
                }
            ));
        }
    };
    let msh = mshio::parse_msh_bytes(bytes).map_err(|e| {
        let full = format!("{e}");
        let short: String = full.lines().take(4).collect::<Vec<_>>().join("; ");
        format!("not a readable MSH 4.1 file: {short}")
    })?;
    let data = &msh.data;
    let entities: HashSet<i32> = data
        .entities
        .as_ref()
        .map(|e| {
            e.surfaces
                .iter()
                .filter(|s| s.physical_tags.iter().any(|&p| p.abs() == tag))
                .map(|s| s.tag)
                .collect()
        })
        .unwrap_or_default();
    if entities.is_empty() {
        return Err(format!(
            "group `{group}` (physical tag {tag}) holds no surface of the file's $Entities"
        ));
    }
    let mut raw: Vec<(u64, [u64; 4])> = Vec::new();
    let mut other: Vec<(ElementType, usize)> = Vec::new();
    if let Some(el) = &data.elements {
        for b in &el.element_blocks {
            if b.entity_dim != 2 || !entities.contains(&b.entity_tag) {
                continue;
            }
            let corners = match b.element_type {
                ElementType::Qua4 => 4,
                ElementType::Tri3 => 3,
                _ => 0,
            };
            if corners > 0 {
                for e in &b.elements {
                    let n = e.nodes.as_slice();
                    if n.len() != corners {
                        return Err(format!(
                            "element {} of group `{group}` has {} nodes, not {corners}",
                            e.element_tag,
                            n.len()
                        ));
                    }
                    // A triangle is a collapsed quad [a, b, c, c] (see ricochet::element).
                    raw.push((e.element_tag, [n[0], n[1], n[2], n[corners - 1]]));
                }
            } else {
                match other.iter_mut().find(|o| o.0 == b.element_type) {
                    Some(o) => o.1 += b.elements.len(),
                    None => other.push((b.element_type, b.elements.len())),
                }
            }
        }
    }
    if !other.is_empty() {
        let list: Vec<String> = other
            .iter()
            .map(|(t, n)| format!("{n} x {t:?} (Gmsh type {})", *t as u8))
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
    // Node coordinates by tag. Dense tags are not kept by mshio: they run from the smallest tag
    // in the order the blocks are written, which is how Gmsh writes them.
    let mut coords: HashMap<u64, [f64; 3]> = HashMap::new();
    if let Some(nodes) = &data.nodes {
        let mut next = nodes.min_node_tag;
        for b in &nodes.node_blocks {
            match &b.node_tags {
                Some(map) => {
                    for (&t, &i) in map {
                        let p = &b.nodes[i];
                        coords.insert(t, [p.x, p.y, p.z]);
                    }
                }
                None => {
                    for p in &b.nodes {
                        coords.insert(next, [p.x, p.y, p.z]);
                        next += 1;
                    }
                }
            }
        }
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
    let groups = node_groups(data, &names, &index);
    Ok(SurfaceMesh {
        nodes,
        node_tags,
        quads,
        element_tags,
        reoriented,
        groups,
    })
}

/// The physical curves and points of the file restricted to the nodes in `index` (Gmsh tag to
/// surface index): the nodes of their 2-node lines and points, and the lines with both nodes in.
fn node_groups(
    data: &mshio::mshfile::MshData<u64, i32, f64>,
    names: &[PhysicalName],
    index: &HashMap<u64, u32>,
) -> Vec<NodeGroup> {
    let Some(entities) = &data.entities else {
        return Vec::new();
    };
    let Some(elements) = &data.elements else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for n in names.iter().filter(|n| n.dim == 0 || n.dim == 1) {
        // The points or curves of the physical group.
        let member =
            |tag: i32, physical: &[i32]| physical.iter().any(|&p| p.abs() == n.tag).then_some(tag);
        let tags: HashSet<i32> = if n.dim == 0 {
            entities
                .points
                .iter()
                .filter_map(|e| member(e.tag, &e.physical_tags))
                .collect()
        } else {
            entities
                .curves
                .iter()
                .filter_map(|e| member(e.tag, &e.physical_tags))
                .collect()
        };
        let mut nodes = BTreeSet::new();
        let mut edges = Vec::new();
        for b in &elements.element_blocks {
            if b.entity_dim != n.dim || !tags.contains(&b.entity_tag) {
                continue;
            }
            for e in &b.elements {
                let local: Vec<u32> = e
                    .nodes
                    .iter()
                    .filter_map(|t| index.get(t).copied())
                    .collect();
                match b.element_type {
                    ElementType::Lin2 if local.len() == 2 => {
                        edges.push([local[0], local[1]]);
                        nodes.extend(local);
                    }
                    ElementType::Pnt if local.len() == 1 => {
                        nodes.extend(local);
                    }
                    _ => {}
                }
            }
        }
        if !nodes.is_empty() {
            out.push(NodeGroup {
                name: n.name.clone(),
                dim: n.dim,
                nodes: nodes.into_iter().collect(),
                edges,
            });
        }
    }
    out
}
