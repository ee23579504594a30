fn main() {
    let ctx = ricochet::gpu::GpuContext::shared().expect("ctx");
    println!(
        "limits: max_buffer {} max_storage_binding {}",
        ctx.device.limits().max_buffer_size,
        ctx.device.limits().max_storage_buffer_binding_size
    );
    for path in [
        "assets/disk_wall.toml",
        "assets/bench/pile_1e4.toml",
        "assets/bench/striker_1e4.toml",
    ] {
        let scene = ricochet::scene::Scene::load(std::path::Path::new(path)).unwrap();
        let model = ricochet::run::model(&scene).unwrap();
        let plan = ricochet::plan::Plan::new(&scene, &model);
        let s = ricochet::gpu::GpuSolver::new(
            ctx.clone(),
            &model,
            &plan,
            ricochet::run::schedule(&scene),
        )
        .unwrap();
        let ne = model.element_count() as f64;
        let nn = model.node_count() as f64;
        println!("{path}: {} elements {} nodes", ne, nn);
        let mut v = s.state().allocated.clone();
        v.sort_by_key(|x| std::cmp::Reverse(x.1));
        for (n, b) in v.iter().take(8) {
            println!(
                "  {n:24} {b:10} {:.1} B/elem {:.1} B/node",
                *b as f64 / ne,
                *b as f64 / nn
            );
        }
    }
}
