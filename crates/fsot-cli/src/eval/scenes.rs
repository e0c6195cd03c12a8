//! Procedural animated scenes for the evaluation: analytic geometry, no assets.
//! Each pixel of each frame is an integral over the unit cube of the scene's
//! dimension (1 to 4): `shade` is the one-sample estimator the renderer runs with
//! a mask's numbers, and its mean over the cube is the pixel's value.
//!
//! The image is a top view of the unit square (pixel centre (x + 0.5) / n), or a
//! camera looking at it; objects and lights move with the frame number.

use glam::DVec3;
use std::f64::consts::TAU;

/// The scenes, with the dimension of their integrands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scene {
    /// 1-D: two lights, one picked per sample with a probability that varies
    /// over the image and the frames (light selection).
    LightPick,
    /// 2-D: soft shadow of a square area light, a sphere moving over the ground.
    SoftShadow,
    /// 2-D: ambient occlusion of the ground under three moving spheres.
    Occlusion,
    /// 2-D: a glossy ground reflecting a moving disc light, BSDF sampling.
    Highlight,
    /// 3-D: thin-lens defocus (2) and motion blur over the shutter (1): a moving
    /// disc in front of an out-of-focus checkerboard.
    DefocusMotion,
    /// 4-D: the Veach MIS scene: four glossy plates from sharp to rough, four
    /// spherical lights from small to large, light and BSDF sampling combined by
    /// the balance heuristic.
    VeachMis,
}

/// Frames per cycle of the scenes' motion: objects move by at most about a
/// pixel per frame at 128 pixels (TAA here has no reprojection, so faster motion
/// would measure ghosting more than sampling).
pub const CYCLE: f64 = 256.0;

pub const SCENES: [Scene; 6] = [
    Scene::LightPick,
    Scene::SoftShadow,
    Scene::Occlusion,
    Scene::Highlight,
    Scene::DefocusMotion,
    Scene::VeachMis,
];

impl Scene {
    pub fn name(&self) -> &'static str {
        match self {
            Scene::LightPick => "light-pick",
            Scene::SoftShadow => "soft-shadow",
            Scene::Occlusion => "occlusion",
            Scene::Highlight => "highlight",
            Scene::DefocusMotion => "defocus-motion",
            Scene::VeachMis => "veach-mis",
        }
    }

    pub fn dims(&self) -> usize {
        match self {
            Scene::LightPick => 1,
            Scene::SoftShadow | Scene::Occlusion | Scene::Highlight => 2,
            Scene::DefocusMotion => 3,
            Scene::VeachMis => 4,
        }
    }

    /// One sample of pixel (px, py) in [0, 1)^2 at frame f, numbers u in [0, 1)^dims.
    pub fn shade(&self, px: f64, py: f64, f: f64, u: &[f64]) -> f64 {
        let phase = f / CYCLE; // one cycle of the animation every CYCLE frames
        match self {
            Scene::LightPick => light_pick(px, py, phase, u[0]),
            Scene::SoftShadow => soft_shadow(px, py, phase, u),
            Scene::Occlusion => occlusion(px, py, phase, u),
            Scene::Highlight => highlight(px, py, phase, u),
            Scene::DefocusMotion => defocus_motion(px, py, f, u),
            Scene::VeachMis => veach(px, py, phase, u, Strategies::Mis),
        }
    }
}

fn light_pick(x: f64, y: f64, phase: f64, u: f64) -> f64 {
    let a = 0.6 + 0.4 * (TAU * (x + 0.3 * phase)).sin();
    let b = 0.5 + 0.5 * (TAU * (y - 0.5 * phase) + 1.0).cos();
    // Selection probability of light A: smooth, not proportional to a (so the
    // estimator has variance), moving.
    let p = 0.5 + 0.35 * (TAU * (x + y) * 1.5 + TAU * phase).sin();
    if u < p {
        a / p
    } else {
        b / (1.0 - p)
    }
}

/// Distance along the ray (o, d), |d| = 1, to a sphere, if hit in (0, max).
fn hit_sphere(o: DVec3, d: DVec3, centre: DVec3, radius: f64, max: f64) -> Option<f64> {
    let oc = o - centre;
    let b = oc.dot(d);
    let c = oc.length_squared() - radius * radius;
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let t = if -b - s > 1e-9 { -b - s } else { -b + s };
    (t > 1e-9 && t < max).then_some(t)
}

