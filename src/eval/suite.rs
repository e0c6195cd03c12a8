//! `fsot eval`: every method's mask rendered into every scene, with and without
//! TAA, measured by pRelMSE and RelMSE (the seed's Tables 1 and 2, for fsot).
//!
//! Definitions (per pixel p of the image interior and per frame f after the
//! warm-up; the mean over both is reported, then averaged over renders):
//! - e = I - R: the 1-spp render I minus the reference R, both after the
//!   display's TAA (moving average, alpha 0.1) in the TAA case;
//! - RelMSE = mean e^2 / (R^2 + eps);
//! - pRelMSE = mean (P e)^2 / ((P R)^2 + eps), P the perceptual filter (the eye's
//!   spatial Gaussian exp(-r^2 / sigma^2) times FovVideoVDP's temporal response,
//!   normalised to sum 1; `eye.rs`); eps = 0.01.

use std::path::{Path, PathBuf};

use crate::baselines::fast::{FastSpec, Filter};
use crate::error::{Error, Result};
use crate::eval::eye::Eye;
use crate::eval::metric::relative_errors;
use crate::eval::pictures::scene_pictures;
use crate::eval::render::{references, render, taa, MaskSampler, Read, Shot};
use crate::eval::scenes::Scene;
use crate::io::atomic::AtomicFile;
use crate::kernel::KernelSpec;
use crate::mask::Mask;
use crate::method::{make, Method};
use crate::plan::{CostModel, Plan};
use crate::problem::Tile;
use crate::settings::Settings;

pub const EPSILON: f64 = 0.01;
pub const TAA_ALPHA: f64 = 0.1;

/// The compared methods, in table order.
pub const METHODS: [&str; 8] = [
    "white",
    "fsot-spatial",
    "stbn",
    "fast",
    "ours-gaussian",
    "ours-taa",
    "ours-perceptual",
    "ours-perceptual-taa",
];

/// Sizes of an evaluation run.
#[derive(Clone, Copy, Debug)]
pub struct EvalSize {
    pub tile: Tile,
    pub iterations: u32,
    pub passes: u32,
    pub shot: Shot,
    pub warmup: usize,
    pub renders: u32,
    pub reference_samples: usize,
    /// Also measure `fsot-planned`: each scene's plan (`scenes/*.toml`), every
    /// decision reading its own mask, made until iterations no longer pay (at most
    /// ten times `iterations`).
    pub planned: bool,
}

impl EvalSize {
    /// A few minutes on 2 cores.
    pub fn quick() -> Self {
        Self {
            tile: Tile::new(32, 32, 16, 1, 2).expect("valid tile"), // ok: a constant, valid tile
            iterations: 500,
            passes: 8,
            shot: Shot { image: 64, frames: 80 },
            warmup: 48,
            renders: 3,
            reference_samples: 256,
            planned: true,
        }
    }

    pub fn full() -> Self {
        Self {
            tile: Tile::new(64, 64, 16, 1, 2).expect("valid tile"), // ok: a constant, valid tile
            iterations: 1000,
            passes: 32,
            shot: Shot { image: 96, frames: 96 },
            warmup: 48,
            renders: 3,
            reference_samples: 1024,
            planned: true,
        }
    }
}

/// One table cell.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Record {
    pub scene: String,
    pub method: String,
    pub taa: bool,
    pub sigma: f64,
    pub prelmse: f64,
    pub relmse: f64,
}

/// The mask of `method` for eye sigma `sigma`, from `cache` when made before
/// with the same parameters.
pub fn method_mask(method: &str, sigma: f64, size: &EvalSize, cache: &Path) -> Result<Mask> {
    let t = size.tile;
    let name = format!(
        "mask-{method}-s{sigma}-{}x{}x{}-d{}-i{}-p{}.exr",
        t.width, t.height, t.frames, t.dims, size.iterations, size.passes
    );
    let path = cache.join(name);
    if let Ok(mask) = crate::io::exr::read(&path) {
        if mask.tile == t {
            return Ok(mask);
        }
    }
    let seed = 1;
    let fsot = |kernel: &str| -> Result<Method> {
        let mut s = Settings::new(KernelSpec::from_name(kernel, sigma, None, TAA_ALPHA, 60.0)?, seed);
        s.iterations = size.iterations;
        Ok(Method::Fsot(s))
    };
    let method = match method {
        "white" => Method::White,
        "fsot-spatial" => fsot("spatial")?,
        "ours-gaussian" => fsot("gaussian")?,
        "ours-taa" => fsot("taa")?,
        "ours-perceptual" => fsot("perceptual")?,
        "ours-perceptual-taa" => fsot("perceptual-taa")?,
        // STBN keeps its own sigma (1.9, its paper's); vector masks by annealing.
        "stbn" => Method::Stbn { sigma: 1.9, sigma_t: 1.9, passes: size.passes },
        // FAST's Gaussian exp(-r^2 / (2 s^2)) matches the eye's exp(-r^2 /
        // sigma^2) at s = sigma / sqrt 2 (1.3435 for 1.9, as published).
        "fast" => Method::Fast {
            spec: FastSpec {
                spatial: Filter::Gaussian { sigma: sigma / std::f64::consts::SQRT_2 },
                ..FastSpec::default()
            },
            passes: size.passes,
        },
        other => return Err(Error::invalid(format!("unknown method `{other}`"))),
    };
    let mask = make(&method, t, seed, &mut |_, _| {})?.mask;
    crate::io::atomic::make_folder(cache)?;
    crate::io::exr::write(&mask, AtomicFile::create(&path)?)?;
    Ok(mask)
}

