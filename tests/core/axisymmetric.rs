//! The axisymmetric formulation (x = r, y the axis; per radian): the constant-strain patch test
//! with the hoop strain, the lumped masses per radian, the nodes on the axis held at u_r = 0
//! without a boundary table, and the refused inputs. The thick cylinder (Lame) and the Taylor bar
//! are verification cases (`assets/verification/`).

use ricochet::model::surface::Surface;
use ricochet::output::fields::element_fields;

use crate::common::*;
use crate::contact::scenes;

const RHO: f64 = 7850.0;

fn scene(origin_x: f64, extra: &str) -> String {
    format!(
        r#"
[run]
end_time = 1.0e-6

[[material]]
name = "steel"
model = "linear_elastic"
density = {RHO}
youngs_modulus = 2.1e11
poisson_ratio = 0.3

[[body]]
name = "tube"
material = "steel"
formulation = "axisymmetric"
mesh = {{ rectangle = {{ origin = [{origin_x:e}, 0.0], size = [0.05, 0.02], cells = [5, 3] }} }}
{extra}
"#
    )
}

/// The steel's stress (rr, zz, rz, hoop) under the uniform expansion u_r = er r, u_z = ez z
/// (hoop strain er), written out from E and nu.
fn expansion_stress(er: f64, ez: f64) -> [f64; 4] {
    let (e, nu) = (2.1e11, 0.3);
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e / (2.0 * (1.0 + nu));
    let tr = 2.0 * er + ez;
    [
        lambda * tr + 2.0 * mu * er,
        lambda * tr + 2.0 * mu * ez,
        0.0,
        lambda * tr + 2.0 * mu * er,
    ]
}

#[test]
fn a_uniform_expansion_gives_the_exact_hoop_stress_and_the_masses_are_per_radian() {
    let (_, model, _) = build(&scene(0.05, ""));
    // Mass per radian: rho * integral of r dA = rho (b^2 - a^2) / 2 * h.
    let total: f64 = model.mass.iter().sum();
    let exact = RHO * (0.1f64.powi(2) - 0.05f64.powi(2)) / 2.0 * 0.02;
    assert!(
        (total - exact).abs() < 1e-12 * exact,
        "{total} against {exact}"
    );
    // u_r = er r, u_z = ez z: F = diag(1 + er, 1 + ez), F_33 = 1 + er in every element.
    let (er, ez) = (1.0e-4, -3.0e-4);
    let u: Vec<[f64; 2]> = model
        .position
        .iter()
        .map(|p| [er * p[0], ez * p[1]])
        .collect();
    let want = expansion_stress(er, ez);
    for el in 0..model.element_count() {
        let s = element_fields(&model, &u, el).stress;
        for i in 0..4 {
            assert!(
                (s[i] - want[i]).abs() < 1e-10 * want[0].abs(),
                "element {el}, component {i}: {} against {}",
                s[i],
                want[i]
            );
        }
    }
}

#[test]
fn triangles_of_a_mixed_gmsh_mesh_give_the_exact_hoop_stress_and_masses_per_radian() {
    // tests/data/gmsh/mixed.msh: the unit square, 20 quads and 35 triangles, its left side on
    // the axis. A triangle's hoop strain is taken at its centroid (weights 1/3, not the
    // collapsed quad's 1/4), so the uniform expansion is exact on it too.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gmsh/mixed.msh");
    let text = format!(
        "[run]\nend_time = 1.0e-6\n[[material]]\nname = \"steel\"\nmodel = \"linear_elastic\"\n\
         density = {RHO}\nyoungs_modulus = 2.1e11\npoisson_ratio = 0.3\n[[body]]\nname = \"disk\"\n\
         material = \"steel\"\nformulation = \"axisymmetric\"\n\
         mesh = {{ gmsh = {:?}, group = \"square\" }}\n",
        path.to_string_lossy()
    );
    let (_, model, _) = build(&text);
    let tris = model
        .quads
        .iter()
        .filter(|q| ricochet::geometry::is_triangle(q))
        .count();
    assert_eq!((model.element_count(), tris), (55, 35));
    // rho * integral of r over the unit square = rho / 2.
    let total: f64 = model.mass.iter().sum();
    assert!((total - RHO / 2.0).abs() < 1e-12 * RHO, "{total}");
    let (er, ez) = (1.0e-4, -3.0e-4);
    let u: Vec<[f64; 2]> = model
        .position
        .iter()
        .map(|p| [er * p[0], ez * p[1]])
        .collect();
    let want = expansion_stress(er, ez);
    // The strain energy per radian of the triangles: w times the integral of r over them,
    // A (r_a + r_b + r_c) / 3 each, which their one point gives exactly at the centroid only.
    let w = 0.5 * (want[0] * er + want[1] * ez + want[3] * er);
    let (mut energy, mut exact) = (0.0, 0.0);
    for el in 0..model.element_count() {
        let q = model.quads[el];
        let out = ricochet::element::evaluate_with(
            model.params(el),
            &model.geometry(el),
            &model.corners[el],
            &q.map(|i| u[i as usize]),
            &[[0.0; 2]; 4],
            &ricochet::element::Dissipation::default(),
            0.0,
        );
        if ricochet::geometry::is_triangle(&q) {
            let x = q.map(|i| model.position[i as usize]);
            let area = 0.5
                * ((x[1][0] - x[0][0]) * (x[2][1] - x[0][1])
                    - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]));
            energy += out.strain_energy;
            exact += w * area * (x[0][0] + x[1][0] + x[2][0]) / 3.0;
        }
        let s = element_fields(&model, &u, el).stress;
        for i in 0..4 {
            assert!(
                (s[i] - want[i]).abs() < 1e-10 * want[0].abs(),
                "element {el} ({:?}), component {i}: {} against {}",
                model.quads[el],
                s[i],
                want[i]
            );
        }
    }
    assert!(
        (energy - exact).abs() < 1e-10 * exact,
        "strain energy per radian of the triangles {energy:e} against {exact:e}"
    );
}

