fn main() {
    for p in std::env::args().skip(1) {
        let a = billow_format::VolumeAsset::read(std::path::Path::new(&p)).unwrap();
        let Some(n) = a.normals.as_ref() else {
            println!("{p}: no normals");
            continue;
        };
        let v: Vec<String> = (0..a.levels.len().min(5))
            .map(|l| {
                format!(
                    "L{l} {:.3}",
                    billow::voxelize::toksvig::normal_coherence(&a.levels[l], &n[l])
                        .unwrap_or(-1.0)
                )
            })
            .collect();
        println!("{p}: {}", v.join(", "));
    }
}
