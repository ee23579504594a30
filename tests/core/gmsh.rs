//! Gmsh meshes (`mesh = { gmsh = "...", group = "..." }`): the shipped MSH 4.1 files read with the
//! counts Gmsh wrote (its own report when it meshed them), ASCII and binary alike; the asset scene
//! that uses them runs. Bad Gmsh input is in `bad_input.rs`, the patch test on a Gmsh mesh in
//! `patch.rs`.

use std::path::{Path, PathBuf};

use ricochet::gmsh::{physical_names, read_bytes, read_surface, version};

use crate::common::*;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A test mesh of `tests/data/gmsh/`.
pub fn test_mesh(name: &str) -> PathBuf {
    root().join("tests/data/gmsh").join(name)
}

fn surface(path: &Path, group: &str) -> ricochet::gmsh::SurfaceMesh {
    let bytes = read_bytes(path).expect("mesh file");
    read_surface(&bytes, group).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn shipped_meshes_have_the_counts_gmsh_wrote_ascii_and_binary_alike() {
    // Gmsh 4.15 reported, meshing assets/gmsh/notched_plate.geo: 5860 4-node quads, 6092 nodes
    // (the two circle centres are geometry points without elements); tests/data/gmsh/square.geo:
    // 64 quads on 81 nodes.
    let plate = root().join("assets/gmsh/notched_plate.msh");
    let binary = root().join("assets/gmsh/notched_plate_binary.msh");
    for path in [&plate, &binary] {
        let bytes = read_bytes(path).expect("mesh file");
        assert_eq!(version(&bytes).expect("version"), "4.1");
        let names = physical_names(&bytes).expect("names");
        let mut listed: Vec<(i32, &str)> = names.iter().map(|n| (n.dim, n.name.as_str())).collect();
        listed.sort();
        assert_eq!(
            listed,
            [
                (1, "clamp"),
                (1, "notch"),
                (1, "plate_top"),
                (1, "striker_face"),
                (2, "plate"),
                (2, "striker")
            ]
        );
        let p = surface(path, "plate");
        let s = surface(path, "striker");
        assert_eq!(
            (p.quads.len(), p.nodes.len()),
            (5424, 5617),
            "{}",
            path.display()
        );
        assert_eq!(
            (s.quads.len(), s.nodes.len()),
            (436, 473),
            "{}",
            path.display()
        );
        assert_eq!(p.quads.len() + s.quads.len(), 5860);
        // Node tags are Gmsh's: 6092 in the file, of which the two bodies use all but the two
        // circle centres.
        let mut tags: Vec<u64> = p.node_tags.iter().chain(&s.node_tags).copied().collect();
        tags.sort_unstable();
        tags.dedup();
        assert_eq!(tags.len(), 6090);
        assert!(*tags.last().expect("tags") <= 6092);
    }
    // The binary file holds the same mesh: the same tags and quads, and the coordinates to the
    // 16 significant digits that Gmsh prints in ASCII (1e-15 of the extent).
    let same = |a: &ricochet::gmsh::SurfaceMesh, b: &ricochet::gmsh::SurfaceMesh, what: &str| {
        assert!(a.quads == b.quads, "{what}: the quads differ");
        assert!(a.node_tags == b.node_tags, "{what}: the node tags differ");
        assert!(
            a.element_tags == b.element_tags,
            "{what}: the element tags differ"
        );
        let d = a
            .nodes
            .iter()
            .zip(&b.nodes)
            .map(|(p, q)| (p[0] - q[0]).abs().max((p[1] - q[1]).abs()))
            .fold(0.0f64, f64::max);
        let extent = a
            .nodes
            .iter()
            .map(|p| p[0].abs().max(p[1].abs()))
            .fold(0.0f64, f64::max);
        assert!(
            d <= 1e-15 * extent,
            "{what}: coordinates differ by {d:e} m (extent {extent} m)"
        );
    };
    same(
        &surface(&plate, "plate"),
        &surface(&binary, "plate"),
        "plate",
    );
    let sq = surface(&test_mesh("square.msh"), "square");
    assert_eq!((sq.quads.len(), sq.nodes.len()), (64, 81));
    same(
        &sq,
        &surface(&test_mesh("square_binary.msh"), "square"),
        "square",
    );
    // Every quad counter-clockwise with positive area, and the areas fill the square.
    let area: f64 = sq
        .quads
        .iter()
        .map(|q| {
            let c = q.map(|n| sq.nodes[n as usize]);
            let a = 0.5
                * ((c[2][0] - c[0][0]) * (c[3][1] - c[1][1])
                    - (c[3][0] - c[1][0]) * (c[2][1] - c[0][1]));
            assert!(a > 0.0, "quad {q:?} has area {a}");
            a
        })
        .sum();
    assert!((area - 1.0).abs() < 1e-12, "areas sum to {area}");
}

#[test]
fn a_quad_dominant_mesh_reads_its_quads_and_triangles_ascii_and_binary_alike() {
    // Gmsh 4.15, meshing tests/data/gmsh/mixed.geo: surface 1 (recombined) 20 quads and 2
    // triangles, surface 2 33 triangles, 51 nodes, all in physical surface `square`.
    let ascii = surface(&test_mesh("mixed.msh"), "square");
    let binary = surface(&test_mesh("mixed_binary.msh"), "square");
    for m in [&ascii, &binary] {
        assert_eq!(
            (m.quads.len() - m.triangles(), m.triangles(), m.nodes.len()),
            (20, 35, 51)
        );
    }
    assert!(ascii.quads == binary.quads && ascii.element_tags == binary.element_tags);
    assert!(ascii.node_tags == binary.node_tags);
    // Triangles are collapsed quads [a, b, c, c] with three distinct nodes; every element is
    // counter-clockwise with positive area and together they fill the square.
    let mut area = 0.0;
    for q in &ascii.quads {
        let tri = q[2] == q[3];
        if tri {
            assert!(q[0] != q[1] && q[1] != q[2] && q[0] != q[2], "{q:?}");
        }
        let c = q.map(|n| ascii.nodes[n as usize]);
        let a = 0.5
            * ((c[2][0] - c[0][0]) * (c[3][1] - c[1][1])
                - (c[3][0] - c[1][0]) * (c[2][1] - c[0][1]));
        assert!(a > 0.0, "{q:?} has area {a}");
        area += a;
    }
    assert!((area - 1.0).abs() < 1e-12, "areas sum to {area}");
    // Written clockwise, its triangles are turned as its quads are.
    let text = std::fs::read_to_string(test_mesh("mixed.msh")).expect("mixed.msh");
    let flipped = edit_elements(&text, 2, |n| {
        n.iter().rev().map(|s| s.to_string()).collect()
    });
    let flipped = edit_elements(&flipped, 3, |n| {
        n.iter().rev().map(|s| s.to_string()).collect()
    });
    let m = read_surface(flipped.as_bytes(), "square").expect("flipped mesh");
    assert_eq!(m.reoriented, 55);
    assert_eq!(m.triangles(), 35);
}

#[test]
fn clockwise_quads_are_turned_and_counted() {
    // The same square with every quad written clockwise (node order reversed in the file).
    let text = std::fs::read_to_string(test_mesh("square.msh")).expect("square.msh");
    let flipped = reverse_quads(&text);
    let m = read_surface(flipped.as_bytes(), "square").expect("flipped square");
    let original = surface(&test_mesh("square.msh"), "square");
    assert_eq!(m.reoriented, 64);
    assert_eq!(original.reoriented, 0);
    assert_eq!(m.nodes, original.nodes);
    // Counter-clockwise again: the same cycle of nodes, possibly from another corner.
    for (q, o) in m.quads.iter().zip(&original.quads) {
        let k = o.iter().position(|n| *n == q[0]).expect("same nodes");
        assert_eq!(*q, [o[k], o[(k + 1) % 4], o[(k + 2) % 4], o[(k + 3) % 4]]);
    }
}

/// `text` (an ASCII MSH 4.1 file) with the node order of every 4-node quad reversed.
pub fn reverse_quads(text: &str) -> String {
    edit_quads(text, |n| {
        [n[0], n[3], n[2], n[1]].map(String::from).to_vec()
    })
}

/// `text` with each quad's node tags (in the Elements section's 4-node-quad blocks) replaced by
/// `f` of them.
pub fn edit_quads(text: &str, f: impl FnMut(&[&str]) -> Vec<String>) -> String {
    edit_elements(text, 3, f)
}

/// `text` with the node tags of each element of Gmsh type `kind` (3: 4-node quad, 2: 3-node
/// triangle) replaced by `f` of them.
pub fn edit_elements(text: &str, kind: u32, mut f: impl FnMut(&[&str]) -> Vec<String>) -> String {
    let nodes = match kind {
        2 => 3,
        3 => 4,
        _ => panic!("element type {kind}"),
    };
    let mut out = String::new();
    let mut in_elements = false;
    let mut left_in_block = 0usize;
    let mut kind_block = false;
    let mut header_seen = false;
    for line in text.lines() {
        let mut l = line.to_string();
        if line.starts_with("$Elements") {
            in_elements = true;
            header_seen = false;
        } else if line.starts_with("$EndElements") {
            in_elements = false;
        } else if in_elements {
            let t: Vec<&str> = line.split_whitespace().collect();
            if !header_seen {
                header_seen = true;
            } else if left_in_block == 0 {
                // Block header: entity dim, entity tag, element type, count.
                kind_block = t[2] == kind.to_string();
                left_in_block = t[3].parse().expect("count");
            } else {
                if kind_block {
                    let nodes: Vec<String> = f(&t[1..1 + nodes]);
                    l = format!("{} {} ", t[0], nodes.join(" "));
                }
                left_in_block -= 1;
            }
        }
        out.push_str(&l);
        out.push('\n');
    }
    out
}

#[test]
fn the_notched_plate_asset_runs_on_the_cpu_reference() {
    let dir = tmp_dir("gmsh-notched-plate");
    let o = run_cpu(&root().join("assets/notched_plate.toml"), &dir, &[]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary = std::fs::read_to_string(dir.join("summary.json")).expect("summary");
    assert!(summary.contains("\"completed\""), "{summary}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The square of `tests/data/gmsh/square.msh` with `tables` appended.
fn square_scene(tables: &str) -> String {
    format!(
        "[run]\nend_time = 1.0e-5\n[[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\n\
         density = 7850.0\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.3\n\
         [[body]]\nname = \"square\"\nmaterial = \"steel\"\n\
         mesh = {{ gmsh = {:?}, group = \"square\" }}\n{tables}",
        test_mesh("square.msh").to_string_lossy()
    )
}

fn square_model(tables: &str) -> ricochet::model::Model {
    let scene = ricochet::scene::Scene::parse(&square_scene(tables), Path::new("square.toml"))
        .unwrap_or_else(|e| panic!("{e}"));
    ricochet::run::model(&scene).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn regions_by_group_select_what_the_boxes_around_the_curves_select() {
    // Velocity boundaries: the physical curves "bottom" and "left" and the point "corner"
    // against boxes around the same edges.
    let by_name = square_model(
        "[[boundary]]\nbody = \"square\"\nregion = { group = \"bottom\" }\nvelocity = { y = 0.0 }\n\
         [[boundary]]\nbody = \"square\"\nregion = { group = \"left\" }\nvelocity = { x = 1.0 }\n\
         [[boundary]]\nbody = \"square\"\nregion = { group = \"corner\" }\nvelocity = { x = 0.0 }\n",
    );
    let by_box = square_model(
        "[[boundary]]\nbody = \"square\"\nregion = { min = [-0.01, -0.01], max = [1.01, 0.01] }\nvelocity = { y = 0.0 }\n\
         [[boundary]]\nbody = \"square\"\nregion = { min = [-0.01, -0.01], max = [0.01, 1.01] }\nvelocity = { x = 1.0 }\n\
         [[boundary]]\nbody = \"square\"\nregion = { min = [-0.01, -0.01], max = [0.01, 0.01] }\nvelocity = { x = 0.0 }\n",
    );
    let key = |m: &ricochet::model::Model| {
        m.constraints
            .iter()
            .map(|c| (c.node, c.vx, c.vy))
            .collect::<Vec<_>>()
    };
    assert_eq!(key(&by_name), key(&by_box));
    // 9 nodes on each edge of this mesh, the corner shared.
    assert_eq!(by_name.constraints.len(), 17);
    // Pressure on the curve "top" against a box around the top edge: the same nodal loads.
    let p_name = square_model(
        "[[pressure]]\nbody = \"square\"\nregion = { group = \"top\" }\nvalue = 1.0e6\n",
    );
    let p_box = square_model(
        "[[pressure]]\nbody = \"square\"\nregion = { min = [-0.01, 0.99], max = [1.01, 1.01] }\nvalue = 1.0e6\n",
    );
    assert_eq!(p_name.pressures[0].edges, 8);
    assert_eq!(p_name.pressures[0].nodes, p_box.pressures[0].nodes);
    // The loads add up to p times the edge length (1 m) times the thickness (1 m), downward.
    let total: f64 = p_name.pressures[0].nodes.iter().map(|(_, f)| f[1]).sum();
    assert!(
        (total + 1.0).abs() < 1e-12,
        "total load per unit pressure {total}"
    );
}

/// The notched plate with `contact` as its `[[contact]]` table body and an end time of 25 us.
fn notched_plate_with(contact: &str) -> (ricochet::scene::Scene, ricochet::model::Model) {
    let path = root().join("assets/notched_plate.toml");
    let text = std::fs::read_to_string(&path)
        .expect("notched_plate.toml")
        .replace("end_time = 4.0e-5", "end_time = 2.5e-5")
        .replace(
            "bodies = [\"striker\", \"plate\"]\nmethod = \"lagrange\"",
            &format!("bodies = [\"striker\", \"plate\"]\nmethod = \"lagrange\"\n{contact}"),
        );
    let scene = ricochet::scene::Scene::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    let model = ricochet::run::model(&scene).unwrap_or_else(|e| panic!("{e}"));
    (scene, model)
}

#[test]
fn a_contact_limited_to_named_faces_takes_only_them_and_gives_the_same_impact() {
    let (whole_scene, whole) = notched_plate_with("");
    let (faces_scene, faces) = notched_plate_with("surfaces = [\"striker_face\", \"plate_top\"]");
    let slots = |m: &ricochet::model::Model| {
        ricochet::contact::ContactSet::new(m)
            .expect("contact")
            .slot_count()
    };
    let (n_whole, n_faces) = (slots(&whole), slots(&faces));
    // The whole boundaries: the striker's rim and the plate's outline with the notch; the faces:
    // the striker's lower half and the plate's top edge.
    // (186 against 456 slots: the plate's top edge is finely meshed under the striker.)
    assert!(
        n_faces * 2 < n_whole,
        "{n_faces} slots with the faces against {n_whole} with the whole boundaries"
    );
    let end_velocity = |scene: &ricochet::scene::Scene, model: ricochet::model::Model| {
        let plan = ricochet::plan::Plan::new(scene, &model);
        let mut st = Stepper::new(
            model,
            plan,
            every_step(scene.run.end_time, None, 0.9, 1.0e-6),
        );
        while st.advance() {}
        assert!(st.failure.is_none(), "{:?}", st.failure);
        let last = st.samples.last().expect("samples").clone();
        (last.body_velocity[1], last.contacts[0].force)
    };
    let (v_whole, f_whole) = end_velocity(&whole_scene, whole);
    let (v_faces, f_faces) = end_velocity(&faces_scene, faces);
    eprintln!(
        "notched plate: {n_faces} contact slots on the named faces, {n_whole} on the whole \
         boundaries; striker velocity {v_faces:?} against {v_whole:?}, force {f_faces:?} against {f_whole:?}"
    );
    // The striker is rebounding from the plate at 25 us: the same impact either way (the
    // Gauss-Seidel order differs, so to the solver's tolerance, not bit for bit).
    assert!(v_whole[1] > 0.0, "the striker rebounds: {v_whole:?}");
    for k in 0..2 {
        assert!(
            (v_faces[k] - v_whole[k]).abs() < 1e-8 * 50.0,
            "striker velocity {v_faces:?} against {v_whole:?}"
        );
    }
}