fn soft_shadow(x: f64, y: f64, phase: f64, u: &[f64]) -> f64 {
    let p = DVec3::new(x, y, 0.0);
    let centre = DVec3::new(0.5 + 0.1 * (TAU * phase).cos(), 0.5, 1.0);
    let size = 0.35;
    let l = centre + DVec3::new((u[0] - 0.5) * size, (u[1] - 0.5) * size, 0.0);
    let to = l - p;
    let dist2 = to.length_squared();
    let d = to / dist2.sqrt();
    let occluder = DVec3::new(0.5 + 0.22 * (TAU * phase).sin(), 0.5 + 0.22 * (TAU * phase).cos(), 0.3);
    if hit_sphere(p, d, occluder, 0.12, dist2.sqrt()).is_some() {
        return 0.0;
    }
    // cos at the ground x cos at the light / r^2 x area, scaled to about 1.
    d.z * d.z / dist2 * size * size * 8.0
}

/// A cosine-weighted direction around +z.
fn cosine_dir(u0: f64, u1: f64) -> DVec3 {
    let r = u0.sqrt();
    let phi = TAU * u1;
    DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u0).max(0.0).sqrt())
}

fn occlusion(x: f64, y: f64, phase: f64, u: &[f64]) -> f64 {
    let p = DVec3::new(x, y, 0.0);
    let d = cosine_dir(u[0], u[1]);
    let spheres = [
        (DVec3::new(0.3 + 0.1 * (TAU * phase).sin(), 0.35, 0.12), 0.12),
        (DVec3::new(0.7, 0.4 + 0.15 * (TAU * phase).cos(), 0.08), 0.08),
        (DVec3::new(0.5 + 0.25 * (TAU * phase).cos(), 0.72, 0.15), 0.15),
    ];
    let occluded = spheres.iter().any(|&(c, r)| hit_sphere(p, d, c, r, 0.4).is_some());
    if occluded {
        0.0
    } else {
        1.0
    }
}

/// Reflection of v about n (both unit).
fn reflect(v: DVec3, n: DVec3) -> DVec3 {
    2.0 * v.dot(n) * n - v
}

/// An orthonormal basis around unit w.
fn basis(w: DVec3) -> (DVec3, DVec3) {
    let a = if w.x.abs() > 0.9 { DVec3::Y } else { DVec3::X };
    let t = w.cross(a).normalize();
    (t, w.cross(t))
}

/// A direction in the Phong lobe cos^e around axis w, and its density.
fn phong_dir(w: DVec3, e: f64, u0: f64, u1: f64) -> DVec3 {
    let c = u0.powf(1.0 / (e + 1.0));
    let s = (1.0 - c * c).max(0.0).sqrt();
    let phi = TAU * u1;
    let (t, b) = basis(w);
    (t * (s * phi.cos()) + b * (s * phi.sin()) + w * c).normalize()
}

fn phong_pdf(w: DVec3, e: f64, d: DVec3) -> f64 {
    let c = w.dot(d).max(0.0);
    (e + 1.0) / TAU * c.powf(e)
}

const CAMERA: DVec3 = DVec3::new(0.5, -0.6, 1.2);
/// Centre of the Veach scene's row of lights.
const LIGHT_ROW: DVec3 = DVec3::new(0.5, 1.4, 0.7);

fn highlight(x: f64, y: f64, phase: f64, u: &[f64]) -> f64 {
    let p = DVec3::new(x, y, 0.0);
    let v = (CAMERA - p).normalize();
    let r = reflect(v, DVec3::Z);
    let e = 60.0;
    let d = phong_dir(r, e, u[0], u[1]);
    if d.z <= 0.0 {
        return 0.0;
    }
    // A disc light facing down at height 0.8, moving along x.
    let centre = DVec3::new(0.5 + 0.3 * (TAU * phase).sin(), 1.3, 0.8);
    let t = (centre.z - p.z) / d.z;
    let hit = p + d * t;
    let inside = (hit - centre).length_squared() < 0.12 * 0.12;
    // Phong BRDF x cos / pdf = (e + 2) / (e + 1) x cos for lobe sampling.
    if inside {
        4.0 * (e + 2.0) / (e + 1.0) * d.z
    } else {
        0.05 * d.z
    }
}

fn defocus_motion(x: f64, y: f64, f: f64, u: &[f64]) -> f64 {
    // Lens sample (polar), radius 0.04 in image units.
    let r = 0.04 * u[0].sqrt();
    let (ls, lc) = (TAU * u[1]).sin_cos();
    let (lx, ly) = (r * lc, r * ls);
    // Shutter: the disc moves during the frame.
    let t = f + u[2];
    let disc = (0.5 + 0.3 * (TAU * t / CYCLE).sin(), 0.5 + 0.1 * (TAU * 2.0 * t / CYCLE).cos());
    // The disc is in focus (no lens offset); the background is at twice the
    // focus distance (offset scaled by 1 - 2 = -1).
    let (dx, dy) = (x - disc.0, y - disc.1);
    if dx * dx + dy * dy < 0.15 * 0.15 {
        let stripes = ((dx * 40.0).sin() > 0.0) as u8 as f64;
        return 0.3 + 0.7 * stripes;
    }
    let (bx, by) = (x - lx, y - ly);
    let checker = (((bx * 12.0).floor() + (by * 12.0).floor()) as i64).rem_euclid(2) as f64;
    0.1 + 0.8 * checker
}

