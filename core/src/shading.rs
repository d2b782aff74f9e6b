//! The lighting models of billow, pure math shared by the billboard bake
//! (`billow::bbcloud`), the reference renderer and CPU slicer (`billow::eval`), and mirrored
//! by the viewer's shaders (`shading.wgsl`, `volume.wgsl`). Re-exported as
//! `billow::eval::lighting::{diffuse_factor, volume_diffuse_factor}`.

use glam::Vec3;

/// Direction towards the light (not normalised) where no scene names one: the viewer's
/// default scene light, the reference's and the CPU slicer's, and the billboard bake's.
pub const DEFAULT_LIGHT: Vec3 = Vec3::new(0.3, 1.0, 0.5);

/// Ambient fraction of [`DEFAULT_LIGHT`] (the unshadowed part of the light): the format's
/// default for a baked light's ambient ([`billow_format::DEFAULT_AMBIENT`]), one value.
pub const DEFAULT_AMBIENT: f32 = billow_format::DEFAULT_AMBIENT;

/// `ambient + (1 − ambient) · |n·light|`: the one lighting model of billow — the
/// billboard bake's factor, the reference's, and the viewer's mesh and cloud passes
/// (two-sided Lambert; `viewer/src/shaders/shading.wgsl`, which also multiplies the
/// diffuse term by shadow visibility, tested against this in
/// `viewer/tests/shading_gpu.rs`).
#[inline]
pub fn diffuse_factor(n: Vec3, light: Vec3, ambient: f32) -> f32 {
    ambient + (1.0 - ambient) * n.dot(light).abs()
}

/// The runtime shading of a volume voxel (`billow::eval::lighting::Lighting::Volume`, the CPU
/// slicer and the viewer's `volume.wgsl`): `ambient + (1 − ambient) · visibility · max(n̄·light, 0)`.
///
/// `n` is the voxel's **Toksvig-filtered** normal, the alpha-weighted mean of the unit
/// normals it holds, *not* renormalised (`|n̄| ≤ 1`, `src/voxelize/toksvig.rs`); `light`
/// is the unit direction towards the light. This is the *effective normal* reading of
/// Toksvig: Lambert's cosine is linear in the normal, so `n̄·L` is exactly the mean of
/// `n·L` over the voxel's normals, and the shorter (rougher) the mean, the weaker the
/// directional term; clamping after the mean under-estimates only where the voxel's
/// normals straddle the terminator. A voxel whose normals cancel (`n̄ = 0`: opposite
/// faces, fuzz) gets the ambient term alone.
///
/// **One-sided**: volumes with normals are closed surfaces (`voxelize --normals auto`
/// keeps normals only where they agree, docs/voxelize.md), whose far side must stay dark
/// to show a terminator; the two-sided [`diffuse_factor`] of leaf cards would light it
/// as brightly as the near side. `visibility` is the shadow map's (1 without shadows).
#[inline]
pub fn volume_diffuse_factor(n: Vec3, light: Vec3, ambient: f32, visibility: f32) -> f32 {
    ambient + (1.0 - ambient) * visibility * n.dot(light).max(0.0)
}

