//! The sections of a Gmsh MSH 4.1 file that ricochet reads (`$MeshFormat`, `$PhysicalNames`,
//! `$Entities`, `$Nodes`, `$Elements`; the others are skipped), ASCII or binary, as plain arrays
//! ([`MshFile`]). Every count, size and tag comes from the file and is checked before it is
//! used: a count is compared with the bytes left before anything is allocated for it, a node
//! tag must be unique and within the `$Nodes` header's range, and a problem is a sentence naming
//! the section and the value (never a panic). Host-side only, no GPU twin; [`super`] turns the
//! arrays into a body's mesh.

use std::collections::HashSet;

/// An entity of `$Entities` (a point, curve, surface or volume) and its physical tags.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entity {
    /// Its tag.
    pub tag: i32,
    /// The physical groups it belongs to (a sign gives an orientation, which is ignored).
    pub physical: Vec<i32>,
}

/// One block of `$Nodes`: the nodes of one entity.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeBlock {
    /// Dimension of the entity.
    pub dim: i32,
    /// Tag of the entity.
    pub entity: i32,
    /// The nodes' tags.
    pub tags: Vec<u64>,
    /// The nodes' coordinates (x, y, z), in the order of `tags`.
    pub coords: Vec<[f64; 3]>,
}

/// One block of `$Elements`: elements of one type on one entity.
#[derive(Debug, Clone, PartialEq)]
pub struct ElementBlock {
    /// Dimension of the entity.
    pub dim: i32,
    /// Tag of the entity.
    pub entity: i32,
    /// Gmsh element type.
    pub kind: i32,
    /// Nodes per element.
    pub per: usize,
    /// The elements' tags.
    pub tags: Vec<u64>,
    /// The elements' node tags, `per` for each element.
    pub nodes: Vec<u64>,
}

/// What ricochet reads of an MSH 4.1 file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MshFile {
    /// Physical groups named in `$PhysicalNames`: (dimension, tag, name).
    pub names: Vec<(i32, i32, String)>,
    /// Entities by dimension: points, curves, surfaces, volumes.
    pub entities: [Vec<Entity>; 4],
    /// Node blocks.
    pub nodes: Vec<NodeBlock>,
    /// Element blocks.
    pub elements: Vec<ElementBlock>,
}

/// Gmsh's element types (`GmshDefines.h`): number, name and nodes (0: not a fixed count).
#[rustfmt::skip]
const TYPES: [(i32, &str, u16); 137] = [
    (1, "Lin2", 2), (2, "Tri3", 3), (3, "Qua4", 4), (4, "Tet4", 4), (5, "Hex8", 8), (6, "Pri6", 6),
    (7, "Pyr5", 5), (8, "Lin3", 3), (9, "Tri6", 6), (10, "Qua9", 9), (11, "Tet10", 10),
    (12, "Hex27", 27), (13, "Pri18", 18), (14, "Pyr14", 14), (15, "Pnt", 1), (16, "Qua8", 8),
    (17, "Hex20", 20), (18, "Pri15", 15), (19, "Pyr13", 13), (20, "Tri9", 9), (21, "Tri10", 10),
    (22, "Tri12", 12), (23, "Tri15", 15), (24, "Tri15i", 15), (25, "Tri21", 21), (26, "Lin4", 4),
    (27, "Lin5", 5), (28, "Lin6", 6), (29, "Tet20", 20), (30, "Tet35", 35), (31, "Tet56", 56),
    (32, "Tet22", 22), (33, "Tet28", 28), (34, "Polyg", 0), (35, "Polyh", 0), (36, "Qua16", 16),
    (37, "Qua25", 25), (38, "Qua36", 36), (39, "Qua12", 12), (40, "Qua16i", 16), (41, "Qua20", 20),
    (42, "Tri28", 28), (43, "Tri36", 36), (44, "Tri45", 45), (45, "Tri55", 55), (46, "Tri66", 66),
    (47, "Qua49", 49), (48, "Qua64", 64), (49, "Qua81", 81), (50, "Qua100", 100),
    (51, "Qua121", 121), (52, "Tri18", 18), (53, "Tri21i", 21), (54, "Tri24", 24),
    (55, "Tri27", 27), (56, "Tri30", 30), (57, "Qua24", 24), (58, "Qua28", 28), (59, "Qua32", 32),
    (60, "Qua36i", 36), (61, "Qua40", 40), (62, "Lin7", 7), (63, "Lin8", 8), (64, "Lin9", 9),
    (65, "Lin10", 10), (66, "Lin11", 11), (67, "LinB", 0), (68, "TriB", 0), (69, "PolygB", 0),
    (70, "LinC", 0), (71, "Tet84", 84), (72, "Tet120", 120), (73, "Tet165", 165),
    (74, "Tet220", 220), (75, "Tet286", 286), (79, "Tet34", 34), (80, "Tet40", 40),
    (81, "Tet46", 46), (82, "Tet52", 52), (83, "Tet58", 58), (84, "Lin1", 1), (85, "Tri1", 1),
    (86, "Qua1", 1), (87, "Tet1", 1), (88, "Hex1", 1), (89, "Pri1", 1), (90, "Pri40", 40),
    (91, "Pri75", 75), (92, "Hex64", 64), (93, "Hex125", 125), (94, "Hex216", 216),
    (95, "Hex343", 343), (96, "Hex512", 512), (97, "Hex729", 729), (98, "Hex1000", 1000),
    (99, "Hex32", 32), (100, "Hex44", 44), (101, "Hex56", 56), (102, "Hex68", 68),
    (103, "Hex80", 80), (104, "Hex92", 92), (105, "Hex104", 104), (106, "Pri126", 126),
    (107, "Pri196", 196), (108, "Pri288", 288), (109, "Pri405", 405), (110, "Pri550", 550),
    (111, "Pri24", 24), (112, "Pri33", 33), (113, "Pri42", 42), (114, "Pri51", 51),
    (115, "Pri60", 60), (116, "Pri69", 69), (117, "Pri78", 78), (118, "Pyr30", 30),
    (119, "Pyr55", 55), (120, "Pyr91", 91), (121, "Pyr140", 140), (122, "Pyr204", 204),
    (123, "Pyr285", 285), (124, "Pyr385", 385), (125, "Pyr21", 21), (126, "Pyr29", 29),
    (127, "Pyr37", 37), (128, "Pyr45", 45), (129, "Pyr53", 53), (130, "Pyr61", 61),
    (131, "Pyr69", 69), (132, "Pyr1", 1), (133, "PntSub", 0), (134, "LinSub", 0),
    (135, "TriSub", 0), (136, "TetSub", 0), (137, "Tet16", 16), (138, "TriMini", 0),
    (139, "TetMini", 0), (140, "Trih4", 0),
];

