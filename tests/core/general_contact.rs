//! General contact (`bodies = "all"` or a list: one symmetric pass per `[[contact]]` table) and
//! self-contact: the scene forms, the flat tables, a pile of disks and a ring pressed onto itself.

use ricochet::contact::ContactSet;
use ricochet::scene::Scene;

use crate::common::*;

use crate::stress::penetration::self_penetration;

#[path = "../shared/general_checks.rs"]
mod general_checks;
use general_checks::{asset, check_pile, check_ring, most_active, PILE_H, RING_T};

/// Three small blocks and `extra`.
fn blocks(extra: &str) -> String {
    let mut s = String::from(concat!("\n[run]\nend_time = 1.0e-5\n\n", steel!(), "\n"));
    for (k, name) in ["a", "b", "c"].iter().enumerate() {
        s.push_str(&format!(
            "\n[[body]]\nname = \"{name}\"\nmaterial = \"steel\"\nmesh = {{ rectangle = {{ origin = [{x}, 0.0], size = [0.1, 0.05], cells = [2, 2] }} }}\n",
            x = 0.2 * k as f64
        ));
    }
    s.push_str(extra);
    s
}

fn parse_err(text: &str) -> String {
    match Scene::parse(text, std::path::Path::new("test_scene.toml")) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn contact_bodies_all_a_list_and_self_contact_parse_into_pairs_and_groups() {
    let s = parse(&blocks("[[contact]]\nbodies = [\"b\", \"a\"]\n"));
    let c = &s.contacts[0];
    assert_eq!(
        (c.bodies.clone(), c.group, c.self_contact, c.two_pass),
        (vec![1, 0], false, false, true)
    );
    assert_eq!(c.name, "b-a");
    let s = parse(&blocks(
        "[[contact]]\nbodies = [\"b\", \"a\"]\ntwo_pass = false\n",
    ));
    assert!(!s.contacts[0].two_pass && !s.contacts[0].group);
    let s = parse(&blocks("[[contact]]\nbodies = \"all\"\n"));
    let c = &s.contacts[0];
    assert_eq!(
        (c.bodies.clone(), c.group, c.self_contact, c.name.as_str()),
        (vec![0, 1, 2], true, false, "all")
    );
    let s = parse(&blocks(
        "[[contact]]\nbodies = [\"c\", \"a\", \"b\"]\nmethod = \"penalty\"\n",
    ));
    let c = &s.contacts[0];
    assert_eq!(
        (c.bodies.clone(), c.group, c.name.as_str()),
        (vec![0, 1, 2], true, "c+a+b")
    );
    let s = parse(&blocks(
        "[[contact]]\nbodies = [\"b\"]\nself_contact = true\n",
    ));
    let c = &s.contacts[0];
    assert_eq!(
        (c.bodies.clone(), c.group, c.self_contact, c.name.as_str()),
        (vec![1], true, true, "b-self")
    );
    let s = parse(&blocks(
        "[[contact]]\nbodies = [\"b\", \"a\"]\nself_contact = true\n",
    ));
    let c = &s.contacts[0];
    assert_eq!(
        (c.bodies.clone(), c.group, c.self_contact, c.name.as_str()),
        (vec![0, 1], true, true, "b+a")
    );
    // Default names never clash: a wall over the same bodies as a contact is suffixed.
    let s = parse(&blocks(
        "[[contact]]\nbodies = [\"a\", \"b\"]\n[[rigid_wall]]\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\nbodies = [\"a\", \"b\"]\n[[contact]]\nbodies = \"all\"\n[[rigid_wall]]\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\nbodies = [\"a\", \"b\"]\n",
    ));
    let names: Vec<&str> = s
        .contacts
        .iter()
        .map(|c| c.name.as_str())
        .chain(s.walls.iter().map(|w| w.name.as_str()))
        .collect();
    assert_eq!(names, ["a-b", "all", "a-b_2", "a-b_3"]);
}

#[test]
fn contact_group_errors_name_the_key_and_value() {
    for (extra, needles) in [
        (
            "bodies = [\"a\"]\n",
            &["contact[0].bodies", "[\"a\"]", "self_contact = true"][..],
        ),
        (
            "bodies = [\"a\", \"b\", \"a\"]\n",
            &["contact[0].bodies", "\"a\" is named twice"][..],
        ),
        (
            "bodies = []\n",
            &["contact[0].bodies", "[]", "at least one body"][..],
        ),
        (
            "bodies = [\"a\", \"z\"]\nself_contact = true\n",
            &["contact[0].bodies", "\"z\"", "no body of that name"][..],
        ),
        (
            "bodies = \"every\"\n",
            &["contact[0].bodies", "\"every\"", "\"all\""][..],
        ),
        (
            "bodies = \"all\"\ntwo_pass = false\n",
            &["contact[0].two_pass", "false", "group"][..],
        ),
        (
            "bodies = [\"a\", \"b\"]\nself_contact = true\ntwo_pass = false\n",
            &["contact[0].two_pass", "false"][..],
        ),
        (
            "bodies = [\"a\", \"b\", \"c\"]\ntwo_pass = false\n",
            &["contact[0].two_pass", "false"][..],
        ),
    ] {
        let err = parse_err(&blocks(&format!("[[contact]]\n{extra}")));
        for n in needles {
            assert!(err.contains(n), "{extra:?}: {n:?} not in {err}");
        }
    }
}

#[test]
fn a_group_is_one_pass_whose_tables_tag_bodies_and_passes() {
    let text = blocks("[[contact]]\nbodies = \"all\"\nself_contact = true\n[[contact]]\nbodies = [\"a\", \"c\"]\n[[rigid_wall]]\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n");
    let (_, model, _) = build(&text);
    let set = ContactSet::new(&model).expect("contact");
    let t = set.tables();
    assert_eq!(set.names(), ["all", "a-c", "a-b-c"]);
    // 8 surface nodes and 8 segments per 2x2 block: the group's pass has all 24 of each, the
    // pair's two passes 8 + 8, the wall 24.
    let slots = |pass: u32| t.slots.iter().filter(|s| s.pass == pass).count();
    assert_eq!(
        (slots(0), slots(1), slots(2), slots(u32::MAX)),
        (24, 8, 8, 24)
    );
    let segs = |pass: u32| t.segments.iter().filter(|s| s.pass == pass).count();
    assert_eq!((segs(0), segs(1), segs(2)), (24, 8, 8));
    assert!(t
        .slots
        .iter()
        .filter(|s| s.pass == 0)
        .all(|s| s.group && s.self_contact && !s.second_is_slave));
    assert!(t
        .slots
        .iter()
        .filter(|s| s.pass == 1)
        .all(|s| !s.group && s.body == 0 && !s.second_is_slave));
    assert!(t
        .slots
        .iter()
        .filter(|s| s.pass == 2)
        .all(|s| !s.group && s.body == 2 && s.second_is_slave));
    for b in 0..3 {
        assert_eq!(
            t.slots
                .iter()
                .filter(|s| s.pass == 0 && s.body == b)
                .count(),
            8
        );
        assert_eq!(
            t.segments
                .iter()
                .filter(|s| s.pass == 0 && s.body == b)
                .count(),
            8
        );
    }
    // Group stiffness is halved like a two-pass contact's: equal to the pair's.
    let k0 = t
        .segments
        .iter()
        .find(|s| s.pass == 0 && s.body == 2)
        .expect("segment")
        .stiffness;
    let k1 = t
        .segments
        .iter()
        .find(|s| s.pass == 1)
        .expect("segment")
        .stiffness;
    assert!((k0 / k1 - 1.0).abs() < 1e-12, "{k0} {k1}");
    assert_eq!(t.reference.len(), t.nodes.len());
    for (x, &g) in t.reference.iter().zip(&t.nodes) {
        assert_eq!(*x, model.position[g as usize]);
    }
    assert_eq!(t.margin, set.margin());
}

#[test]
fn a_pile_of_sixteen_disks_in_one_general_contact_keeps_the_energy_and_no_node_inside_another_disk()
{
    let (r, model, u) = run_cpu_text(&asset("pile.toml"), "pile");
    assert_eq!(model.bodies.len(), 16);
    assert_eq!(
        r.samples[0].0.contacts.len(),
        2,
        "one history block per table"
    );
    // One column block for the whole group.
    let p = check_pile(&r, &model, &u, 1e-6);
    let floor = most_active(&r, 1);
    let pen = r
        .samples
        .iter()
        .map(|(s, _)| s.contacts[0].max_penetration)
        .fold(0.0, f64::max);
    let h = PILE_H;
    println!(
        "pile: {} steps, energy error {:.2e}, deepest node inside another disk at the end {:.2e} m \
         ({:.1e} h), reported penetration {pen:.2e} m, most active nodes: disks {}, floor {floor}",
        r.summary.steps,
        p.err,
        p.deepest,
        p.deepest / h,
        p.active
    );
    // Measured: energy error 2.1e-5, no node inside another disk (0 m), reported penetration
    // 1e-16 m, up to 14 nodes in contact between disks.
    assert!(floor > 0, "the disks met the floor");
    assert!(pen < 1e-6 * h, "{pen:e}");
}

#[test]
fn a_ring_pressed_onto_itself_stays_out_of_its_own_surface_with_self_contact_only() {
    let text = asset("ring_crush.toml");
    let t = RING_T; // element size across the wall
    let (r, model, u) = run_cpu_text(&text, "ring-self");
    let ring = check_ring(&r, &model, &u, 1e-6);
    println!(
        "ring, self-contact: {} steps, energy error {:.2e}, deepest node inside its own ring \
         {:.2e} m ({:.1e} h), inside the punch {:.2e} m, most self-contact nodes {}",
        r.summary.steps,
        ring.err,
        ring.inside,
        ring.inside / t,
        ring.other,
        ring.active
    );
    // Measured: 16 nodes in self-contact, energy error 7.2e-4, no node inside (0 m).
    // The self-contact exerts no net force on the ring.
    for (s, _) in &r.samples {
        assert_eq!(s.contacts[1].force, [0.0; 2]);
    }
    // Without self-contact the top wall goes through the bottom one.
    let start = text
        .find("[[contact]]\nbodies = [\"ring\"]")
        .expect("the self-contact table");
    let end = start
        + text[start..]
            .find("[[rigid_wall]]")
            .expect("a wall after it");
    let without = format!("{}{}", &text[..start], &text[end..]);
    let (_, model, u) = run_cpu_text(&without, "ring-noself");
    let through = self_penetration(&model, &u, 0);
    println!("ring, no self-contact: deepest node inside its own ring {through:.2e} m");
    // Measured: 3.9e-4 m (a node is at most h / 2 = 1e-3 m from the sides of an element it is in).
    assert!(through > 0.1 * t, "{through:e}");
}

#[test]
fn bodies_overlapping_at_t0_in_a_group_are_moved_apart_and_stay_at_rest() {
    for method in ["lagrange", "penalty"] {
        let text = crate::contact::overlapping_blocks(2e-5, method)
            .replace("bodies = [\"upper\", \"lower\"]", "bodies = \"all\"");
        let (_, model, _) = build(&text);
        let moved = &model.initial_overlaps;
        let worst = moved.iter().map(|o| o.depth).fold(0.0, f64::max);
        assert!(moved.iter().any(|o| o.interface == "all"), "group overlaps");
        assert!((worst - 2e-5).abs() < 1e-12, "{worst:e}");
        let mut again = ContactSet::new(&model).expect("contact");
        assert!(again.initial_overlaps(&model).is_empty(), "overlaps left");
        let (r, _, _) = run_cpu_text(&text, "group-overlap");
        let mut peak: f64 = 0.0;
        for (s, _) in &r.samples {
            peak = peak.max(s.kinetic.abs() + s.internal.abs() + s.hourglass.abs());
            for c in &s.contacts {
                peak = peak.max(c.max_penetration);
            }
        }
        println!(
            "group overlap ({method}): {} nodes moved; largest energy or penetration {peak:.2e}",
            moved.len()
        );
        assert!(peak < 1e-12, "{method}: the bodies moved: {peak:e}");
    }
}