/// The scene files of the evaluation's scenes (`scenes/*.toml`).
pub const SCENE_FILES: [(&str, &str); 6] = [
    ("light-pick", include_str!("../../scenes/light-pick.toml")),
    ("soft-shadow", include_str!("../../scenes/soft-shadow.toml")),
    ("occlusion", include_str!("../../scenes/occlusion.toml")),
    ("highlight", include_str!("../../scenes/highlight.toml")),
    ("defocus-motion", include_str!("../../scenes/defocus-motion.toml")),
    ("veach-mis", include_str!("../../scenes/veach-mis.toml")),
];

/// A scene's planned masks (each file once) and the reads of its decisions.
pub struct PlannedMasks {
    pub masks: Vec<Mask>,
    /// Per part of each decision, in order: (index into `masks`, the first scene
    /// dimension it serves, the plan's offset and shift).
    pub reads: Vec<(usize, usize, [u32; 3], Vec<f32>)>,
    /// Whether some decision reads a mask another one owns.
    pub shares: bool,
    /// Seconds making them took (0 when all came from the cache).
    pub seconds: f64,
}

impl PlannedMasks {
    /// The reads, for `MaskSampler::planned`.
    pub fn reads(&self) -> Vec<Read<'_>> {
        self.reads
            .iter()
            .map(|(m, first, offset, shift)| Read {
                mask: &self.masks[*m],
                first: *first,
                offset: *offset,
                shift,
            })
            .collect()
    }
}

/// The `fsot-planned` masks of a scene for eye sigma `sigma`, with TAA or not:
/// the scene file's plan on the evaluation's tile (with `share` false, no
/// decision reads another's mask); cached like the other methods' masks.
pub fn planned_masks(
    scene: Scene,
    sigma: f64,
    taa: bool,
    share: bool,
    size: &EvalSize,
    cache: &Path,
) -> Result<PlannedMasks> {
    let text = SCENE_FILES
        .iter()
        .find(|(name, _)| *name == scene.name())
        .map(|s| s.1)
        .ok_or_else(|| Error::invalid(format!("no scene file for {}", scene.name())))?;
    let mut file = crate::scene::Scene::parse(text, scene.name())
        .map_err(|e| Error::invalid(format!("scenes/{}.toml: {e}", scene.name())))?;
    file.display.sigma = sigma;
    file.display.taa_alpha = taa.then_some(TAA_ALPHA);
    let t = size.tile;
    file.size = Some((t.width, t.height, t.frames));
    for g in &mut file.groups {
        g.share &= share;
    }
    let plan = Plan::new(&file, &CostModel::unmeasured())?;
    let mut out = PlannedMasks { masks: Vec::new(), reads: Vec::new(), shares: false, seconds: 0.0 };
    for planned in &plan.masks {
        let tile = plan.tile(planned)?;
        let name = format!(
            "planned-{}-{}-s{sigma}-{}x{}x{}-cap{}-{}",
            scene.name(),
            if taa { "taa" } else { "no-taa" },
            t.width,
            t.height,
            t.frames,
            10 * size.iterations,
            planned.file
        );
        let path = cache.join(name);
        let cached = crate::io::exr::read(&path).ok().filter(|m| m.tile == tile);
        let mask = match (cached, planned.white) {
            (Some(m), _) => m,
            (None, true) => Mask::white(tile, planned.seed),
            (None, false) => {
                let mut s = plan.settings(planned);
                s.iterations = 10 * size.iterations;
                let start = std::time::Instant::now();
                let m = crate::run::optimize(tile, s, None)?;
                out.seconds += start.elapsed().as_secs_f64();
                crate::io::atomic::make_folder(cache)?;
                crate::io::exr::write(&m, AtomicFile::create(&path)?)?;
                m
            }
        };
        out.masks.push(mask);
    }
    let mut base = 0; // the scene dimension where this group's decision starts
    for group in &plan.groups {
        for part in &group.parts {
            let index = plan
                .masks
                .iter()
                .position(|m| m.file == part.mask)
                .ok_or_else(|| Error::invalid("a part without its mask"))?;
            out.shares |= part.shares.is_some();
            out.reads.push((index, base + part.first, part.offset, part.shift.clone()));
        }
        base += group.dims;
    }
    Ok(out)
}