/// The name of Gmsh element type `kind` (`Qua9`), or `type N` for a number Gmsh does not define.
pub fn type_name(kind: i32) -> String {
    TYPES
        .iter()
        .find(|t| t.0 == kind)
        .map_or_else(|| format!("type {kind}"), |t| t.1.to_string())
}

fn type_nodes(kind: i32) -> Option<usize> {
    TYPES
        .iter()
        .find(|t| t.0 == kind && t.2 > 0)
        .map(|t| t.2 as usize)
}

/// Reads the numbers of a section, in either encoding.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    binary: bool,
    /// Bytes of a `size_t` in a binary file (4 or 8).
    size_t: usize,
    little: bool,
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

impl Reader<'_> {
    fn left(&self) -> usize {
        self.bytes.len() - self.at
    }

    fn skip_space(&mut self) {
        while self.at < self.bytes.len() && self.bytes[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
    }

    /// The next whitespace-delimited word (ASCII), as text.
    fn word(&mut self, what: &str) -> Result<&str, String> {
        self.skip_space();
        let start = self.at;
        while self.at < self.bytes.len() && !self.bytes[self.at].is_ascii_whitespace() {
            self.at += 1;
        }
        if start == self.at {
            return Err(format!("the file ends where {what} should be"));
        }
        std::str::from_utf8(&self.bytes[start..self.at])
            .map_err(|_| format!("{what} is not a number"))
    }

    fn raw<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        let Some(b) = self.bytes.get(self.at..self.at + N) else {
            return Err(format!("the file ends where {what} should be"));
        };
        self.at += N;
        let mut out = [0u8; N];
        out.copy_from_slice(b);
        if !self.little {
            out.reverse();
        }
        Ok(out)
    }

    /// A `size_t` (a count or a tag).
    fn size(&mut self, what: &str) -> Result<u64, String> {
        if !self.binary {
            let w = self.word(what)?;
            return w
                .parse()
                .map_err(|_| format!("{what} is `{}`, not a count or tag", clip(w)));
        }
        Ok(if self.size_t == 4 {
            u32::from_le_bytes(self.raw::<4>(what)?) as u64
        } else {
            u64::from_le_bytes(self.raw::<8>(what)?)
        })
    }

    /// An `int`.
    fn int(&mut self, what: &str) -> Result<i32, String> {
        if !self.binary {
            let w = self.word(what)?;
            return w
                .parse()
                .map_err(|_| format!("{what} is `{}`, not a 32-bit integer", clip(w)));
        }
        Ok(i32::from_le_bytes(self.raw::<4>(what)?))
    }

    /// A `double`.
    fn float(&mut self, what: &str) -> Result<f64, String> {
        if !self.binary {
            let w = self.word(what)?;
            return w
                .parse()
                .map_err(|_| format!("{what} is `{}`, not a number", clip(w)));
        }
        Ok(f64::from_le_bytes(self.raw::<8>(what)?))
    }

    /// A count of items of at least `item` bytes each (in the file's encoding), checked against
    /// the bytes left before anything is allocated for it.
    fn count(&mut self, what: &str, item: usize) -> Result<usize, String> {
        let n = self.size(what)?;
        let room = self.left() / item.max(1);
        if n > room as u64 {
            return Err(format!(
                "{what} is {n}, more than the {} bytes left in the file can hold",
                self.left()
            ));
        }
        Ok(n as usize)
    }

    /// Bytes of a `size_t`, `int` and `double` at least (ASCII: a digit and a separator).
    fn sizes(&self) -> (usize, usize, usize) {
        if self.binary {
            (self.size_t, 4, 8)
        } else {
            (2, 2, 2)
        }
    }

    /// The end marker `$End<name>` of the section just read.
    fn end(&mut self, name: &str) -> Result<(), String> {
        self.skip_space();
        let tag = format!("$End{name}");
        if !self.bytes[self.at..].starts_with(tag.as_bytes()) {
            return Err(format!(
                "its ${name} section does not end with {tag} where its counts say it ends"
            ));
        }
        self.at += tag.len();
        Ok(())
    }
}

