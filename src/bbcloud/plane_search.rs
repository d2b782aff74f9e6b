//! Algorithm 1 of Lacewell et al. 2006: random search for billboard planes.
//!
//! ```text
//! repeat                                   (round r = 0, 1, …)
//!   for each of N seeds T_s among the remaining elements (N = samples):
//!     p_j <- v_j + d_j n_Ts, d_j uniform in [-eps, eps)   (j = 0, 1, 2)
//!     B   <- plane through p_0, p_1, p_2
//!     area(B) = sum over remaining T with every vertex within eps of B of area(T) |n_B . n_T|
//!   keep the candidate with the largest area (ties: the first), remove its elements
//! until nothing remains
//! ```
//!
//! (The paper's listing resets `maxarea` inside the loop; its text says to keep the best of the
//! N, which is what this does.) Elements are triangles (level 0) or the previous level's
//! billboard quads (LOD levels: the seed triangle is corners 0, 1, 2, as the paper says).
//!
//! **Random numbers, keyed per element.** Every element has an identity `id(e)`: a hash of
//! its vertex coordinates' bits (not its index, which shifts when the input changes). In
//! round r each remaining (non-degenerate) element holds T tickets with keys
//! `k_0 = mix(salt(r) ^ id(e))`, `k_j = mix(k_0 ^ j)`, where
//! `salt(r) = mix(mix(mix(seed) ^ stream) ^ r)`, `mix` is the SplitMix64 finaliser and
//! `T = ceil(N / P)`, P the largest power of two ≤ the number of remaining elements. The N
//! tickets with the smallest keys (ties: spatial order) are the round's candidates, tried in
//! key order; ticket k's offsets d_0, d_1, d_2 are the first three `range_f32(-eps, eps)`
//! draws of `Pcg32::new(k, stream)`. That is N uniform draws of a seed (distinct seeds while
//! at least N remain; each remaining seed about N/|R| times, with different offsets, when
//! fewer do — as Algorithm 1's independent draws would), made so that what a round tries
//! depends only on the seed, the round and *which* elements remain (and the power of two
//! below their count), not on their order or indices: removing one triangle from the input
//! changes nothing in a round unless that triangle is drawn as a seed, takes part in (or
//! shifts the rounding of) the scores that decide the round, or moves the count across a
//! power of two; and once it has been taken the rounds are identical again (tested on the
//! oak: `tests/bbcloud_stability.rs`).
//!
//! Determinism: candidates are scored in parallel (rayon), each scan summing in a fixed order
//! (8 interleaved lanes over the spatially ordered elements, combined in a fixed order), and
//! the best is picked sequentially. The result is the same for any thread count. The scan may
//! be accelerated ([`SearchParams::accelerate`], on by default): runs of elements whose
//! bounding box misses the slab are skipped, which gives the same bits as the plain scan
//! (`slab.rs`; tested).
//!
//! Extent limit (§5, optional): with `max_extent = Some(r)` a candidate only counts (and
//! only takes) elements whose vertices all lie within `r` of its seed element's centroid,
//! which bounds a billboard's size (and so its texture) around its seed.
//!
//! View preference (§5, optional): with `view = Some(p)` candidates are ranked by their
//! projected area times `p.weight(n_B)` (expected on-screen area, `view.rs`); membership and
//! the reported area are unchanged.
//!
//! Degenerate seeds: an element whose seed triangle is (near) collinear — `|e1 x e2|` below
//! `1e-6 |longest edge|^2` — defines no normal and is never drawn as a seed (counted once in
//! `degenerate_seeds`); a perturbed plane that comes out degenerate is skipped (counted in
//! `skipped_candidates`). If a round has no usable candidate (only degenerate elements
//! remain), the remaining element with the smallest key gets a fallback plane through its
//! centroid (counted), so the search always terminates and never produces a NaN plane.

use glam::Vec3;
use rayon::prelude::*;

use super::element::{Element, Plane};
use super::slab::Soa;
use super::view::ViewPreference;
use crate::rng::Pcg32;

