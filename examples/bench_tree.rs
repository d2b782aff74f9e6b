//! Writes the voxelize benchmark's 200,000-triangle tree ([`billow::procgen::bench_tree`]):
//! `cargo run --release --example bench_tree -- OUT/tree.obj` (+ tree.mtl, tree.png).

fn main() -> std::io::Result<()> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "tree.obj".to_string());
    let tree = billow::procgen::bench_tree(12345);
    tree.write_obj(std::path::Path::new(&out))?;
    println!(
        "{out}: {} vertices, {} triangles",
        tree.positions.len(),
        tree.faces.len()
    );
    Ok(())
}