fn clip(s: &str) -> String {
    s.chars().take(40).collect()
}

/// The `$MeshFormat` header: version text, binary or not, size of `size_t`, little-endian.
/// The checks of `super::version` (the version alone) come first, for their message.
fn header(bytes: &[u8]) -> Result<(bool, usize, bool, usize), String> {
    let start = b"$MeshFormat";
    let mut at = 0;
    while at < bytes.len() && bytes[at].is_ascii_whitespace() {
        at += 1;
    }
    if !bytes[at..].starts_with(start) {
        return Err("not a Gmsh mesh file: it does not start with $MeshFormat".into());
    }
    at += start.len();
    let line_end = at
        + find(&bytes[at..], b"\n")
            .ok_or("its $MeshFormat section is cut short")?
            .min(bytes.len() - at);
    // The line after `$MeshFormat`.
    let body_start = line_end + 1;
    let body_end = body_start
        + find(&bytes[body_start.min(bytes.len())..], b"\n")
            .ok_or("its $MeshFormat section is cut short")?;
    let line = std::str::from_utf8(&bytes[body_start..body_end])
        .map_err(|_| "its $MeshFormat line is not text")?;
    let parts: Vec<&str> = line.split_whitespace().collect();
    let [version, file_type, data_size] = parts[..] else {
        return Err(format!(
            "its $MeshFormat line `{}` is not `version file-type data-size`",
            clip(line)
        ));
    };
    if version != "4.1" {
        return Err(format!(
            "MSH format version {}: ricochet reads version 4.1 (in Gmsh: Mesh.MshFileVersion \
             = 4.1, or `gmsh -format msh41`)",
            clip(version)
        ));
    }
    let binary = match file_type {
        "0" => false,
        "1" => true,
        other => {
            return Err(format!(
                "its $MeshFormat file type is `{}`: 0 (ASCII) or 1 (binary)",
                clip(other)
            ))
        }
    };
    let size_t = match data_size {
        "4" => 4,
        "8" => 8,
        other => {
            return Err(format!(
                "its $MeshFormat data size is `{}`: Gmsh writes 8 (the bytes of a size_t; 4 on \
                 32-bit machines)",
                clip(other)
            ))
        }
    };
    let mut at = body_end + 1;
    let mut little = true;
    if binary {
        let one = bytes
            .get(at..at + 4)
            .ok_or("its $MeshFormat section is cut short (no endianness test)")?;
        if i32::from_le_bytes([one[0], one[1], one[2], one[3]]) == 1 {
            little = true;
        } else if i32::from_be_bytes([one[0], one[1], one[2], one[3]]) == 1 {
            little = false;
        } else {
            return Err("its binary $MeshFormat has no endianness test value (the int 1)".into());
        }
        at += 4;
    }
    Ok((binary, size_t, little, at))
}

