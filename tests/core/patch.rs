//! Constant-strain patch tests: a linear displacement field u = A X must give the exact stress
//! D eps in every element, zero nodal force at interior nodes, and boundary nodal forces equal to
//! the consistent traction t sigma n (half of each adjacent boundary edge), to round-off. Done for
//! a single distorted quad, a 2x2 patch with its interior node moved, the 5-element
//! MacNeal-Harder patch, and for both plane strain and plane stress; plus the neo-Hookean
//! analogue with a large homogeneous deformation.

use ricochet::element::{evaluate, Dissipation};
use ricochet::scene::{Formulation, HourglassForm, MaterialModel};

use crate::common::*;
use crate::scene_text::steel_of;

#[path = "../shared/traction.rs"]
mod traction;
use traction::{interior, traction_forces};

/// Displacement gradient of the imposed field (its skew part is an infinitesimal rotation, which
/// small-strain elasticity ignores): eps_xx = 1e-3, eps_yy = -5e-4, eps_xy = 1e-4.
const A: [[f64; 2]; 2] = [[1.0e-3, 4.0e-4], [-2.0e-4, -5.0e-4]];
/// A rigid translation added to the field; it must change nothing.
const SHIFT: [f64; 2] = [3.0e-4, -7.0e-4];

/// Exact small-strain Hooke stress (xx, yy, xy, zz) from E and nu, written out independently of
/// the library's Lame constants.
fn hooke(e: f64, nu: f64, form: Formulation, a: [[f64; 2]; 2]) -> [f64; 4] {
    let (exx, eyy, exy) = (a[0][0], a[1][1], 0.5 * (a[0][1] + a[1][0]));
    match form {
        Formulation::PlaneStrain => {
            let k = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
            [
                k * ((1.0 - nu) * exx + nu * eyy),
                k * (nu * exx + (1.0 - nu) * eyy),
                e / (1.0 + nu) * exy,
                k * nu * (exx + eyy),
            ]
        }
        Formulation::PlaneStress => {
            let k = e / (1.0 - nu * nu);
            [
                k * (exx + nu * eyy),
                k * (nu * exx + eyy),
                e / (1.0 + nu) * exy,
                0.0,
            ]
        }
        Formulation::Axisymmetric => unreachable!("the planar patch tests only"),
    }
}

/// Exact compressible neo-Hookean Cauchy stress (xx, yy, xy, zz) of the in-plane deformation
/// gradient `f` (W = mu/2 (I1 - 3 - 2 ln J) + lambda/2 ln^2 J), with F33 = 1 (plane strain) or
/// F33 from sigma_zz = 0 found by bisection (plane stress).
fn neo_hookean(e: f64, nu: f64, form: Formulation, f: [[f64; 2]; 2]) -> [f64; 4] {
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e / (2.0 * (1.0 + nu));
    let j2 = f[0][0] * f[1][1] - f[0][1] * f[1][0];
    let f33 = match form {
        Formulation::PlaneStrain => 1.0,
        Formulation::PlaneStress => plane_stress_f33(e, nu, j2),
        Formulation::Axisymmetric => unreachable!("the planar patch tests only"),
    };
    let j = j2 * f33;
    // Left Cauchy-Green tensor b = F F^T.
    let bxx = f[0][0] * f[0][0] + f[0][1] * f[0][1];
    let byy = f[1][0] * f[1][0] + f[1][1] * f[1][1];
    let bxy = f[0][0] * f[1][0] + f[0][1] * f[1][1];
    let p = lambda * j.ln() / j;
    let szz = match form {
        Formulation::PlaneStrain => mu / j * (f33 * f33 - 1.0) + p,
        Formulation::PlaneStress => 0.0,
        Formulation::Axisymmetric => unreachable!("the planar patch tests only"),
    };
    [
        mu / j * (bxx - 1.0) + p,
        mu / j * (byy - 1.0) + p,
        mu / j * bxy,
        szz,
    ]
}

