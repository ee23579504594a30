//! Hostile and unusual Gmsh mesh files (issue 40, items 1-3 and 12): a binary `$MeshFormat`
//! with any data size, a mesh path that is an endless stream or a FIFO, node tags that are
//! permuted, repeated, 0 or out of the header's range, and physical groups that have numbers
//! but no names. Each is read by `ricochet check` (bounded in time and memory, so that a reader
//! that hangs or reads without bound fails the test instead of the machine) or in process.

use std::path::{Path, PathBuf};

use ricochet::gmsh::{read_bytes, read_surface};

use crate::common::*;
use crate::gmsh::test_mesh;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A one-body scene of the mesh file `mesh`, physical surface `group` (TOML: `"square"` or
/// `1`), with `tables` appended.
fn scene(mesh: &Path, group: &str, tables: &str) -> String {
    format!(
        "[run]\nend_time = 1.0e-6\n[[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\n\
         density = 7850.0\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.3\n\
         [[body]]\nname = \"part\"\nmaterial = \"steel\"\n\
         mesh = {{ gmsh = {:?}, group = {group} }}\n{tables}",
        mesh.to_string_lossy()
    )
}

/// `ricochet check` on scene `text` written as `dir/scene.toml`, bounded to 60 s and 4 GiB:
/// (exit code, stderr).
fn check(dir: &Path, text: &str) -> (Option<i32>, String) {
    let file = dir.join("scene.toml");
    std::fs::write(&file, text).expect("write the scene");
    let (o, killed) = run_bin_bounded(&["check", file.to_str().expect("path")], 60);
    assert!(!killed, "`ricochet check` ran for more than 60 s");
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Asserts that `ricochet check` refuses the scene of mesh `mesh` with exit 2, naming the mesh
/// file and each of `needles`.
fn refused(dir: &Path, mesh: &Path, needles: &[&str]) -> String {
    let (code, err) = check(dir, &scene(mesh, "\"square\"", ""));
    assert_eq!(code, Some(2), "{}: {err}", mesh.display());
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains(&*mesh.to_string_lossy()),
        "no mesh file named: {err}"
    );
    for n in needles {
        assert!(err.contains(n), "{n:?} not in: {err}");
    }
    err
}

#[test]
fn a_binary_mesh_format_with_any_data_size_is_refused_without_a_panic() {
    // Item 1: a data size of 0 or 7 made the mesh reader panic (exit 101).
    let dir = tmp_dir("mesh-data-size");
    let bytes = std::fs::read(test_mesh("square_binary.msh")).expect("square_binary.msh");
    let header = b"4.1 1 8\n";
    let at = bytes
        .windows(header.len())
        .position(|w| w == header)
        .expect("binary header");
    for size in ["0", "7", "16", "99999999999999999999999", "-8", "x"] {
        let mut b = bytes[..at].to_vec();
        b.extend_from_slice(format!("4.1 1 {size}\n").as_bytes());
        b.extend_from_slice(&bytes[at + header.len()..]);
        let mesh = dir.join(format!("size_{size}.msh"));
        std::fs::write(&mesh, b).expect("write");
        let err = refused(&dir, &mesh, &["data size"]);
        println!("data size {size}: {}", err.trim());
    }
    // A data size of 4 (32-bit size_t) is read as such: the file rewritten with 4-byte size_t
    // values would be accepted; with 8-byte values under a header of 4 it is refused.
    let mut b = bytes[..at].to_vec();
    b.extend_from_slice(b"4.1 1 4\n");
    b.extend_from_slice(&bytes[at + header.len()..]);
    let mesh = dir.join("size_4.msh");
    std::fs::write(&mesh, b).expect("write");
    refused(&dir, &mesh, &[]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_mesh_path_that_is_a_stream_a_fifo_or_too_large_is_refused_without_reading_it() {
    // Item 2: `/dev/zero` was read until memory ran out (the cap trusted the reported size).
    let dir = tmp_dir("mesh-streams");
    let fifo = dir.join("fifo.msh");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo");
    assert!(made.success());
    let large = dir.join("large.msh");
    let f = std::fs::File::create(&large).expect("create");
    f.set_len(ricochet::gmsh::MAX_FILE_BYTES + 1)
        .expect("sparse file");
    for (mesh, needle) in [
        (PathBuf::from("/dev/zero"), "not a regular file"),
        (PathBuf::from("/dev/urandom"), "not a regular file"),
        (fifo.clone(), "not a regular file"),
        (dir.clone(), "a folder"),
        (large.clone(), "more than the 1 GiB read at most"),
    ] {
        let t0 = std::time::Instant::now();
        let err = refused(&dir, &mesh, &[needle]);
        assert!(t0.elapsed().as_secs_f64() < 10.0, "{}", mesh.display());
        println!("{}: {}", mesh.display(), err.trim());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `text` (an ASCII MSH 4.1 file) with each `$Nodes` block's (tag, coordinates) lines given to
/// `f`, which may reorder or change them.
fn edit_nodes(text: &str, mut f: impl FnMut(&mut Vec<(String, String)>)) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let start = lines.iter().position(|l| *l == "$Nodes").expect("$Nodes") + 1;
    let mut out: Vec<String> = lines[..=start].iter().map(|s| s.to_string()).collect();
    let blocks: usize = lines[start]
        .split_whitespace()
        .next()
        .and_then(|w| w.parse().ok())
        .expect("block count");
    let mut at = start + 1;
    for _ in 0..blocks {
        out.push(lines[at].to_string());
        let n: usize = lines[at]
            .split_whitespace()
            .nth(3)
            .and_then(|w| w.parse().ok())
            .expect("node count");
        let tags = &lines[at + 1..at + 1 + n];
        let coords = &lines[at + 1 + n..at + 1 + 2 * n];
        let mut pairs: Vec<(String, String)> = tags
            .iter()
            .zip(coords)
            .map(|(t, c)| (t.to_string(), c.to_string()))
            .collect();
        f(&mut pairs);
        out.extend(pairs.iter().map(|p| p.0.clone()));
        out.extend(pairs.iter().map(|p| p.1.clone()));
        at += 1 + 2 * n;
    }
    out.extend(lines[at..].iter().map(|s| s.to_string()));
    out.join("\n") + "\n"
}

#[test]
fn nodes_are_found_by_their_tags_and_bad_tags_are_refused_naming_them() {
    // Item 3: with a dense tag range the tags were ignored and nodes numbered by their order in
    // the file: a valid file listing its nodes in another order was refused as "element
    // inverted", and repeated or zero tags were accepted.
    let text = std::fs::read_to_string(test_mesh("square.msh")).expect("square.msh");
    let original = read_surface(text.as_bytes(), "square").expect("square.msh");
    // Every block's nodes in reverse order (each tag with its own coordinates).
    let reversed = edit_nodes(&text, |p| p.reverse());
    assert_ne!(reversed, text);
    let m = read_surface(reversed.as_bytes(), "square").expect("the nodes in another order");
    assert_eq!(m.node_tags, original.node_tags);
    assert_eq!(m.nodes, original.nodes);
    assert_eq!(m.quads, original.quads);
    assert_eq!(m.reoriented, 0);
    // Through the command line too.
    let dir = tmp_dir("mesh-tags");
    let mesh = dir.join("reversed.msh");
    std::fs::write(&mesh, &reversed).expect("write");
    let (code, err) = check(&dir, &scene(&mesh, "\"square\"", ""));
    assert_eq!(code, Some(0), "{err}");
    // A tag given twice, a tag 0, a tag beyond the header's range (1 to 81).
    let mut first = true;
    let cases: [(&str, String, &str); 3] = [
        (
            "twice",
            edit_nodes(&text, |p| {
                if first && p.len() > 1 {
                    p[1].0 = p[0].0.clone();
                    first = false;
                }
            }),
            "given twice",
        ),
        (
            "zero",
            edit_nodes(&text, |p| {
                if p[0].0 == "1" {
                    p[0].0 = "0".into();
                }
            }),
            "is 0",
        ),
        (
            "beyond",
            edit_nodes(&text, |p| {
                if p[0].0 == "1" {
                    p[0].0 = "82".into();
                }
            }),
            "is 82",
        ),
    ];
    for (name, bad, needle) in cases {
        let mesh = dir.join(format!("{name}.msh"));
        std::fs::write(&mesh, &bad).expect("write");
        let err = refused(&dir, &mesh, &[needle, "$Nodes"]);
        println!("{name}: {}", err.trim());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The notched plate's mesh without its `$PhysicalNames` section: groups with numbers only, as
/// Gmsh's tutorials write them (`Physical Curve(5) = {...};`). The plate is surface 1, the
/// striker 2; the curves are clamp 3, plate_top 4, striker_face 5.
fn numbered_plate(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("assets/gmsh/notched_plate.msh")).expect("mesh");
    let a = text.find("$PhysicalNames").expect("names");
    let b = text.find("$EndPhysicalNames\n").expect("end") + "$EndPhysicalNames\n".len();
    let path = dir.join("numbered.msh");
    std::fs::write(&path, format!("{}{}", &text[..a], &text[b..])).expect("write");
    path
}

/// The notched plate's two bodies from `mesh`, surfaces and curves named by `g` (the TOML of
/// plate, striker, clamp, top, face), with a boundary, a pressure and a contact on faces.
fn plate_scene(mesh: &Path, g: [&str; 5]) -> String {
    let m = mesh.to_string_lossy();
    format!(
        "[run]\nend_time = 2.0e-6\n[[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\n\
         density = 7850.0\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.3\n\
         [[body]]\nname = \"plate\"\nmaterial = \"steel\"\nmesh = {{ gmsh = {m:?}, group = {} }}\n\
         [[body]]\nname = \"striker\"\nmaterial = \"steel\"\nmesh = {{ gmsh = {m:?}, group = {} }}\n\
         initial_velocity = [0.0, -50.0]\n\
         [[boundary]]\nbody = \"plate\"\nregion = {{ group = {} }}\nvelocity = {{ x = 0.0, y = 0.0 }}\n\
         [[pressure]]\nbody = \"plate\"\nregion = {{ group = {} }}\nvalue = 1.0e6\n\
         [[contact]]\nbodies = [\"striker\", \"plate\"]\nmethod = \"lagrange\"\nsurfaces = [{}, {}]\n",
        g[0], g[1], g[2], g[3], g[4], g[3]
    )
}

#[test]
fn physical_groups_with_numbers_only_are_usable_wherever_names_are() {
    // Item 12: `group = "5"` was refused ("the file names ..."), and a number was a type error.
    let dir = tmp_dir("mesh-numbered-groups");
    let numbered = numbered_plate(&dir);
    let named = root().join("assets/gmsh/notched_plate.msh");
    let model = |text: &str| {
        let scene = ricochet::scene::Scene::parse(text, &dir.join("s.toml"))
            .unwrap_or_else(|e| panic!("{e}"));
        ricochet::run::model(&scene).unwrap_or_else(|e| panic!("{e}"))
    };
    let reference = model(&plate_scene(
        &named,
        [
            "\"plate\"",
            "\"striker\"",
            "\"clamp\"",
            "\"plate_top\"",
            "\"striker_face\"",
        ],
    ));
    // Numbers as integers and as strings, on the file without names and on the named file.
    for (mesh, g) in [
        (&numbered, ["1", "2", "3", "4", "5"]),
        (&numbered, ["\"1\"", "\"2\"", "\"3\"", "\"4\"", "\"5\""]),
        (&named, ["1", "\"2\"", "3", "\"4\"", "5"]),
    ] {
        let m = model(&plate_scene(mesh, g));
        assert_eq!(m.quads, reference.quads, "{g:?}");
        assert_eq!(m.position, reference.position, "{g:?}");
        let key = |m: &ricochet::model::Model| {
            m.constraints
                .iter()
                .map(|c| (c.node, c.vx, c.vy))
                .collect::<Vec<_>>()
        };
        assert_eq!(key(&m), key(&reference), "{g:?}");
        assert!(!m.constraints.is_empty());
        assert_eq!(m.pressures[0].nodes, reference.pressures[0].nodes, "{g:?}");
        // The same faces (each named as the scene names it).
        let faces = |m: &ricochet::model::Model| {
            let s = m.contacts[0].surfaces.clone().expect("surfaces");
            s.into_iter().map(|f| f.1).collect::<Vec<_>>()
        };
        assert_eq!(faces(&m), faces(&reference), "{g:?}");
    }
    let (code, err) = check(&dir, &plate_scene(&numbered, ["1", "2", "3", "4", "5"]));
    assert_eq!(code, Some(0), "{err}");
    // A number the file does not have: the message lists the groups by name and number.
    let (code, err) = check(&dir, &plate_scene(&numbered, ["9", "2", "3", "4", "5"]));
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("no physical surface named or numbered `9`") && err.contains(": 1, 2)"),
        "{err}"
    );
    let (code, err) = check(&dir, &plate_scene(&named, ["1", "2", "17", "4", "5"]));
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("boundary[0].region.group") && err.contains("\"clamp\" (3)"),
        "{err}"
    );
    // A surface's number where a curve is wanted, and a group that is neither text nor number.
    let (code, err) = check(&dir, &plate_scene(&numbered, ["3", "2", "3", "4", "5"]));
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("is a physical curve, not a surface"), "{err}");
    let (code, err) = check(&dir, &plate_scene(&numbered, ["1.5", "2", "3", "4", "5"]));
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("group name") || err.contains("number"),
        "{err}"
    );
    let _ = read_bytes(&numbered).expect("readable");
    let _ = std::fs::remove_dir_all(&dir);
}