#[test]
fn nodes_on_the_axis_are_held_at_zero_radial_velocity() {
    let (_, model, _) = build(&scene(0.0, "initial_velocity = [5.0, -3.0]"));
    let on_axis: Vec<usize> = (0..model.node_count())
        .filter(|&n| model.position[n][0] == 0.0)
        .collect();
    assert_eq!(on_axis.len(), 4);
    for n in on_axis {
        let c = model
            .constraints
            .iter()
            .find(|c| c.node as usize == n)
            .expect("axis node constrained");
        assert_eq!(c.vx, Some(0.0));
        assert_eq!(c.vy, None);
        assert_eq!(model.velocity[n], [0.0, -3.0]);
    }
    // Off the axis, no constraint.
    assert_eq!(model.constraints.len(), 4);
}

#[test]
fn bad_axisymmetric_input_is_refused() {
    let dir = tmp_dir("axi-bad");
    for (case, text, needles) in [
        (
            "negative_x",
            scene(-0.01, ""),
            vec!["body[0].mesh", "x = r >= 0"],
        ),
        (
            "thickness",
            scene(0.05, "thickness = 0.01"),
            vec!["body[0].thickness", "per radian"],
        ),
    ] {
        let file = dir.join(format!("{case}.toml"));
        std::fs::write(&file, text).unwrap();
        let o = run_bin(&["check", file.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{case}: {err}");
        for n in needles {
            assert!(err.contains(n), "{case}: {n:?} not in {err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_history_of_an_axisymmetric_scene_says_it_is_per_radian() {
    let dir = tmp_dir("axi-history");
    let file = dir.join("tube.toml");
    std::fs::write(&file, scene(0.05, "initial_velocity = [0.0, -1.0]")).unwrap();
    let out = dir.join("out");
    let o = run_cpu(&file, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let first = text.lines().next().unwrap();
    assert_eq!(first, ricochet::output::history::PER_RADIAN);
    // The readers skip it: the columns and rows as usual, the kinetic energy per radian.
    let (header, rows) = read_csv(&out.join("history.csv"));
    let ke = rows[0][column(&header, "kinetic_energy")];
    let mass: f64 = RHO * (0.1f64.powi(2) - 0.05f64.powi(2)) / 2.0 * 0.02;
    assert!(
        (ke - 0.5 * mass).abs() < 1e-9 * ke,
        "{ke} against {}",
        0.5 * mass
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn check_prints_the_formulation_and_the_flow_stress() {
    let dir = tmp_dir("axi-check");
    let file = dir.join("tube.toml");
    let text = scene(0.05, "").replace(
        "model = \"linear_elastic\"",
        "model = \"j2_plastic\"\njohnson_cook = { a = 9.0e7, b = 2.92e8, n = 0.31, c = 0.025, reference_strain_rate = 1.0 }",
    );
    std::fs::write(&file, text).unwrap();
    let o = run_bin(&["check", file.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("axisymmetric (x = r;"), "{out}");
    assert!(
        out.contains("J2 plastic, Johnson-Cook: a 9e7 Pa, b 2.92e8 Pa, n 0.31, c 0.025"),
        "{out}"
    );
    assert!(out.contains("-> plasticity ->"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Contact at the axis: the edges on it are no part of a body's surface (nothing reaches them
/// from r < 0), and a node on the axis meets a nose dimpled at the axis at its axis node
/// (`scenes::DIMPLE`: the vertex of the nose's segment and its mirror image) instead of passing
/// into it.
#[test]
fn a_node_on_the_axis_stops_at_a_nose_dimpled_at_the_axis_and_axis_edges_are_no_surface() {
    let (r, model, u) = run_cpu_text(scenes::DIMPLE, "dimple");
    for b in 0..model.bodies.len() {
        let s = Surface::of_body(&model, b);
        assert_eq!(s.segments.len(), 3, "{:?}", s.segments);
        assert!(s
            .segments
            .iter()
            .all(|g| g.nodes.iter().any(|&n| model.position[n as usize][0] > 0.0)));
    }
    let inside = scenes::apex_inside(&model, &u);
    // Without the vertex the apex ended 6.8e-4 m inside the rod.
    assert!(inside < 1e-12, "{inside:e}");
    // It met the axis node and bounced: the tip moves away at the end, and the run balances.
    let last = r.samples.last().expect("rows").0.clone();
    assert!(last.body_velocity[1][1] < 0.0, "{:?}", last.body_velocity);
    assert!(
        r.summary.max_energy_error < 1e-3,
        "{}",
        r.summary.max_energy_error
    );
}
