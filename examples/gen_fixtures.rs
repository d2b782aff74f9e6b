//! Writes the procedural hard-case shapes as OBJ files (run: `make fixtures`).
//!
//! `cargo run --release --example gen_fixtures -- OUT_DIR` writes:
//! - `truss.obj`: a 40-storey lattice tower of beams 1/2000 of its height thick;
//! - `furry_torus.obj`: a torus with 3,000 strands of fur;
//! - `torus.obj` + `fur_tile.obj`: the surface and tileable fur patch for shell texturing;
//! - `tree.obj` (+ `tree.mtl`, `leaf.png`): a broadleaf tree, 1,500 alpha-masked leaf cards.

use std::path::PathBuf;

use billow::procgen::{fur_tile, furry_torus, leafy_tree, torus, truss, write_obj};

fn main() -> std::io::Result<()> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "out/procedural".into()),
    );
    std::fs::create_dir_all(&out)?;
    write_obj(&truss(10.0, 3.0, 40, 0.005), &out.join("truss.obj"))?;
    write_obj(&furry_torus(3000, 1), &out.join("furry_torus.obj"))?;
    write_obj(&torus(1.0, 0.35, 48, 24), &out.join("torus.obj"))?;
    write_obj(&fur_tile(400, 1), &out.join("fur_tile.obj"))?;
    write_obj(&leafy_tree(1500, 9, 1), &out.join("tree.obj"))?;
    eprintln!("wrote procedural fixtures to {}", out.display());
    Ok(())
}