/// Reads the sections ricochet uses from the bytes of an MSH 4.1 file.
///
/// # Errors
/// A sentence naming the section and the problem: another version, a bad header, a section
/// cut short or repeated, a count larger than the file, an unknown element type, a node tag
/// that is 0, outside the header's range or given twice.
pub fn parse(bytes: &[u8]) -> Result<MshFile, String> {
    let (binary, size_t, little, at) = header(bytes)?;
    let mut r = Reader {
        bytes,
        at,
        binary,
        size_t,
        little,
    };
    r.end("MeshFormat")?;
    let mut out = MshFile::default();
    let mut seen: HashSet<String> = HashSet::new();
    loop {
        r.skip_space();
        if r.at >= bytes.len() {
            break;
        }
        if bytes[r.at] != b'$' {
            return Err(format!(
                "byte {} is not the start of a section (`$Name`)",
                r.at
            ));
        }
        let line = find(&bytes[r.at..], b"\n").map_or(bytes.len(), |n| r.at + n);
        let name = std::str::from_utf8(&bytes[r.at + 1..line])
            .map_err(|_| format!("the section header at byte {} is not text", r.at))?
            .trim()
            .to_string();
        if name.is_empty() || !name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_') {
            return Err(format!(
                "the section header at byte {} is `${}`",
                r.at,
                clip(&name)
            ));
        }
        r.at = (line + 1).min(bytes.len());
        let known = matches!(
            name.as_str(),
            "PhysicalNames" | "Entities" | "Nodes" | "Elements"
        );
        if known && !seen.insert(name.clone()) {
            return Err(format!("it has two ${name} sections"));
        }
        match name.as_str() {
            "PhysicalNames" => {
                let end = find(&bytes[r.at..], b"$EndPhysicalNames")
                    .ok_or("its $PhysicalNames section has no $EndPhysicalNames")?;
                out.names = physical_names(&bytes[r.at..r.at + end])?;
                r.at += end;
            }
            "Entities" => out.entities = entities(&mut r)?,
            "Nodes" => out.nodes = nodes(&mut r)?,
            "Elements" => out.elements = elements(&mut r)?,
            _ => {
                let tag = format!("$End{name}");
                let end = find(&bytes[r.at..], tag.as_bytes())
                    .ok_or_else(|| format!("its ${name} section has no {tag}"))?;
                r.at += end;
            }
        }
        r.end(&name)?;
    }
    Ok(out)
}

/// The lines of `$PhysicalNames` (the text between its markers): `dim tag "name"`.
pub fn physical_names(s: &[u8]) -> Result<Vec<(i32, i32, String)>, String> {
    let text = std::str::from_utf8(s).map_err(|_| "its $PhysicalNames section is not text")?;
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let count: usize = lines
        .next()
        .and_then(|l| l.parse().ok())
        .ok_or("its $PhysicalNames section does not start with a count")?;
    let mut out = Vec::new();
    for line in lines {
        let mut parts = line.splitn(3, char::is_whitespace);
        let bad = || format!("malformed $PhysicalNames line `{}`", clip(line));
        let dim: i32 = parts.next().and_then(|p| p.parse().ok()).ok_or_else(bad)?;
        let tag: i32 = parts.next().and_then(|p| p.parse().ok()).ok_or_else(bad)?;
        let name = parts
            .next()
            .ok_or_else(bad)?
            .trim()
            .trim_matches('"')
            .to_string();
        out.push((dim, tag, name));
    }
    if out.len() != count {
        return Err(format!(
            "its $PhysicalNames section announces {count} names and has {}",
            out.len()
        ));
    }
    Ok(out)
}

fn entities(r: &mut Reader) -> Result<[Vec<Entity>; 4], String> {
    let (st, int, dbl) = r.sizes();
    let mut counts = [0usize; 4];
    for (d, c) in counts.iter_mut().enumerate() {
        *c = r.count(
            &format!("the $Entities count of dimension {d}"),
            int + 3 * dbl + st,
        )?;
    }
    let mut out: [Vec<Entity>; 4] = Default::default();
    for (d, &n) in counts.iter().enumerate() {
        for i in 0..n {
            let what = |w: &str| format!("{w} of $Entities entity {} of dimension {d}", i + 1);
            let tag = r.int(&what("the tag"))?;
            // A point's coordinates, or the bounding box of a curve, surface or volume.
            for _ in 0..if d == 0 { 3 } else { 6 } {
                r.float(&what("a coordinate"))?;
            }
            let np = r.count(&what("the number of physical tags"), int)?;
            let mut physical = Vec::with_capacity(np);
            for _ in 0..np {
                physical.push(r.int(&what("a physical tag"))?);
            }
            if d > 0 {
                let nb = r.count(&what("the number of bounding entities"), int)?;
                for _ in 0..nb {
                    r.int(&what("a bounding entity"))?;
                }
            }
            out[d].push(Entity { tag, physical });
        }
    }
    Ok(out)
}