/// Filtered references of one scene: per TAA setting, the frames after TAA
/// (or not) and what the eye sees of them.
struct SceneReference {
    frames: [Vec<Vec<f64>>; 2],
    seen: [Vec<Vec<f64>>; 2],
}

/// Runs the evaluation; `log` gets a line per step.
pub fn run_eval(
    size: &EvalSize,
    sigmas: &[f64],
    scenes: &[Scene],
    cache: &Path,
    pictures: Option<&Path>,
    extra: &[(String, Mask)],
    mut log: impl FnMut(&str),
) -> Result<Vec<Record>> {
    let n = size.shot.image;
    let mut records = Vec::new();
    for &scene in scenes {
        let refs = references(scene, size.shot, size.reference_samples, Some(cache))?;
        log(&format!("reference of {} ready", scene.name()));
        for (sigma_index, &sigma) in sigmas.iter().enumerate() {
            let eye = Eye::new(sigma, 60.0);
            // One render per method for the pictures (first sigma only).
            let mut kept = Vec::new();
            if n <= 2 * eye.margin {
                return Err(Error::invalid(format!("image {n} too small for the eye's sigma {sigma}")));
            }
            let start = size.warmup.max(eye.history());
            let taa_frames = taa(&refs, TAA_ALPHA);
            let seen =
                |frames: &Vec<Vec<f64>>| (start..frames.len()).map(|f| eye.filter(frames, f, n)).collect();
            let reference =
                SceneReference { seen: [seen(&refs), seen(&taa_frames)], frames: [refs.clone(), taa_frames] };
            let names: Vec<&str> =
                METHODS.iter().copied().chain(extra.iter().map(|e| e.0.as_str())).collect();
            for method in names {
                let mask = match extra.iter().find(|e| e.0 == method) {
                    Some((_, m)) => m.clone(),
                    None => method_mask(method, sigma, size, cache)?,
                };
                let mut sums = [(0.0, 0.0); 2];
                for r in 0..size.renders {
                    let sampler = MaskSampler::new(&mask, scene.dims(), 100 + r as u64);
                    let image = render(scene, size.shot, &sampler);
                    let with_taa = taa(&image, TAA_ALPHA);
                    for (k, frames) in [&image, &with_taa].into_iter().enumerate() {
                        let (p, rel) =
                            relative_errors(frames, &reference.frames[k], &reference.seen[k], &eye, start, n);
                        sums[k].0 += p / size.renders as f64;
                        sums[k].1 += rel / size.renders as f64;
                    }
                    if pictures.is_some() && sigma_index == 0 && r == 0 {
                        kept.push((image, with_taa));
                    }
                }
                for (k, &(prelmse, relmse)) in sums.iter().enumerate() {
                    records.push(Record {
                        scene: scene.name().to_string(),
                        method: method.to_string(),
                        taa: k == 1,
                        sigma,
                        prelmse,
                        relmse,
                    });
                }
                log(&format!(
                    "{} sigma {sigma} {method}: pRelMSE {:.4e} (TAA {:.4e})",
                    scene.name(),
                    sums[0].0,
                    sums[1].0
                ));
            }
            if size.planned {
                records
                    .extend(planned_records(scene, sigma, size, cache, &reference, &eye, start, &mut log)?);
            }
            if let (Some(dir), false) = (pictures, kept.is_empty()) {
                crate::io::atomic::make_folder(dir)?;
                let refs = (&reference.frames[0][..], &reference.frames[1][..]);
                scene_pictures(dir, scene.name(), n, &eye, refs, &kept)?;
            }
        }
    }
    Ok(records)
}