/// Out-of-plane stretch of plane-stress neo-Hookean with in-plane Jacobian `j2`: the root of
/// mu (z^2 - 1) + lambda ln(j2 z) = 0 (sigma_zz = 0), by bisection (the left side increases in z).
fn plane_stress_f33(e: f64, nu: f64, j2: f64) -> f64 {
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e / (2.0 * (1.0 + nu));
    let g = |z: f64| mu * (z * z - 1.0) + lambda * (j2 * z).ln();
    let (mut lo, mut hi) = (1e-3, 1e3);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Scene text of one explicit-mesh body.
fn explicit_scene(
    model: &str,
    form: &str,
    hourglass: &str,
    nodes: &[[f64; 2]],
    quads: &[[u32; 4]],
) -> String {
    let nodes: Vec<String> = nodes
        .iter()
        .map(|p| format!("[{:?}, {:?}]", p[0], p[1]))
        .collect();
    let quads: Vec<String> = quads.iter().map(|q| format!("{q:?}")).collect();
    format!(
        r#"
[run]
end_time = 1.0e-3
bulk_viscosity = {{ linear = 0.0, quadratic = 0.0 }}

{steel}

[[body]]
name = "patch"
material = "steel"
formulation = "{form}"
thickness = 0.02
mesh = {{ nodes = [{}], quads = [{}] }}
hourglass = {{ form = "{hourglass}", coefficient = 0.1 }}
"#,
        nodes.join(", "),
        quads.join(", "),
        steel = steel_of(model),
    )
}

/// Imposes u = F X - X + SHIFT (F = I + grad) on the patch and checks stress and forces.
/// Returns (max relative stress error, max relative force error, max interior force / scale).
fn check_patch(
    model_name: &str,
    form: Formulation,
    hourglass: &str,
    nodes: &[[f64; 2]],
    quads: &[[u32; 4]],
    grad: [[f64; 2]; 2],
) -> (f64, f64, f64) {
    let form_name = match form {
        Formulation::PlaneStrain => "plane_strain",
        Formulation::PlaneStress => "plane_stress",
        Formulation::Axisymmetric => "axisymmetric",
    };
    let (_, model, _) = build(&explicit_scene(
        model_name, form_name, hourglass, nodes, quads,
    ));
    let t = 0.02;
    let u: Vec<[f64; 2]> = model
        .position
        .iter()
        .map(|x| {
            let d = mat_vec(grad, *x);
            [d[0] + SHIFT[0], d[1] + SHIFT[1]]
        })
        .collect();
    let f_def = [
        [1.0 + grad[0][0], grad[0][1]],
        [grad[1][0], 1.0 + grad[1][1]],
    ];
    let exact = match model_name {
        "linear_elastic" => hooke(E_STEEL, 0.3, form, grad),
        _ => neo_hookean(E_STEEL, 0.3, form, f_def),
    };
    let s_scale = exact.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut stress_err = 0.0f64;
    for e in 0..model.element_count() {
        let q = model.quads[e];
        let out = evaluate(
            model.params(e),
            &model.corners[e],
            &q.map(|i| u[i as usize]),
            &[[0.0; 2]; 4],
            &Dissipation::default(),
            0.0,
        );
        for (got, want) in out.stress.iter().zip(&exact) {
            stress_err = stress_err.max(rel(*got, *want, s_scale));
        }
        // The element sees the homogeneous deformation gradient exactly.
        for (k, g) in [f_def[0][0], f_def[0][1], f_def[1][0], f_def[1][1]]
            .iter()
            .enumerate()
        {
            assert!(
                (out.def_grad[k] - g).abs() < 1e-13,
                "element {e}: F[{k}] = {} instead of {g}",
                out.def_grad[k]
            );
        }
        // No hourglass energy for a linear field.
        assert!(out.hourglass_stored.abs() <= 1e-24 * s_scale);
    }
    let f = assemble(&model, &u, &vec![[0.0; 2]; model.node_count()]);
    // Expected forces: traction of the Cauchy stress on the current boundary equals the
    // traction of the first Piola-Kirchhoff stress on the reference boundary; for the
    // small-strain model these coincide with the reference traction of sigma.
    let expected = match model_name {
        // Small strain: P = sigma on the reference configuration.
        "linear_elastic" => {
            traction_forces(&model, [[exact[0], exact[2]], [exact[2], exact[1]]], t)
        }
        _ => {
            // Finite strain: P = J sigma F^-T (in plane; J includes F33), on reference edges.
            let j2 = f_def[0][0] * f_def[1][1] - f_def[0][1] * f_def[1][0];
            let f33 = match form {
                Formulation::PlaneStrain => 1.0,
                Formulation::PlaneStress => plane_stress_f33(E_STEEL, 0.3, j2),
                Formulation::Axisymmetric => unreachable!("the planar patch tests only"),
            };
            let fit = [
                [f_def[1][1] / j2, -f_def[1][0] / j2],
                [-f_def[0][1] / j2, f_def[0][0] / j2],
            ];
            let s = [[exact[0], exact[2]], [exact[2], exact[1]]];
            let mut p = [[0.0; 2]; 2];
            for i in 0..2 {
                for k in 0..2 {
                    p[i][k] = j2 * f33 * (s[i][0] * fit[0][k] + s[i][1] * fit[1][k]);
                }
            }
            traction_forces(&model, p, t)
        }
    };
    // Force scale: stress times thickness times the patch size.
    let size = model
        .position
        .iter()
        .fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
    let f_scale = s_scale * t * size;
    let mut force_err = 0.0f64;
    for i in 0..model.node_count() {
        for k in 0..2 {
            force_err = force_err.max(rel(f[i][k], expected[i][k], f_scale));
        }
    }
    let inner = interior(&model);
    let mut interior_force = 0.0f64;
    for &i in &inner {
        interior_force = interior_force.max(f[i][0].hypot(f[i][1]) / f_scale);
    }
    (stress_err, force_err, interior_force)
}

const SINGLE_NODES: [[f64; 2]; 4] = [[0.0, 0.0], [2.0, 0.1], [2.3, 1.7], [-0.2, 1.1]];
const SINGLE_QUADS: [[u32; 4]; 1] = [[0, 1, 2, 3]];

/// 2x2 patch on [0, 1]^2 with the interior node moved from (0.5, 0.5) to (0.62, 0.41).
const PATCH2_NODES: [[f64; 2]; 9] = [
    [0.0, 0.0],
    [0.5, 0.0],
    [1.0, 0.0],
    [0.0, 0.5],
    [0.62, 0.41],
    [1.0, 0.5],
    [0.0, 1.0],
    [0.5, 1.0],
    [1.0, 1.0],
];
const PATCH2_QUADS: [[u32; 4]; 4] = [[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]];

/// MacNeal-Harder patch: the 0.24 x 0.12 rectangle with four interior nodes, five distorted quads.
const MH_NODES: [[f64; 2]; 8] = [
    [0.0, 0.0],
    [0.24, 0.0],
    [0.24, 0.12],
    [0.0, 0.12],
    [0.04, 0.02],
    [0.18, 0.03],
    [0.16, 0.08],
    [0.08, 0.08],
];
const MH_QUADS: [[u32; 4]; 5] = [
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
    [4, 5, 6, 7],
];

/// A named patch: nodes and counter-clockwise quads.
type Patch = (&'static str, &'static [[f64; 2]], &'static [[u32; 4]]);

fn all_patches() -> Vec<Patch> {
    vec![
        ("single distorted quad", &SINGLE_NODES, &SINGLE_QUADS),
        (
            "2x2 patch, interior node moved",
            &PATCH2_NODES,
            &PATCH2_QUADS,
        ),
        ("MacNeal-Harder 5-element patch", &MH_NODES, &MH_QUADS),
    ]
}

#[test]
fn linear_elastic_patch_tests_give_exact_stress_and_zero_interior_forces() {
    // "Exact to round-off": the strain is formed as F - 1 with |eps| ~ 1e-3, so it carries an
    // absolute error of a few machine epsilons, i.e. a relative error of about eps_mach / 1e-3.
    // Tolerance 100 eps_mach / 1e-3 = 2.2e-11. Measured worst: stress 2.7e-13, nodal forces
    // 8.9e-14, interior forces 8.2e-14 of sigma t L (printed below).
    let tol = 100.0 * f64::EPSILON / 1e-3;
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    for form in [Formulation::PlaneStrain, Formulation::PlaneStress] {
        for hourglass in ["none", "stiffness", "viscous"] {
            for (name, nodes, quads) in all_patches() {
                let (s, f, i) = check_patch("linear_elastic", form, hourglass, nodes, quads, A);
                worst = (worst.0.max(s), worst.1.max(f), worst.2.max(i));
                assert!(
                    s < tol,
                    "{name}, {form:?}, {hourglass}: stress error {s:e} relative to |sigma|"
                );
                assert!(
                    f < tol,
                    "{name}, {form:?}, {hourglass}: nodal forces differ from the consistent traction by {f:e}"
                );
                assert!(
                    i < tol,
                    "{name}, {form:?}, {hourglass}: interior nodal force {i:e} of sigma t L"
                );
            }
        }
    }
    println!(
        "linear patch tests: worst stress error {:.2e}, force error {:.2e}, interior force {:.2e} (tolerance {tol:.1e})",
        worst.0, worst.1, worst.2
    );
}

/// The patch test on unstructured meshes that Gmsh made, read from MSH 4.1: tests/data/gmsh/
/// square.msh (64 quads) and mixed.msh (20 quads and 35 triangles, a quad-dominant mesh): exact
/// stress in every element, zero interior forces, consistent boundary forces, to the same
/// round-off tolerance as the hand-made patches (2.2e-11, inside the 1e-10 asked of the mixed
/// mesh), for the small-strain and the neo-Hookean material.
#[test]
fn gmsh_quad_and_mixed_meshes_pass_the_patch_test() {
    let tol = 100.0 * f64::EPSILON / 1e-3;
    for file in ["square.msh", "mixed.msh"] {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/gmsh")
            .join(file);
        let bytes = ricochet::gmsh::read_bytes(&path).expect("mesh file");
        let mesh = ricochet::gmsh::read_surface(&bytes, "square").expect("group square");
        let tris = mesh.triangles();
        assert_eq!(tris > 0, file == "mixed.msh", "{file}: {tris} triangles");
        let mut worst = (0.0f64, 0.0f64, 0.0f64);
        for form in [Formulation::PlaneStrain, Formulation::PlaneStress] {
            for hourglass in ["none", "stiffness", "viscous"] {
                let (s, f, i) = check_patch(
                    "linear_elastic",
                    form,
                    hourglass,
                    &mesh.nodes,
                    &mesh.quads,
                    A,
                );
                worst = (worst.0.max(s), worst.1.max(f), worst.2.max(i));
                assert!(s < tol, "{file}, {form:?}, {hourglass}: stress error {s:e}");
                assert!(
                    f < tol,
                    "{file}, {form:?}, {hourglass}: boundary force error {f:e}"
                );
                assert!(
                    i < tol,
                    "{file}, {form:?}, {hourglass}: interior force {i:e}"
                );
            }
            // A large homogeneous deformation on the same mesh (round-off about 1e-15).
            let grad = [[0.3, 0.2], [-0.1, -0.2]];
            let (s, f, i) = check_patch(
                "neo_hookean",
                form,
                "stiffness",
                &mesh.nodes,
                &mesh.quads,
                grad,
            );
            assert!(
                s < 1e-12 && f < 1e-12 && i < 1e-12,
                "{file}, {form:?}, neo-Hookean: {s:e} {f:e} {i:e}"
            );
        }
        println!(
            "Gmsh {file} patch test ({} quads, {tris} triangles): worst stress error {:.2e}, force error {:.2e}, interior force {:.2e} (tolerance {tol:.1e})",
            mesh.quads.len() - tris,
            worst.0,
            worst.1,
            worst.2
        );
    }
}

#[test]
fn neo_hookean_patch_tests_reproduce_a_large_homogeneous_deformation() {
    // A large homogeneous deformation (30 % stretch, 20 % compression, shear): every element
    // sees the same F and gives the closed-form neo-Hookean stress; interior forces vanish.
    // Strains are O(0.1), so round-off is about 1e-15 relative; tolerance 1e-12.
    let grad = [[0.3, 0.2], [-0.1, -0.2]];
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    for form in [Formulation::PlaneStrain, Formulation::PlaneStress] {
        for (name, nodes, quads) in all_patches() {
            let (s, f, i) = check_patch("neo_hookean", form, "stiffness", nodes, quads, grad);
            worst = (worst.0.max(s), worst.1.max(f), worst.2.max(i));
            assert!(s < 1e-12, "{name}, {form:?}: stress error {s:e}");
            assert!(f < 1e-12, "{name}, {form:?}: force error {f:e}");
            assert!(i < 1e-12, "{name}, {form:?}: interior force {i:e}");
        }
    }
    println!(
        "neo-Hookean patch tests: worst stress error {:.2e}, force error {:.2e}, interior force {:.2e}",
        worst.0, worst.1, worst.2
    );
}

#[test]
fn patch_test_through_the_cpu_solver_leaves_interior_nodes_unforced() {
    // The same through the solver's own assembly: a linear initial velocity field v = G X on the
    // MacNeal-Harder patch; after one step u_1 = dt G X is linear, so the interior nodes must not
    // accelerate while the boundary nodes do (the free boundary is unloaded).
    let mut text = explicit_scene(
        "linear_elastic",
        "plane_strain",
        "viscous",
        &MH_NODES,
        &MH_QUADS,
    );
    text.push_str("velocity_gradient = [[100.0, 40.0], [-20.0, -50.0]]\n");
    let (scene, model, plan) = build(&text);
    let inner = interior(&model);
    assert_eq!(inner, vec![4, 5, 6, 7]);
    let sched = every_step(scene.run.end_time, None, 0.9, 1e-7); // dt ~ 3e-6 s
    let mut s = Stepper::new(model, plan, sched);
    s.advance(); // step 0: u_0 = 0, no force; v^{1/2} = v_0
    let v_half = s.solver.velocity().to_vec();
    s.advance(); // step 1: forces from u_1 = dt v^{1/2}
    let v = s.solver.velocity();
    let dv: Vec<f64> = (0..v.len())
        .map(|i| (v[i][0] - v_half[i][0]).hypot(v[i][1] - v_half[i][1]))
        .collect();
    let boundary_dv = dv.iter().take(4).fold(0.0f64, |m, x| m.max(*x));
    let interior_dv = inner.iter().fold(0.0f64, |m, &i| m.max(dv[i]));
    assert!(boundary_dv > 0.0, "the boundary nodes must be loaded");
    assert!(
        interior_dv < 1e-12 * boundary_dv,
        "interior velocity change {interior_dv:e} vs boundary {boundary_dv:e}"
    );
}

#[test]
fn material_model_closed_forms_agree_with_each_other_for_small_strain() {
    // Guards the two closed forms used above: neo-Hookean tends to Hooke for small strain.
    let g = [[1e-7, 3e-8], [-1e-8, -4e-8]];
    for form in [Formulation::PlaneStrain, Formulation::PlaneStress] {
        let f = [[1.0 + g[0][0], g[0][1]], [g[1][0], 1.0 + g[1][1]]];
        let a = hooke(E_STEEL, 0.3, form, g);
        let b = neo_hookean(E_STEEL, 0.3, form, f);
        let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for k in 0..4 {
            assert!(
                rel(a[k], b[k], scale) < 1e-5,
                "{form:?} {k}: {a:?} vs {b:?}"
            );
        }
    }
    // And the library's parameters for a fixed element, as a direct cross-check.
    let p = steel_params(
        MaterialModel::LinearElastic,
        0.3,
        Formulation::PlaneStress,
        HourglassForm::None,
        0.0,
        1.0,
    );
    assert!(rel(p.lambda_plane + 2.0 * p.mu, E_STEEL / (1.0 - 0.09), E_STEEL) < 1e-14);
}