/// The Veach MIS scene: four plates (horizontal bands of the image) with Phong
/// exponents from sharp to rough, four spherical lights of growing radius and
/// falling radiance (equal power) above the far edge.
/// Which sampling strategies the Veach scene's estimator runs.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Strategies {
    Mis,
    LightOnly,
    BsdfOnly,
}

fn veach(x: f64, y: f64, phase: f64, u: &[f64], strategies: Strategies) -> f64 {
    const EXPONENTS: [f64; 4] = [2000.0, 300.0, 60.0, 12.0];
    const RADII: [f64; 4] = [0.01, 0.03, 0.08, 0.16];
    let plate = ((y * 4.0) as usize).min(3);
    let e = EXPONENTS[plate];
    let p = DVec3::new(x, y, 0.0);
    // Each plate is tilted (as in Veach's scene) so that it mirrors the middle
    // of the light row towards the camera at its centre: normal = half vector.
    let middle = DVec3::new(0.5, (plate as f64 + 0.5) / 4.0, 0.0);
    let n = ((CAMERA - middle).normalize() + (LIGHT_ROW - middle).normalize()).normalize();
    let v = (CAMERA - p).normalize();
    let r = reflect(v, n);
    let lights: [(DVec3, f64, f64); 4] = std::array::from_fn(|i| {
        let cx = 0.2 + 0.2 * i as f64 + 0.05 * (TAU * phase + i as f64).sin();
        (DVec3::new(cx, LIGHT_ROW.y, LIGHT_ROW.z), RADII[i], 0.01 / (RADII[i] * RADII[i]))
    });
    // Radiance along direction d from p (the first light it hits), and the
    // light-sampling density of d: uniform choice of a light times its cone
    // density, summed over every light whose cone holds d (cones may overlap).
    let trace = |d: DVec3| -> (f64, f64) {
        let mut best: Option<(f64, usize)> = None;
        let mut density = 0.0;
        for (i, &(c, rad, _)) in lights.iter().enumerate() {
            if let Some(t) = hit_sphere(p, d, c, rad, f64::MAX) {
                if best.is_none_or(|b| t < b.0) {
                    best = Some((t, i));
                }
                density += 0.25 * cone_pdf(p, c, rad);
            }
        }
        match best {
            Some((_, i)) => (lights[i].2, density),
            None => (0.0, 0.0),
        }
    };
    let brdf = |d: DVec3| (e + 2.0) / TAU * r.dot(d).max(0.0).powf(e);
    // Balance-heuristic weight of a strategy with density `a` beside `b`.
    let weight = |a: f64, b: f64| match strategies {
        Strategies::Mis => a / (a + b),
        _ => 1.0,
    };
    let mut total = 0.0;
    // Light sampling: u0 picks a light and is reused within its stratum.
    let pick = ((u[0] * 4.0) as usize).min(3);
    let u0 = u[0] * 4.0 - pick as f64;
    let (c, rad, _) = lights[pick];
    let dl = cone_dir(p, c, rad, u0, u[1]);
    if dl.dot(n) > 0.0 && strategies != Strategies::BsdfOnly {
        let (le, pl) = trace(dl);
        if le > 0.0 && pl > 0.0 {
            total += brdf(dl) * le * dl.dot(n) / pl * weight(pl, phong_pdf(r, e, dl));
        }
    }
    // BSDF sampling.
    let db = phong_dir(r, e, u[2], u[3]);
    if db.dot(n) > 0.0 && strategies != Strategies::LightOnly {
        let (le, pl) = trace(db);
        let pb = phong_pdf(r, e, db);
        if le > 0.0 && pb > 0.0 {
            total += brdf(db) * le * db.dot(n) / pb * weight(pb, pl);
        }
    }
    total
}

/// Uniform direction in the cone from p subtended by the sphere (c, r).
fn cone_dir(p: DVec3, c: DVec3, r: f64, u0: f64, u1: f64) -> DVec3 {
    let to = c - p;
    let dist2 = to.length_squared();
    let cos_max = (1.0 - r * r / dist2).max(0.0).sqrt();
    let cos = 1.0 - u0 * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let w = to / dist2.sqrt();
    let (t, b) = basis(w);
    let phi = TAU * u1;
    (t * (sin * phi.cos()) + b * (sin * phi.sin()) + w * cos).normalize()
}

