//! Assembling the asset: per level, pack the billboard textures into atlases (with MIPs),
//! write the billboards with their atlas rectangles and parent projections, and the foliage
//! base mesh with each vertex's projection onto its level-0 billboard (morph target).
//! Each side's MIP chain is built right after it is rendered (`atlas::side_chain`, its
//! allocation alone: allocations are aligned so no stored level crosses one), so assembling
//! an atlas is packing the sides and copying their levels into place. Normal maps, when
//! baked, use the colour atlas's packing (same places, same gutters, same levels).

use billow_format::{AtlasRect, Billboard, CloudAsset, CloudLevel, Header, Mesh};

use super::atlas::{self, Chain, Layout};
use super::bake;
use super::foliage;
use super::lod::Level;
use super::rect::PlaneRect;
use super::{BbcloudError, LevelStats, Seconds, Stage};
use crate::scene::Scene;
use std::time::Instant;

use rayon::prelude::*;

/// Density, layout and snapped (rectangle, texture width, height) per billboard, per level.
pub type LevelLayout = (f32, Layout, Vec<(PlaneRect, u32, u32)>);

/// One billboard's two sides, ready for packing: content sizes, each side's encoded MIP
/// chain (built right after rendering, [`atlas::side_chain`]), and summed coverage.
pub struct Sides {
    pub sizes: [(u32, u32); 2],
    pub colour: [Vec<Vec<u8>>; 2],
    pub normals: Option<[Vec<Vec<u8>>; 2]>,
    pub alpha: f64,
}

impl Sides {
    pub fn new(b: bake::Baked, layout: &Layout, levels: u32) -> Sides {
        let chain = |i: &bake::Image, n| atlas::side_chain(i, layout, levels, n);
        // Alpha-tested coverage kept at every stored level (atlas module docs).
        let colour = Chain::Coverage(atlas::ALPHA_CUTOFF);
        let alpha = [&b.front, &b.back]
            .iter()
            .map(|i| i.texels.iter().map(|t| f64::from(t.w)).sum::<f64>())
            .sum();
        Sides {
            sizes: [&b.front, &b.back].map(|i| (i.width, i.height)),
            colour: [chain(&b.front, colour), chain(&b.back, colour)],
            normals: b
                .normals
                .as_ref()
                .map(|[f, k]| [chain(f, Chain::Normals), chain(k, Chain::Normals)]),
            alpha,
        }
    }
}

