//! Seconds to write one field snapshot (`fields/*.vtu`) of the generated bench block at 10^4,
//! 10^5 and 10^6 elements, in each encoding (`run.field_format`): ASCII text against zlib-
//! compressed binary. The file sizes are printed once per size.

use criterion::{criterion_group, criterion_main, Criterion};

use ricochet::output::fields::FieldWriter;
use ricochet::scene::FieldFormat;
use ricochet::step::Snapshot;

fn write(c: &mut Criterion) {
    let dir = std::env::temp_dir().join("ricochet_fields_bench");
    let mut group = c.benchmark_group("field_snapshot");
    group.sample_size(10);
    for cells in [100usize, 316, 1000] {
        let scene = ricochet::bench::scene(cells).expect("bench scene");
        let model = ricochet::run::model(&scene).expect("model");
        let n = model.node_count();
        // A smooth deformation so that the arrays hold varied values, as in a real run.
        let displacement: Vec<[f64; 2]> = model
            .position
            .iter()
            .map(|p| [1e-4 * (40.0 * p[1]).sin(), 2e-4 * (30.0 * p[0]).cos()])
            .collect();
        let velocity: Vec<[f64; 2]> = model
            .position
            .iter()
            .map(|p| [3.0 * (50.0 * p[0]).cos(), -2.0 * (20.0 * p[1]).sin()])
            .collect();
        assert_eq!(displacement.len(), n);
        let snap = Snapshot {
            time: 0.0,
            step: 0,
            displacement,
            velocity,
            plastic: Vec::new(),
            eroded: Vec::new(),
            damage: Vec::new(),
        };
        for (name, format) in [
            ("ascii", FieldFormat::Ascii),
            ("binary", FieldFormat::Binary),
        ] {
            let out = dir.join(format!("{name}_{cells}"));
            let _ = std::fs::remove_dir_all(&out);
            let mut writer = FieldWriter::new(&out, format).expect("writer");
            writer.write(&model, &snap).expect("write");
            let bytes: u64 = std::fs::read_dir(out.join("fields"))
                .expect("fields")
                .map(|e| e.expect("entry").metadata().expect("size").len())
                .sum();
            eprintln!(
                "field_snapshot {name} {} elements: {bytes} bytes",
                model.element_count()
            );
            group.bench_function(format!("{name}_{}_elements", model.element_count()), |b| {
                b.iter(|| {
                    let mut w = FieldWriter::new(&out, format).expect("writer");
                    w.write(&model, &snap).expect("write")
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, write);
criterion_main!(benches);