fn nodes(r: &mut Reader) -> Result<Vec<NodeBlock>, String> {
    let (st, int, dbl) = r.sizes();
    let blocks = r.count("the $Nodes block count", 3 * int + st)?;
    let total = r.size("the $Nodes node count")?;
    let min = r.size("the $Nodes smallest tag")?;
    let max = r.size("the $Nodes largest tag")?;
    if total > 0 && (min == 0 || max < min) {
        return Err(format!(
            "its $Nodes header gives the tag range {min} to {max}: node tags start at 1"
        ));
    }
    let mut out = Vec::with_capacity(blocks);
    let mut seen: HashSet<u64> = HashSet::new();
    let mut count = 0u64;
    for b in 0..blocks {
        let what = |w: &str| format!("{w} of $Nodes block {}", b + 1);
        let dim = r.int(&what("the entity dimension"))?;
        let entity = r.int(&what("the entity tag"))?;
        let parametric = r.int(&what("the parametric flag"))?;
        if !(0..=3).contains(&dim) || !(0..=1).contains(&parametric) {
            return Err(format!(
                "{} is {dim} and {}: dimensions are 0 to 3 and the flag 0 or 1",
                what("the entity dimension and parametric flag"),
                parametric
            ));
        }
        let extra = if parametric == 1 { dim as usize } else { 0 };
        let n = r.count(&what("the node count"), st + (3 + extra) * dbl)?;
        let mut tags = Vec::with_capacity(n);
        for _ in 0..n {
            let t = r.size(&what("a node tag"))?;
            if t == 0 || t < min || t > max {
                return Err(format!(
                    "{} is {t}, outside the range {min} to {max} of its $Nodes header (tags \
                     start at 1)",
                    what("a node tag")
                ));
            }
            if !seen.insert(t) {
                return Err(format!("node tag {t} is given twice in $Nodes"));
            }
            tags.push(t);
        }
        let mut coords = Vec::with_capacity(n);
        for _ in 0..n {
            let p = [
                r.float(&what("an x coordinate"))?,
                r.float(&what("a y coordinate"))?,
                r.float(&what("a z coordinate"))?,
            ];
            for _ in 0..extra {
                r.float(&what("a parametric coordinate"))?;
            }
            coords.push(p);
        }
        count += n as u64;
        out.push(NodeBlock {
            dim,
            entity,
            tags,
            coords,
        });
    }
    if count != total {
        return Err(format!(
            "its $Nodes header announces {total} nodes and its blocks hold {count}"
        ));
    }
    Ok(out)
}

fn elements(r: &mut Reader) -> Result<Vec<ElementBlock>, String> {
    let (st, int, _) = r.sizes();
    let blocks = r.count("the $Elements block count", 3 * int + st)?;
    let total = r.size("the $Elements element count")?;
    r.size("the $Elements smallest tag")?;
    r.size("the $Elements largest tag")?;
    let mut out = Vec::with_capacity(blocks);
    let mut count = 0u64;
    for b in 0..blocks {
        let what = |w: &str| format!("{w} of $Elements block {}", b + 1);
        let dim = r.int(&what("the entity dimension"))?;
        let entity = r.int(&what("the entity tag"))?;
        let kind = r.int(&what("the element type"))?;
        let per = type_nodes(kind).ok_or_else(|| {
            format!(
                "{} is {kind} ({}), which ricochet cannot read (not a Gmsh element type of a \
                 fixed node count)",
                what("the element type"),
                type_name(kind)
            )
        })?;
        let n = r.count(&what("the element count"), (per + 1) * st)?;
        let mut tags = Vec::with_capacity(n);
        let mut nodes = Vec::with_capacity(n * per);
        for _ in 0..n {
            tags.push(r.size(&what("an element tag"))?);
            for _ in 0..per {
                nodes.push(r.size(&what("a node tag of an element"))?);
            }
        }
        count += n as u64;
        out.push(ElementBlock {
            dim,
            entity,
            kind,
            per,
            tags,
            nodes,
        });
    }
    if count != total {
        return Err(format!(
            "its $Elements header announces {total} elements and its blocks hold {count}"
        ));
    }
    Ok(out)
}