/// The runtime shading of a volume voxel that stores the **second moments** of its normals
/// instead of their mean (`voxelize --normals moments`, and `auto` on foliage; SPEC §8.4a):
/// `ambient + (1 − ambient) · visibility · c`, with `c` the voxel's estimate of the
/// two-sided Lambert term the mesh shows (the mesh pass's [`diffuse_factor`]) from
/// `u = m / (mx + my + mz)`, `q = u·(L∘L)` (`≈ E[(n·L)²]`) and the view `V`:
///
/// `c = w·√q + (1 − w)·min(g·min(3/16 + 15/16·q, 1), 1)`, `w = clamp((3·u·u − 1) / 2, 0, 1)`,
/// `g = 8/(3π)·(sin γ + (π/2 − γ)·cos γ)` ([`spread_view_factor`]),
/// `cos γ = |u·(V∘L)| / √(u·(V∘V) · q)`.
///
/// - `√q` is exact for normals that share one direction along an axis (`√E[(n·L)²]` of a
///   single normal is `|n·L|`, whatever the view), and overshoots where they spread:
///   `1/√3 ≈ 0.58` against `E|n·L| = ½` for normals spread evenly over the sphere (Jensen).
/// - `3/16 + 15/16·q` is `E|n·L|` band-limited to what a second moment knows: `|t|` in
///   Legendre polynomials is `½P₀(t) + ⅝P₂(t) − …`, and `E[P₂(n·L)] = (3E[(n·L)²] − 1)/2`,
///   so it is exact for an even spread and rings for one direction (`3/16` edge-on).
/// - `g` is what a viewer sees of spread normals: each leaf in proportion to its projected
///   area `|n·V|`, so the light it sees is `E[|n·V||n·L|] / E|n·V|`, which for an even
///   spread is `½·g(γ)`, `γ` the angle between `V` and `±L` (`E|xy| = 2/(3π)·(sin γ +
///   (π/2 − γ) cos γ)` over the sphere): 4/3 when the viewer looks along the light,
///   0.85 across it, 1 on average over views. `cos γ` is the normals' correlation of
///   `n·V` and `n·L` under `u` (`|V·L|` for an even spread).
/// - `w` blends the two by the concentration `u·u`: 1 for one axis, ⅓ for an even spread.
///
/// `m` is the diagonal of `E[n nᵀ]` over the unit normals in the voxel (filtered like the
/// colour; `mx + my + mz = 1` for a texel with surface, so the division only undoes
/// quantization and filtering), `light` the unit direction towards the light and `view`
/// the unit direction towards the viewer (the camera's view axis), both **in the volume's
/// own axes**. The SGGX microflake model of Heitz, Dupuy, Crassin and Dachsbacher (2015)
/// keeps the whole matrix `S`; billow keeps its diagonal, which filters linearly in four
/// bytes (the whole matrix was measured and changed nothing that matters: docs/voxelize.md,
/// "Normals"). **Two-sided**, like the viewer's meshes: the sign of a leaf's normal does not
/// matter. Zero moments (no surface) give the ambient term alone.
#[inline]
pub fn moments_diffuse_factor(
    m: Vec3,
    light: Vec3,
    view: Vec3,
    ambient: f32,
    visibility: f32,
) -> f32 {
    let trace = m.x + m.y + m.z;
    if !(trace > 1e-6 && trace.is_finite()) {
        return ambient;
    }
    let u = m / trace;
    let q = u.dot(light * light).clamp(0.0, 1.0);
    let w = ((3.0 * u.dot(u) - 1.0) * 0.5).clamp(0.0, 1.0);
    let spread = (3.0 / 16.0 + 15.0 / 16.0 * q).min(1.0) * view_factor(u, light, view, q);
    let cosine = w * q.sqrt() + (1.0 - w) * spread.min(1.0);
    ambient + (1.0 - ambient) * visibility * cosine
}

/// `g` of [`moments_diffuse_factor`] with `cos γ` the correlation of `n·V` and `n·L` under
/// the normalised moments `u` (`q = u·(L∘L)`); 1 when either variance is 0 or not finite.
#[inline]
fn view_factor(u: Vec3, light: Vec3, view: Vec3, q: f32) -> f32 {
    let vv = u.dot(view * view);
    let d = (vv * q).sqrt();
    if !(d > 1e-12 && d.is_finite()) {
        return 1.0;
    }
    spread_view_factor((u.dot(view * light).abs() / d).min(1.0))
}

