//! Assembling the asset: per level, pack the billboard textures into atlases (with MIPs),
//! write the billboards with their atlas rectangles and parent projections, and the foliage
//! base mesh with each vertex's projection onto its level-0 billboard (morph target).
//! Normal maps, when baked, are composed with the colour atlas's packing (same places, same
//! gutters) and get the same number of MIP levels.

use billow_format::{AtlasRect, Billboard, CloudAsset, CloudLevel, Header, Mesh};

use super::atlas::{self, Layout};
use super::bake;
use super::foliage;
use super::lod::Level;
use super::rect::PlaneRect;
use super::{BbcloudError, LevelStats, Seconds, Stage};
use crate::scene::Scene;
use std::time::Instant;

/// Density, layout and snapped (rectangle, texture width, height) per billboard, per level.
pub type LevelLayout = (f32, Layout, Vec<(PlaneRect, u32, u32)>);

#[allow(clippy::too_many_arguments)]
pub fn assemble(
    scene: &Scene,
    levels: &[Level],
    per_level: &[LevelLayout],
    images: &[bake::Baked],
    mip_levels: u32,
    leaves: &[u32],
    trunk: Mesh,
    header: Header,
    secs: &mut Seconds,
    progress: &(dyn Fn(Stage, f32) + Sync),
) -> Result<(CloudAsset, Vec<LevelStats>), BbcloudError> {
    // Pack, compose and MIP each level's atlases; assemble the asset.
    let mut asset_levels = Vec::new();
    let mut billboards = Vec::new();
    let mut atlases = Vec::new();
    let mut stats_levels = Vec::new();
    let mut img_off = 0;
    let first_of = |l: usize| {
        levels[..l]
            .iter()
            .map(|v| v.boards.len() as u32)
            .sum::<u32>()
    };
    for (l, level) in levels.iter().enumerate() {
        let t = Instant::now();
        progress(Stage::Pack, l as f32 / levels.len() as f32);
        let (d, layout, rects) = &per_level[l];
        let baked = &images[img_off..img_off + level.boards.len()];
        let imgs: Vec<&bake::Image> = baked.iter().flat_map(|b| [&b.front, &b.back]).collect();
        let nrms: Option<Vec<&bake::Image>> = baked
            .iter()
            .map(|b| b.normals.as_ref().map(|[f, k]| [f, k]))
            .collect::<Option<Vec<_>>>()
            .map(|v| v.into_iter().flatten().collect());
        img_off += level.boards.len();
        let sizes: Vec<(u32, u32)> = imgs.iter().map(|i| (i.width, i.height)).collect();
        let packing = atlas::pack(&sizes, layout).ok_or_else(|| {
            BbcloudError::BadParameter(format!(
                "level {l}: a billboard texture does not fit a {} atlas",
                layout.max_size
            ))
        })?;
        let composed = atlas::compose(&imgs, &packing, layout);
        let composed_n = nrms.map(|n| atlas::compose(&n, &packing, layout));
        let alpha_sum: f64 = imgs
            .iter()
            .map(|i| i.texels.iter().map(|t| f64::from(t.w)).sum::<f64>())
            .sum();
        secs.pack += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let first_atlas = atlases.len() as u32;
        let mut normal_maps = composed_n.map(|v| v.into_iter());
        for a in composed {
            let (w, h) = (a.width, a.height);
            let normals = normal_maps
                .as_mut()
                .and_then(|it| it.next())
                .map(|n| atlas::normal_chain(n, mip_levels));
            atlases.push(billow_format::Atlas {
                width: w,
                height: h,
                mips: atlas::mip_chain(a, mip_levels),
                normals,
            });
        }
        secs.mips += t.elapsed().as_secs_f64();
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