/// The records of `fsot-planned` (without and with TAA, each from its own plan)
/// for one scene and sigma; where the plan shares a mask between decisions, also
/// `fsot-planned-unshared`, the same plan with masks of their own, to show what
/// sharing costs.
#[allow(clippy::too_many_arguments)]
fn planned_records(
    scene: Scene,
    sigma: f64,
    size: &EvalSize,
    cache: &Path,
    reference: &SceneReference,
    eye: &Eye,
    start: usize,
    log: &mut impl FnMut(&str),
) -> Result<Vec<Record>> {
    let n = size.shot.image;
    let mut records = Vec::new();
    let mut any_shares = false;
    for share in [true, false] {
        for (k, with_taa) in [false, true].into_iter().enumerate() {
            if !share && !any_shares {
                continue;
            }
            let planned = planned_masks(scene, sigma, with_taa, share, size, cache)?;
            any_shares |= planned.shares;
            let reads = planned.reads();
            let (mut prelmse, mut relmse) = (0.0, 0.0);
            for r in 0..size.renders {
                let image = render(scene, size.shot, &MaskSampler::planned(&reads, 100 + r as u64));
                let frames = if with_taa { taa(&image, TAA_ALPHA) } else { image };
                let (p, rel) =
                    relative_errors(&frames, &reference.frames[k], &reference.seen[k], eye, start, n);
                prelmse += p / size.renders as f64;
                relmse += rel / size.renders as f64;
            }
            let iterations: Vec<String> =
                planned.masks.iter().map(|m| m.meta("iterations").unwrap_or("white").to_string()).collect();
            let method = if share { "fsot-planned" } else { "fsot-planned-unshared" };
            log(&format!(
                "{} sigma {sigma} {method} ({}): pRelMSE {prelmse:.4e}; masks of {} iterations, made in {:.1} s{}",
                scene.name(),
                if with_taa { "TAA plan" } else { "no-TAA plan" },
                iterations.join(" + "),
                planned.seconds,
                if planned.seconds == 0.0 { " (cached)" } else { "" }
            ));
            records.push(Record {
                scene: scene.name().to_string(),
                method: method.to_string(),
                taa: with_taa,
                sigma,
                prelmse,
                relmse,
            });
        }
    }
    Ok(records)
}

/// The records as JSON: a list of {"scene", "method", "taa", "sigma",
/// "prelmse", "relmse"}.
pub fn to_json(records: &[Record]) -> Result<String> {
    let mut text = serde_json::to_string_pretty(records)
        .map_err(|e| Error::invalid(format!("cannot write the records as JSON: {e}")))?;
    text.push('\n');
    Ok(text)
}

/// Markdown tables laid out like the seed's Table 2: scenes x methods, one
/// table per sigma and TAA setting, pRelMSE as a ratio to white noise (white's
/// absolute value in its column), the best of each row in bold.
pub fn to_markdown(records: &[Record]) -> String {
    let mut out = String::new();
    let mut sigmas: Vec<f64> = records.iter().map(|r| r.sigma).collect();
    sigmas.sort_by(|a, b| b.total_cmp(a));
    sigmas.dedup();
    let mut scenes: Vec<&str> = Vec::new();
    let mut methods: Vec<&str> = Vec::new();
    for r in records {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    for &sigma in &sigmas {
        for taa in [true, false] {
            out += &format!(
                "\n### pRelMSE, sigma {sigma}, {} (white: absolute; others: ratio to white)\n\n",
                if taa { "with TAA" } else { "without TAA" }
            );
            out += &format!("| scene | {} |\n", methods.join(" | "));
            out += &format!("| --- |{}\n", " ---: |".repeat(methods.len()));
            for scene in &scenes {
                let get = |m: &str| {
                    records
                        .iter()
                        .find(|r| r.scene == *scene && r.method == m && r.taa == taa && r.sigma == sigma)
                };
                let Some(white) = get("white") else { continue };
                let best = methods
                    .iter()
                    .filter(|m| **m != "white")
                    .filter_map(|m| get(m).map(|r| r.prelmse))
                    .fold(f64::INFINITY, f64::min);
                let cells: Vec<String> = methods
                    .iter()
                    .map(|m| match get(m) {
                        Some(r) if *m == "white" => format!("{:.3e}", r.prelmse),
                        Some(r) if r.prelmse == best => format!("**{:.3}**", r.prelmse / white.prelmse),
                        Some(r) => format!("{:.3}", r.prelmse / white.prelmse),
                        None => "-".to_string(),
                    })
                    .collect();
                out += &format!("| {scene} | {} |\n", cells.join(" | "));
            }
        }
    }
    out
}

/// Where the cache goes under an output folder.
pub fn cache_dir(out: &Path) -> PathBuf {
    out.join("cache")
}