/// `g(c) = 8/(3π)·(sin γ + (π/2 − γ)·c)`, `c = cos γ ∈ [0, 1]`, as the polynomial shaders
/// evaluate cheaply: `sin γ + (π/2 − γ)·c = √(1 − c²) + c·asin c = 1 + c²/2 + c⁴/24 +
/// c⁶/80 + …` (its derivative is `asin c`), cut after `c⁶` and closed with the `c⁸` term
/// that makes it exact at `c = 1` (π/2): within 0.18 % of the closed form everywhere.
#[inline]
pub fn spread_view_factor(c: f32) -> f32 {
    const K8: f32 = std::f32::consts::FRAC_PI_2 - (1.0 + 1.0 / 2.0 + 1.0 / 24.0 + 1.0 / 80.0);
    let c2 = c * c;
    let s = 1.0 + c2 * (1.0 / 2.0 + c2 * (1.0 / 24.0 + c2 * (1.0 / 80.0 + c2 * K8)));
    8.0 / (3.0 * std::f32::consts::PI) * s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `E[n∘n]` of `normals` (f64 sums), and `E[|n·V||n·L|] / E|n·V|` over them: the mesh
    /// pass's two-sided cosine over the normals a viewer from `view` sees, each in
    /// proportion to its projected area — what a voxel holding them should reflect.
    fn moments_and_seen_cosine(normals: &[Vec3], light: Vec3, view: Vec3) -> (Vec3, f64) {
        let (mut m, mut num, mut den) = ([0f64; 3], 0f64, 0f64);
        for n in normals {
            let n = n.normalize();
            for (k, v) in m.iter_mut().zip(n.to_array()) {
                *k += f64::from(v) * f64::from(v);
            }
            let seen = f64::from(n.dot(view).abs());
            num += seen * f64::from(n.dot(light).abs());
            den += seen;
        }
        let k = normals.len() as f64;
        let m = Vec3::new((m[0] / k) as f32, (m[1] / k) as f32, (m[2] / k) as f32);
        (m, num / den.max(1e-12))
    }

    #[test]
    fn one_flat_patch_is_lit_as_the_mesh_is_from_either_side() {
        // Exact for a patch facing along an axis, whatever the light and the view; a tilted
        // patch alone in its voxel needs the off-diagonal terms the four bytes leave out.
        let dirs = [
            Vec3::new(0.3, 1.0, 0.5).normalize(),
            Vec3::X,
            Vec3::new(-1.0, -0.2, 0.1).normalize(),
        ];
        for light in dirs {
            for view in dirs {
                for n in [Vec3::Y, Vec3::X, -Vec3::Z] {
                    let (m, _) = moments_and_seen_cosine(&[n], light, view);
                    for sign in [1.0, -1.0] {
                        let mesh = diffuse_factor(n * sign, light, 0.3);
                        let got = moments_diffuse_factor(m, light, view, 0.3, 1.0);
                        assert!((got - mesh).abs() < 1e-5, "{n}: {got} vs {mesh}");
                    }
                }
            }
        }
    }

    /// Leaves spread evenly over the sphere (a Fibonacci lattice) and leaves tilted from
    /// the vertical by 0–60°, facing either way: the shading against the f64 mean of what
    /// the mesh shows, over lights and views, ambient 0.3 — mean and worst relative error,
    /// bounded at what was measured (sphere +0.02 % / 0.11 %: the polynomial of the view
    /// factor; canopy +1.0 % / 8.7 %).
    /// Without the view factor `g` they were −3.1 % / 15.2 % and −0.2 % / 15.3 % (the
    /// view's weighting); with `√q` alone +5.0 % / 17.9 % and +4.3 % / 16.2 % (the Jensen
    /// overshoot of √E[x²]).
    #[test]
    fn spread_leaves_reflect_what_the_mesh_shows_within_the_measured_bounds() {
        let n = 1500;
        let sphere: Vec<Vec3> = (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                let r = (1.0 - z * z).sqrt();
                let phi = i as f32 * 2.399_963;
                Vec3::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect();
        let canopy: Vec<Vec3> = (0..n)
            .flat_map(|i| {
                let t = (60.0 * (i as f32 + 0.5) / n as f32).to_radians();
                let phi = i as f32 * 2.399_963;
                let v = Vec3::new(t.sin() * phi.cos(), t.cos(), t.sin() * phi.sin());
                [v, -v]
            })
            .collect();
        let dirs = [
            Vec3::Y,
            Vec3::X,
            Vec3::new(0.94, 0.34, 0.1).normalize(),
            Vec3::new(-0.94, 0.34, 0.25).normalize(),
            Vec3::ONE.normalize(),
            Vec3::new(1.0, 0.0, 1.0).normalize(),
        ];
        for (name, normals, mean_tol, worst_tol) in [
            ("sphere", &sphere, 0.001, 0.002),
            ("canopy", &canopy, 0.015, 0.09),
        ] {
            let mut errs = Vec::new();
            for light in dirs {
                for view in dirs {
                    let (m, truth) = moments_and_seen_cosine(normals, light, view);
                    let mesh = 0.3 + 0.7 * truth;
                    let got = f64::from(moments_diffuse_factor(m, light, view, 0.3, 1.0));
                    errs.push(got / mesh - 1.0);
                }
            }
            let mean = errs.iter().sum::<f64>() / errs.len() as f64;
            let worst = errs.iter().fold(0f64, |w, e| w.max(e.abs()));
            assert!(
                mean.abs() < mean_tol && worst < worst_tol,
                "{name}: {mean} {worst}"
            );
        }
        // Horizontal leaves (normals ±y): bright from above, dark from the side, as the mesh.
        let flat = [Vec3::Y, -Vec3::Y];
        let (m, _) = moments_and_seen_cosine(&flat, Vec3::Y, Vec3::Y);
        let f = |l, v| moments_diffuse_factor(m, l, v, 0.3, 1.0);
        assert!((f(Vec3::Y, Vec3::Y) - 1.0).abs() < 1e-6);
        assert!((f(Vec3::X, Vec3::Y) - 0.3).abs() < 1e-6);
    }

    #[test]
    fn normals_spread_evenly_show_what_a_viewer_sees_of_them() {
        // Over the sphere E|n·L| = ½ (√E[(n·L)²] would say 1/√3), and a viewer sees each
        // normal in proportion to |n·V|: E[|n·V||n·L|] / E|n·V| = 2/3 looking along the
        // light, 4/(3π) across it, and ½·g(γ) between (closed form in the docs).
        let m = Vec3::splat(1.0 / 3.0);
        for l in [Vec3::Y, Vec3::X, Vec3::new(0.3, 1.0, 0.5).normalize()] {
            let along = moments_diffuse_factor(m, l, l, 0.0, 1.0);
            let against = moments_diffuse_factor(m, l, -l, 0.0, 1.0);
            let across = moments_diffuse_factor(m, l, l.any_orthonormal_vector(), 0.0, 1.0);
            assert!((along - 2.0 / 3.0).abs() < 1e-5, "{l}: {along}");
            assert!((against - 2.0 / 3.0).abs() < 1e-5, "{l}: {against}");
            let want = 4.0 / (3.0 * std::f32::consts::PI);
            assert!((across - want).abs() < 1e-5, "{l}: {across}");
        }
    }

    #[test]
    fn the_view_factor_polynomial_is_within_0_18_percent_of_the_closed_form() {
        let mut worst = 0f64;
        for i in 0..=10_000 {
            let c = f64::from(i) / 10_000.0;
            let exact = 8.0 / (3.0 * std::f64::consts::PI) * ((1.0 - c * c).sqrt() + c * c.asin());
            let got = f64::from(spread_view_factor(c as f32));
            worst = worst.max((got / exact - 1.0).abs());
        }
        assert!(worst < 0.0018, "{worst}");
        let one = f64::from(spread_view_factor(1.0)) - 4.0 / 3.0;
        assert!(one.abs() < 1e-6, "{one}");
    }

    #[test]
    fn no_surface_and_bad_input_give_the_ambient_term() {
        for m in [
            Vec3::ZERO,
            Vec3::splat(f32::NAN),
            Vec3::splat(f32::INFINITY),
        ] {
            assert_eq!(
                moments_diffuse_factor(m, Vec3::Y, Vec3::Z, 0.3, 1.0),
                0.3,
                "{m}"
            );
        }
        // Shadowed: the ambient term alone too.
        assert_eq!(
            moments_diffuse_factor(Vec3::Y, Vec3::Y, Vec3::Z, 0.3, 0.0),
            0.3
        );
    }
}
