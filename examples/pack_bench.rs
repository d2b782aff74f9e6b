//! Times `emptyspace::pack::pack` on a slot list and prints the atlas and a hash of the
//! placements (equal hashes: the same packing).
//!
//! `cargo run --release --example pack_bench -- benches/pack_slots_tree512.txt`
//!
//! The file: `#` comment lines, then `max_side pair_align`, then one slot per line as
//! `[x, y, z] [s0, s1, s2, s3, s4, s5]` (size in blocks, soft depth per face).
use billow::emptyspace::pack::{pack, Slot};
use std::time::Instant;

fn nums(s: &str) -> Vec<usize> {
    s.split(|c: char| !c.is_ascii_digit())
        .filter(|t| !t.is_empty())
        .map(|t| t.parse().unwrap())
        .collect()
}

fn main() {
    let path = std::env::args().nth(1).expect("slot file");
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head = nums(lines.next().unwrap());
    let slots: Vec<Slot> = lines
        .map(|l| {
            let v = nums(l);
            Slot {
                size: [v[0], v[1], v[2]],
                soft: [v[3], v[4], v[5], v[6], v[7], v[8]],
            }
        })
        .collect();
    let t = Instant::now();
    let p = pack(&slots, head[0], head[1] != 0).unwrap();
    let dt = t.elapsed().as_secs_f64();
    let mut h: u64 = 1469598103934665603;
    for pl in &p.placed {
        for v in pl.origin.iter().chain(&pl.perm) {
            h = (h ^ *v as u64).wrapping_mul(1099511628211);
        }
    }
    println!(
        "{} slots: atlas {:?} ({} blocks) in {dt:.3} s, hash {h:016x}",
        slots.len(),
        p.dims,
        p.dims.iter().product::<usize>()
    );
}