fn cone_pdf(p: DVec3, c: DVec3, r: f64) -> f64 {
    let dist2 = (c - p).length_squared();
    let cos_max = (1.0 - r * r / dist2).max(0.0).sqrt();
    1.0 / (TAU * (1.0 - cos_max)).max(1e-300)
}

/// Mean of the scene's estimator over the cube by a stratified rule of about
/// `m` samples: jittered grids per pair of dimensions, the pairs' strata
/// matched by a random permutation (padding), from the deterministic `stream`.
pub fn reference(
    scene: Scene,
    px: f64,
    py: f64,
    f: f64,
    m: usize,
    stream: &mut fsot::core::rng::Stream,
) -> f64 {
    let dims = scene.dims();
    let k = (m as f64).sqrt().round().max(1.0) as usize;
    let n = k * k;
    // For each pair of dimensions, a jittered k x k grid in a random order.
    let pairs = dims.div_ceil(2);
    let mut points = vec![[0.0f64; 4]; n];
    for pair in 0..pairs {
        let mut order: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            order.swap(i, stream.below(i as u32 + 1) as usize);
        }
        for (s, &cell) in order.iter().enumerate() {
            let (cx, cy) = (cell % k, cell / k);
            points[s][2 * pair] = (cx as f64 + stream.next_f64()) / k as f64;
            if 2 * pair + 1 < 4 {
                points[s][2 * pair + 1] = (cy as f64 + stream.next_f64()) / k as f64;
            }
        }
    }
    points.iter().map(|u| scene.shade(px, py, f, &u[..dims])).sum::<f64>() / n as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_pick_is_unbiased_in_closed_form() {
        // Its mean over u is a + b exactly; the stratified reference agrees.
        let (x, y, f) = (0.3, 0.7, 5.0);
        let phase = f / CYCLE;
        let a = 0.6 + 0.4 * (TAU * (x + 0.3 * phase)).sin();
        let b = 0.5 + 0.5 * (TAU * (y - 0.5 * phase) + 1.0).cos();
        let mut s = fsot::core::rng::Stream::new(1);
        let r = reference(Scene::LightPick, x, y, f, 4096, &mut s);
        assert!((r - (a + b)).abs() < 2e-3, "{r} vs {}", a + b);
    }

    #[test]
    fn occlusion_without_occluders_nearby_is_one_and_cosine_dirs_are_unit() {
        for (u0, u1) in [(0.0, 0.0), (0.5, 0.25), (0.999, 0.9)] {
            assert!((cosine_dir(u0, u1).length() - 1.0).abs() < 1e-12);
        }
        let mut s = fsot::core::rng::Stream::new(2);
        // A corner far from the three spheres: nothing occludes.
        assert_eq!(reference(Scene::Occlusion, 0.02, 0.98, 0.0, 256, &mut s), 1.0);
    }

    #[test]
    fn phong_sampling_density_integrates_to_one() {
        // Monte Carlo over the sphere of directions: mean of pdf / (1 / 4 pi).
        let w = DVec3::new(0.3, 0.2, 0.9).normalize();
        let mut s = fsot::core::rng::Stream::new(3);
        let n = 200_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let z = 1.0 - 2.0 * s.next_f64();
            let phi = TAU * s.next_f64();
            let r = (1.0 - z * z).sqrt();
            let d = DVec3::new(r * phi.cos(), r * phi.sin(), z);
            sum += phong_pdf(w, 20.0, d) * 2.0 * TAU;
        }
        assert!((sum / n as f64 - 1.0).abs() < 0.02, "{}", sum / n as f64);
    }

    #[test]
    fn veach_mis_strategies_agree_so_the_densities_are_right() {
        // Light sampling alone, BSDF sampling alone and their MIS combination
        // estimate the same integral; they agree only if both densities (cone
        // and Phong lobe) and the weights are right. Plates 1 to 3 (plate 0's
        // 2000 lobe makes BSDF-only sampling of the small light too noisy).
        let n = 400_000;
        for y in [0.3, 0.6, 0.9] {
            let mut means = [0.0; 3];
            for (k, strategies) in
                [Strategies::Mis, Strategies::LightOnly, Strategies::BsdfOnly].into_iter().enumerate()
            {
                let mut s = fsot::core::rng::Stream::new(40 + k as u32);
                let mut sum = 0.0;
                for _ in 0..n {
                    let u = [s.next_f64(), s.next_f64(), s.next_f64(), s.next_f64()];
                    sum += veach(0.45, y, 0.1, &u, strategies);
                }
                means[k] = sum / n as f64;
            }
            assert!(means[0] > 0.01, "plate at y = {y} unlit: {means:?}");
            for m in &means[1..] {
                assert!((m - means[0]).abs() < 0.05 * means[0], "y = {y}: {means:?}");
            }
        }
    }
}
