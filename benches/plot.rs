//! Seconds to draw one field snapshot (`ricochet plot`): a deformed n x n quad mesh with one value
//! per element, rasterized and encoded as a PNG, at 10^4, 10^5 and 10^6 elements.

use criterion::{criterion_group, criterion_main, Criterion};

use ricochet::plot::field::{edges_readable, range, Field, Frame, Layer, Window};
use ricochet::plot::read::Piece;

/// An n x n block of unit size, sheared a little, with a smooth field over it.
fn block(n: usize) -> (Piece, Vec<f64>) {
    let mut piece = Piece::default();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            piece
                .points
                .push([x + 0.1 * y * y, y + 0.05 * (3.0 * x).sin()]);
        }
    }
    let mut values = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let a = (j * (n + 1) + i) as u32;
            let m = n as u32 + 1;
            piece.connectivity.extend([a, a + 1, a + 1 + m, a + m]);
            piece.offsets.push(piece.connectivity.len() as u32);
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            values.push((6.0 * x).sin() * (4.0 * y).cos());
        }
    }
    (piece, values)
}

fn draw(c: &mut Criterion) {
    assert!(ricochet::plot::style::register_font());
    let dir = std::env::temp_dir().join("ricochet_plot_bench");
    std::fs::create_dir_all(&dir).expect("bench folder");
    let mut group = c.benchmark_group("plot_snapshot");
    group.sample_size(10);
    for n in [100usize, 316, 1000] {
        let (piece, values) = block(n);
        let window = Window::around((0.0, 1.1, -0.05, 1.05));
        let layers = vec![Layer {
            piece: &piece,
            values: &values,
        }];
        let frame = Frame {
            edges: edges_readable(&layers, &window),
            range: range(values.iter()),
            layers,
            window,
            field: Field::VonMises,
            time: 0.0,
        };
        let path = dir.join(format!("field_{n}.png"));
        group.bench_function(format!("{}_elements", n * n), |b| {
            b.iter(|| ricochet::plot::write_field_png(&path, &frame).expect("draw"))
        });
    }
    group.finish();
}

criterion_group!(benches, draw);
criterion_main!(benches);