/// One billboard plane found by the search and the input elements it took (ascending).
#[derive(Clone, Debug, PartialEq)]
pub struct Found {
    pub plane: Plane,
    pub members: Vec<u32>,
    /// Summed projected area of the members.
    pub area: f32,
    /// The element whose perturbed seed triangle gave the plane (for a fallback plane: the
    /// element it was fitted to).
    pub seed: u32,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SearchStats {
    pub planes: usize,
    pub candidates: u64,
    /// Elements never drawn as seeds because their seed triangle has no normal.
    pub degenerate_seeds: u64,
    pub skipped_candidates: u64,
    pub fallback_planes: u64,
}

/// Search parameters. `epsilon` is in world units here (the caller scales by the radius).
#[derive(Clone, Debug)]
pub struct SearchParams {
    pub epsilon: f32,
    pub samples: u32,
    pub seed: u64,
    /// Random stream, so that each LOD level draws independent numbers from one seed.
    pub stream: u64,
    /// Lacewell §5's optional extent limit, world units: a candidate only takes elements
    /// whose vertices all lie within this distance of its seed's centroid.
    pub max_extent: Option<f32>,
    /// Lacewell §5's optional preference for planes facing the expected views.
    pub view: Option<ViewPreference>,
    /// Skip runs of elements outside the slab (same result as the plain scan).
    pub accelerate: bool,
}

impl Default for SearchParams {
    fn default() -> Self {
        SearchParams {
            epsilon: 0.01,
            samples: 500,
            seed: 0,
            stream: 0,
            max_extent: None,
            view: None,
            accelerate: true,
        }
    }
}

/// SplitMix64's finaliser: a bijective 64-bit mix.
pub fn mix(mut x: u64) -> u64 {
    x ^= x >> 30;
    x = x.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// `id(e)`: starting from the vertex count, `h = mix(h ^ bits)` over the f32 bits of
/// x, y, z of each vertex in order.
pub fn element_id(e: &Element) -> u64 {
    let mut h = e.count as u64;
    for v in &e.verts[..e.count] {
        for c in [v.x, v.y, v.z] {
            h = mix(h ^ u64::from(c.to_bits()));
        }
    }
    h
}

/// Tickets per remaining element: `ceil(N / P)`, P the largest power of two ≤ the number
/// remaining (at least 1). Only changes when the count crosses a power of two.
pub fn tickets_per_element(samples: usize, remaining: usize) -> usize {
    let p = if remaining == 0 {
        1
    } else {
        1usize << (usize::BITS - 1 - remaining.leading_zeros())
    };
    samples.div_ceil(p).max(1)
}

/// A candidate plane and the element it was seeded from.
#[derive(Clone, Copy)]
struct Candidate {
    plane: Plane,
    /// SoA position of the seed.
    pos: usize,
    /// Centroid of the seed element (centre of the extent limit).
    centre: Vec3,
}

/// The plane through seed `e`'s vertices moved by the offsets drawn from `key`.
fn perturbed(e: &Element, n: Vec3, key: u64, stream: u64, eps: f32) -> Option<Plane> {
    let mut rng = Pcg32::new(key, stream);
    let d = [0, 1, 2].map(|_| rng.range_f32(-eps, eps));
    let p = [0, 1, 2].map(|j| e.verts[j] + d[j] * n);
    let nb = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
    let offset = nb.dot((p[0] + p[1] + p[2]) / 3.0);
    (nb != Vec3::ZERO && nb.is_finite() && offset.is_finite())
        .then_some(Plane { normal: nb, offset })
}

/// Run Algorithm 1 until every element is on some plane. `progress(assigned, total)`.
pub fn search(
    elems: &[Element],
    params: &SearchParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> (Vec<Found>, SearchStats) {
    let eps = params.epsilon;
    let mut soa = Soa::new(elems);
    let ids: Vec<u64> = elems.iter().map(element_id).collect();
    let normals: Vec<Option<Vec3>> = elems.iter().map(Element::seed_normal).collect();
    let mut stats = SearchStats {
        degenerate_seeds: normals.iter().filter(|n| n.is_none()).count() as u64,
        ..SearchStats::default()
    };
    let base = mix(mix(params.seed) ^ params.stream);
    let mut found = Vec::new();
    let total = elems.len();
    let want = params.samples.max(1) as usize;
    let mut keyed: Vec<(u64, usize)> = Vec::with_capacity(total);
    for round in 0u64.. {
        if soa.is_empty() {
            break;
        }
        let salt = mix(base ^ round);
        let key = |pos: usize| mix(salt ^ ids[soa.id[pos] as usize]);
        let tickets = tickets_per_element(want, soa.len());
        keyed.clear();
        for pos in (0..soa.len()).filter(|&pos| normals[soa.id[pos] as usize].is_some()) {
            let k = key(pos);
            keyed.push((k, pos));
            keyed.extend((1..tickets).map(|j| (mix(k ^ j as u64), pos)));
        }
        if keyed.len() > want {
            keyed.select_nth_unstable(want - 1);
            keyed.truncate(want);
        }
        keyed.sort_unstable();
        let mut cands = Vec::with_capacity(keyed.len());
        for &(k, pos) in &keyed {
            stats.candidates += 1;
            let e = &elems[soa.id[pos] as usize];
            let n = normals[soa.id[pos] as usize].expect("non-degenerate seed");
            match perturbed(e, n, k, params.stream, eps) {
                Some(plane) => cands.push(Candidate {
                    plane,
                    pos,
                    centre: e.centroid(),
                }),
                None => stats.skipped_candidates += 1,
            }
        }
        let best = if cands.is_empty() {
            stats.fallback_planes += 1;
            let pos = (0..soa.len()).min_by_key(|&p| (key(p), p)).unwrap_or(0);
            let e = &elems[soa.id[pos] as usize];
            Candidate {
                plane: fallback_plane(e),
                pos,
                centre: e.centroid(),
            }
        } else {
            let cull = params.accelerate;
            let scores: Vec<f32> = cands
                .par_iter()
                .map(|c| {
                    let s = match params.max_extent {
                        None => soa.score::<false>(&c.plane, eps, (c.centre, 0.0), cull),
                        Some(r) => soa.score::<true>(&c.plane, eps, (c.centre, r), cull),
                    };
                    params
                        .view
                        .as_ref()
                        .map_or(s, |v| s * v.weight(c.plane.normal))
                })
                .collect();
            let mut bi = 0;
            for (i, &s) in scores.iter().enumerate() {
                if s > scores[bi] {
                    bi = i;
                }
            }
            cands[bi]
        };
        let mut keep = vec![true; soa.len()];
        let mut members = Vec::new();
        let mut area = 0.0;
        let lim = params.max_extent.map(|r| (best.centre, r));
        for (j, k) in keep.iter_mut().enumerate() {
            // The seed is inside by construction (|d_j| < eps); including it explicitly only
            // guards against rounding, so every round removes at least one element.
            if j == best.pos || soa.inside(j, &best.plane, eps, lim) {
                *k = false;
                members.push(soa.id[j]);
                area += soa.contrib::<false>(j, &best.plane, f32::INFINITY, (Vec3::ZERO, 0.0));
            }
        }
        members.sort_unstable();
        let seed = soa.id[best.pos];
        soa.retain(&keep);
        found.push(Found {
            plane: best.plane,
            members,
            area,
            seed,
        });
        progress(total - soa.len(), total);
    }
    stats.planes = found.len();

    (found, stats)
}

/// A plane through a degenerate element: its own normal if it has one, else one containing
/// its longest edge (or any plane through a point), through its centroid.
pub fn fallback_plane(e: &Element) -> Plane {
    let v = &e.verts[..e.count];
    let centroid = v.iter().copied().sum::<Vec3>() / e.count as f32;
    let normal = e.seed_normal().unwrap_or_else(|| {
        let mut edge = Vec3::ZERO;
        for i in 0..e.count {
            let d = v[(i + 1) % e.count] - v[i];
            if d.length_squared() > edge.length_squared() {
                edge = d;
            }
        }
        let edge = edge.normalize_or_zero();
        if edge == Vec3::ZERO {
            return Vec3::Y;
        }
        let a = edge.abs();
        let axis = if a.x <= a.y && a.x <= a.z {
            Vec3::X
        } else if a.y <= a.z {
            Vec3::Y
        } else {
            Vec3::Z
        };
        edge.cross(axis).normalize()
    });
    Plane {
        normal,
        offset: normal.dot(centroid),
    }
}