#[allow(clippy::too_many_arguments)]
pub fn assemble(
    scene: &Scene,
    levels: &[Level],
    per_level: &[LevelLayout],
    images: &[Sides],
    mip_levels: u32,
    leaves: &[u32],
    trunk: Mesh,
    header: Header,
    secs: &mut Seconds,
    progress: &(dyn Fn(Stage, f32) + Sync),
) -> Result<(CloudAsset, Vec<LevelStats>), BbcloudError> {
    // Pack each level's sides and put their chains in place (levels in parallel: they are
    // independent), then assemble the asset in level order.
    let mut asset_levels = Vec::new();
    let mut billboards = Vec::new();
    let mut atlases = Vec::new();
    let mut stats_levels = Vec::new();
    let first_of = |l: usize| {
        levels[..l]
            .iter()
            .map(|v| v.boards.len() as u32)
            .sum::<u32>()
    };
    let sides_of = |l: usize| {
        let first = first_of(l) as usize;
        &images[first..first + levels[l].boards.len()]
    };
    let sizes =
        |l: usize| -> Vec<(u32, u32)> { sides_of(l).iter().flat_map(|s| s.sizes).collect() };
    let t = Instant::now();
    let packings = (0..levels.len())
        .into_par_iter()
        .map(|l| {
            let layout = &per_level[l].1;
            atlas::pack(&sizes(l), layout).ok_or_else(|| BbcloudError::BadParameter {
                option: "atlas_size",
                message: format!(
                    "level {l}: a billboard texture does not fit a {} atlas",
                    layout.max_size
                ),
            })
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    secs.pack += t.elapsed().as_secs_f64();
    let t = Instant::now();
    let built: Vec<(Vec<billow_format::Atlas>, f64)> = (0..levels.len())
        .into_par_iter()
        .map(|l| {
            progress(Stage::Pack, l as f32 / levels.len() as f32);
            let (layout, packing, sides) = (&per_level[l].1, &packings[l], sides_of(l));
            let colour: Vec<&[Vec<u8>]> = sides
                .iter()
                .flat_map(|s| s.colour.iter().map(Vec::as_slice))
                .collect();
            let place = |chains: &[&[Vec<u8>]], empty| {
                atlas::assemble_levels(chains, &sizes(l), packing, layout, mip_levels, empty)
            };
            let mips = place(&colour, [0; 4]);
            let normals: Option<Vec<&[Vec<u8>]>> = sides
                .iter()
                .map(|s| s.normals.as_ref().map(|n| n.iter().map(Vec::as_slice)))
                .collect::<Option<Vec<_>>>()
                .map(|v| v.into_iter().flatten().collect());
            let mut normal_maps = normals.map(|n| place(&n, [128, 128, 255, 255]).into_iter());
            let out = mips
                .into_iter()
                .zip(&packing.sizes)
                .map(|(mips, &(width, height))| billow_format::Atlas {
                    width,
                    height,
                    mips,
                    normals: normal_maps.as_mut().and_then(|it| it.next()),
                })
                .collect();
            (out, sides.iter().map(|s| s.alpha).sum())
        })
        .collect();
    secs.mips += t.elapsed().as_secs_f64();
    for (((l, level), (level_atlases, alpha_sum)), packing) in
        levels.iter().enumerate().zip(built).zip(packings)
    {
        let (d, _, rects) = &per_level[l];
        let first_atlas = atlases.len() as u32;
        atlases.extend(level_atlases);
        let next = levels.get(l + 1);
        for (bi, b) in level.boards.iter().enumerate() {
            let (r, w, h) = rects[bi];
            let side = |k: usize| {
                let p = packing.places[2 * bi + k];
                let (aw, ah) = packing.sizes[p.atlas as usize];
                let (aw, ah) = (aw as f32, ah as f32);
                AtlasRect {
                    atlas: first_atlas + p.atlas,
                    uv: [
                        p.x as f32 / aw,
                        p.y as f32 / ah,
                        (p.x + w) as f32 / aw,
                        (p.y + h) as f32 / ah,
                    ],
                }
            };
            let corners = r.corners();
            let parent_plane = b
                .parent
                .and_then(|p| next.map(|n| n.boards[p as usize].plane));
            let pc = corners.map(|c| parent_plane.map_or(c, |pp| pp.project(c)));
            billboards.push(Billboard {
                plane: [
                    b.plane.normal.x,
                    b.plane.normal.y,
                    b.plane.normal.z,
                    b.plane.offset,
                ],
                corners: corners.map(|c| c.to_array()),
                parent_corners: pc.map(|c| c.to_array()),
                front: side(0),
                back: side(1),
                parent: b.parent.map(|p| first_of(l + 1) + p),
                elements: b.elements,
            });
        }
        asset_levels.push(CloudLevel {
            first_billboard: first_of(l),
            billboard_count: level.boards.len() as u32,
            first_atlas,
            atlas_count: packing.sizes.len() as u32,
            epsilon: level.epsilon,
            texel_density: *d,
        });
        stats_levels.push(LevelStats {
            billboards: level.boards.len(),
            epsilon: level.epsilon,
            texel_density: *d,
            atlases: packing.sizes.clone(),
            fill: packing.fill(),
            content_fill: packing.content_fill(),
            texels: packing.content,
            alpha_coverage: alpha_sum / packing.atlas_texels().max(1) as f64,
            search: level.search,
        });
    }

    // Foliage base mesh with morph targets onto the level-0 billboards.
    let mut board_of = vec![0u32; scene.triangles.len()];
    for (bi, b) in levels[0].boards.iter().enumerate() {
        b.sources
            .iter()
            .for_each(|&t| board_of[t as usize] = bi as u32);
    }
    let mut fb = foliage::MeshBuilder::default();
    for &t in leaves {
        let tri = &scene.triangles[t as usize];
        let bi = board_of[t as usize];
        let plane = levels[0].boards[bi as usize].plane;
        fb.push(tri, bi, Some(tri.v.map(|v| plane.project(v.position))));
    }
    let asset = CloudAsset {
        header,
        levels: asset_levels,
        billboards,
        atlases,
        materials: foliage::materials(scene),
        textures: foliage::textures(scene),
        trunk,
        foliage: fb.finish(),
    };
    asset.validate()?;
    Ok((asset, stats_levels))
}
