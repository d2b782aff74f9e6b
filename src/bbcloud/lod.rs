//! The LOD chain (Lacewell et al. §3, last paragraphs).
//!
//! Level 0 is Algorithm 1 on the foliage triangles. Level ℓ ≥ 1 runs it again on level ℓ−1's
//! trimmed billboards as quads, with ε doubled per level (and textures halved, see
//! `mod.rs`). When there are two or more levels the last one is the special case: two
//! perpendicular vertical billboards through the centre of the foliage's bounding sphere,
//! "vertical" meaning that both contain the up axis ([`cross_normals`]; +Y by default, as
//! glTF, `--up` to change it). Every billboard of a level has a
//! parent in the next one: the billboard whose search took it, or for the last level the one
//! of the two whose normal is closest to its own (the first on a tie). Each billboard is
//! textured from the source triangles it stands for (those of its children, recursively),
//! so coarser levels are rendered from the real leaves, never from filtered textures.

use glam::Vec3;

use super::element::{Element, Plane};
use super::plane_search::{search, SearchParams, SearchStats};
use super::rect::{trim, PlaneRect};
use super::unfold::{unfold, Flatten};
use super::view::ViewPreference;
use crate::scene::Scene;

/// A billboard being built.
#[derive(Clone, Debug, PartialEq)]
pub struct Board {
    pub plane: Plane,
    /// Trimmed rectangle (before snapping to the texel grid).
    pub rect: PlaneRect,
    /// Scene triangle indices it is textured from, ascending.
    pub sources: Vec<u32>,
    /// Where each source triangle is textured from (turned into the plane by
    /// [`super::unfold`], or where it is with [`Flatten::Project`]), one entry per `sources`
    /// entry.
    pub unfolded: Vec<[Vec3; 3]>,
    /// Elements the search put on it (triangles for level 0, child billboards otherwise).
    pub elements: u32,
    /// Index of the parent within the next level.
    pub parent: Option<u32>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    pub boards: Vec<Board>,
    /// Slab half-width, world units.
    pub epsilon: f32,
    pub search: SearchStats,
}

/// Centre and radius of the foliage's bounding sphere: the centre of the vertices' bounding
/// box and the largest distance from it to a vertex.
pub fn bounding_sphere(scene: &Scene, tris: &[u32]) -> (Vec3, f32) {
    let pts = || {
        tris.iter()
            .flat_map(|&t| scene.triangles[t as usize].v.iter().map(|v| v.position))
    };
    let (lo, hi) = pts().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| {
        (a.min(p), b.max(p))
    });
    let c = 0.5 * (lo + hi);
    let r = pts().map(|p| p.distance(c)).fold(0.0f32, f32::max);
    (c, r)
}

fn make_board(
    scene: &Scene,
    plane: Plane,
    sources: Vec<u32>,
    elements: u32,
    flatten: Flatten,
) -> Board {
    let unfolded = match flatten {
        Flatten::Project => sources
            .iter()
            .map(|&t| scene.triangles[t as usize].v.map(|v| v.position))
            .collect(),
        Flatten::Unfold => unfold(scene, &sources, plane.normal),
    };
    let pts: Vec<Vec3> = unfolded.iter().flatten().copied().collect();
    let rect = trim(&plane, &pts);
    Board {
        plane,
        rect,
        sources,
        unfolded,
        elements,
        parent: None,
    }
}

/// The normals of the last level's two billboards for a unit `up` axis: `a`, the first of
/// +X, +Y, +Z (in that order) that is at least 0.5 away from parallel to `up`, made
/// perpendicular to `up`, and `a × up`. For up = +Y that is +X and +Z; for +Z, +X and −Y;
/// for +X, +Y and −Z. Both planes contain the up axis through the centre.
pub fn cross_normals(up: Vec3) -> [Vec3; 2] {
    let a = [Vec3::X, Vec3::Y, Vec3::Z]
        .into_iter()
        .find(|a| a.dot(up).abs() < 0.5)
        .unwrap_or(Vec3::X);
    let a = (a - a.dot(up) * up).normalize();
    [a, a.cross(up).normalize()]
}

/// Parameters of the chain.
#[derive(Clone, Debug)]
pub struct ChainParams {
    /// ε of level 0, world units.
    pub epsilon: f32,
    pub samples: u32,
    pub seed: u64,
    pub levels: u32,
    /// Extent limit of level 0, world units (doubled per level like ε); `None`: no limit.
    pub max_extent: Option<f32>,
    /// Preference for planes facing the expected views (every searched level).
    pub view: Option<ViewPreference>,
    /// Unit up axis of the last level's two vertical billboards.
    pub up: Vec3,
    /// How the billboards' triangles are laid onto their planes.
    pub flatten: Flatten,
}

/// Build every level's billboards (planes, trimmed rectangles, sources, parents).
/// `progress(level, assigned, total)`.
pub fn build_chain(
    scene: &Scene,
    leaves: &[u32],
    centre: Vec3,
    p: &ChainParams,
    progress: &(dyn Fn(u32, usize, usize) + Sync),
) -> Vec<Level> {
    let mut levels: Vec<Level> = Vec::new();
    for l in 0..p.levels.max(1) {
        let eps = p.epsilon * (1u32 << l.min(30)) as f32;
        if l > 0 && l + 1 == p.levels {
            let prev = levels.last_mut().expect("previous level");
            let normals = cross_normals(p.up);
            let mut counts = [0u32; 2];
            for b in &mut prev.boards {
                let k = usize::from(
                    b.plane.normal.dot(normals[1]).abs() > b.plane.normal.dot(normals[0]).abs(),
                );
                b.parent = Some(k as u32);
                counts[k] += 1;
            }
            let boards = normals
                .iter()
                .zip(counts)
                .map(|(&n, c)| {
                    make_board(
                        scene,
                        Plane {
                            normal: n,
                            offset: n.dot(centre),
                        },
                        leaves.to_vec(),
                        c,
                        p.flatten,
                    )
                })
                .collect();
            levels.push(Level {
                boards,
                epsilon: eps,
                search: SearchStats::default(),
            });
            break;
        }
        let (elems, children): (Vec<Element>, Vec<Vec<u32>>) = match levels.last() {
            None => leaves
                .iter()
                .map(|&t| {
                    let v = &scene.triangles[t as usize].v;
                    (
                        Element::triangle(v[0].position, v[1].position, v[2].position),
                        vec![t],
                    )
                })
                .unzip(),
            Some(prev) => prev
                .boards
                .iter()
                .map(|b| (Element::quad(b.rect.corners()), b.sources.clone()))
                .unzip(),
        };
        let params = SearchParams {
            epsilon: eps,
            samples: p.samples,
            seed: p.seed,
            stream: u64::from(l),
            max_extent: p.max_extent.map(|r| r * (1u32 << l.min(30)) as f32),
            view: p.view.clone(),
            accelerate: true,
        };
        let (found, stats) = search(&elems, &params, &|a, t| progress(l, a, t));
        let mut boards = Vec::with_capacity(found.len());
        for (bi, f) in found.iter().enumerate() {
            let mut sources: Vec<u32> = f
                .members
                .iter()
                .flat_map(|&m| children[m as usize].iter().copied())
                .collect();
            sources.sort_unstable();
            if let Some(prev) = levels.last_mut() {
                for &m in &f.members {
                    prev.boards[m as usize].parent = Some(bi as u32);
                }
            }
            boards.push(make_board(
                scene,
                f.plane,
                sources,
                f.members.len() as u32,
                p.flatten,
            ));
        }
        levels.push(Level {
            boards,
            epsilon: eps,
            search: stats,
        });
    }
    levels
}
