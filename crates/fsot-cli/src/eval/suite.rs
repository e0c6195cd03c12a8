//! `fsot eval`: every method's mask rendered into every scene, with and without
//! TAA, measured by pRelMSE and RelMSE (the seed's Tables 1 and 2, for fsot) and
//! by an independent judge, ColorVideoVDP's JOD (`jod.rs`).
//!
//! Every method is measured over `seeds` masks made from different seeds (white
//! noise too), each with its own renders at their own placements; a figure is
//! the mean over seeds with its 95% interval (Student's t, `stats.rs`). A mask
//! given from outside (the published peers, `--mask`) is one mask: its interval
//! is over placements only.
//!
//! pRelMSE and RelMSE are defined in `fsot::quality::metric`. pRelMSE is
//! measured twice: with the eye of the column's sigma (the eye the `ours-*`
//! methods' masks are made for), and with the eye of the display judged on
//! (`Eye::on_display`, the eye the planned masks are made for; their scalar
//! masks take it at no fewer than 75.4 pixels per degree).

use std::path::{Path, PathBuf};

use crate::eval::anatomy::{anatomy, Anatomy};
use crate::eval::flip::Flip;
use crate::eval::jod::{Grey, Judge, DISPLAY};
use crate::eval::pictures::scene_pictures;
use crate::eval::render::{references, render, taa, MaskSampler, Read, Shot};
use crate::eval::scenes::Scene;
use crate::eval::stats::Interval;
use fsot::core::kernel::{KernelSpec, Spatial};
use fsot::core::mask::Mask;
use fsot::core::tile::Tile;
use fsot::error::{Error, Result};
use fsot::io::atomic::AtomicFile;
use fsot::optimize::settings::Settings;
use fsot::peers::fast::{FastSpec, Filter};
use fsot::peers::method::{make, Method};
use fsot::peers::swap::SwapDevice;
use fsot::quality::eye::Eye;
use fsot::quality::metric::relative_errors;
use fsot::scene::plan::{CostModel, Plan};

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
#[derive(Clone, Debug)]
pub struct EvalSize {
    pub tile: Tile,
    pub iterations: u32,
    pub passes: u32,
    pub shot: Shot,
    pub warmup: usize,
    /// Masks per method, each from its own seed (its own renders too).
    pub seeds: u32,
    /// Renders per mask, each at its own placement.
    pub renders: u32,
    pub reference_samples: usize,
    /// Also measure `fsot-planned`: each scene's plan (`crates/fsot-cli/scenes/*.toml`),
    /// every decision reading its own mask, made from the animated start until
    /// iterations no longer pay (at most ten times `iterations`).
    pub planned: bool,
    /// Also the no-TAA plan's masks (`fsot-planned` without TAA); the quick run
    /// leaves them out for time.
    pub planned_without_taa: bool,
    /// Also `fsot-planned-unshared` where a plan shares masks: the full run
    /// leaves it out for time.
    pub planned_unshared: bool,
    /// Masks `fsot-planned` makes per setting (display, TAA): 1 or `seeds`;
    /// seed k renders with mask k mod `planned_masks` at its own placement. One
    /// mask judged at every placement is how the published masks are judged
    /// (the full run); `seeds` masks add the spread between masks to the
    /// interval.
    pub planned_masks: u32,
    /// The ColorVideoVDP display models every render is judged on
    /// (`jod::DISPLAY` by default); `fsot-planned` plans for each.
    pub displays: Vec<&'static str>,
    /// Whether the plans take the evaluation's tile (`tile`'s size) instead of
    /// their own choice.
    pub plan_tile: bool,
    /// How grey frames reach ColorVideoVDP.
    pub grey: Grey,
    /// Also judge the frames after TAA by FLIP (`flip.rs`).
    pub flip: bool,
    /// Also dissect each record's error (`anatomy.rs`): its spectra and what
    /// ColorVideoVDP pools per channel and band.
    pub anatomy: bool,
    /// The TAA settings judged, `[without, with]`: a run asking for one
    /// judges half the frames (and makes only that setting's planned masks).
    pub judged: [bool; 2],
}

impl EvalSize {
    /// Small tiles, images and sample counts, for a quick run.
    pub fn quick() -> Self {
        Self {
            tile: Tile::new(32, 32, 16, 1, 2).expect("valid tile"), // ok: a constant, valid tile
            iterations: 500,
            passes: 8,
            shot: Shot { image: 64, frames: 80 },
            warmup: 48,
            seeds: 3,
            renders: 1,
            reference_samples: 256,
            planned: true,
            planned_without_taa: false,
            planned_unshared: true,
            planned_masks: 3,
            displays: vec![DISPLAY],
            plan_tile: true,
            grey: Grey::Rgb,
            flip: false,
            anatomy: false,
            judged: [true, true],
        }
    }

    pub fn full() -> Self {
        Self {
            tile: Tile::new(64, 64, 16, 1, 2).expect("valid tile"), // ok: a constant, valid tile
            iterations: 1000,
            passes: 32,
            shot: Shot { image: 96, frames: 96 },
            warmup: 48,
            seeds: 5,
            renders: 1,
            reference_samples: 1024,
            planned: true,
            planned_without_taa: true,
            planned_unshared: false,
            planned_masks: 1,
            displays: vec![DISPLAY],
            plan_tile: false,
            grey: Grey::Rgb,
            flip: false,
            anatomy: false,
            judged: [true, true],
        }
    }
}

/// One table cell: means over the seeds and the half-widths of their 95%
/// intervals.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Record {
    pub scene: String,
    pub method: String,
    /// The display it was judged on (ColorVideoVDP's name).
    pub display: String,
    pub taa: bool,
    pub sigma: f64,
    pub prelmse: f64,
    pub prelmse_ci95: f64,
    pub relmse: f64,
    pub relmse_ci95: f64,
    /// pRelMSE with the eye of the display judged on, not the column's sigma.
    pub prelmse_display: f64,
    pub prelmse_display_ci95: f64,
    /// ColorVideoVDP's JOD of the judged frames (10: no visible difference).
    pub jod: f64,
    pub jod_ci95: f64,
    /// FLIP's mean error of the judged frames (0: no difference), when asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flip: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flip_ci95: Option<f64>,
    /// Independent masks measured (1 for a mask given from outside).
    pub seeds: u32,
    /// Every placement's values, in order: placement k is drawn from the same
    /// seed for every method of a run, independently of the other placements,
    /// so two methods' values pair up placement by placement.
    pub placements: Placements,
    /// The error dissected (mean over the renders), when asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anatomy: Option<Anatomy>,
}

/// Per placement (the mean over its renders), the values a record's means
/// and intervals are made from.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Placements {
    pub prelmse: Vec<f64>,
    pub relmse: Vec<f64>,
    pub prelmse_display: Vec<f64>,
    pub jod: Vec<f64>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub flip: Vec<f64>,
}

/// What one seed's renders measured, per TAA setting (without, with): the
/// means of pRelMSE and RelMSE over its renders, per display judged the mean
/// pRelMSE with that display's eye and the mean JOD, and the anatomies when
/// asked for.
#[derive(Clone, Default)]
struct SeedValues {
    errors: [[f64; 2]; 2],
    display_errors: [Vec<f64>; 2],
    jods: [Vec<f64>; 2],
    flips: [Vec<f64>; 2],
    anatomy: [Vec<Vec<Anatomy>>; 2],
}

/// The records (per display judged, `displays` naming the judges `values`
/// hold, in order: without TAA, then with, of the settings `judged` names) of
/// a method's seeds.
fn records_of(
    scene: Scene,
    method: &str,
    sigma: f64,
    seeds: u32,
    values: &[SeedValues],
    displays: &[&str],
    judged: [bool; 2],
) -> Vec<Record> {
    let mut out = Vec::new();
    for (d, display) in displays.iter().enumerate() {
        for taa in [false, true].into_iter().filter(|&t| judged[t as usize]) {
            let k = taa as usize;
            let dissected: Vec<Anatomy> =
                values.iter().flat_map(|v| v.anatomy[k].get(d).into_iter().flatten().cloned()).collect();
            let placements = Placements {
                prelmse: values.iter().map(|v| v.errors[k][0]).collect(),
                relmse: values.iter().map(|v| v.errors[k][1]).collect(),
                prelmse_display: values.iter().map(|v| v.display_errors[k][d]).collect(),
                jod: values.iter().map(|v| v.jods[k][d]).collect(),
                flip: if values.iter().all(|v| v.flips[k].len() > d) {
                    values.iter().map(|v| v.flips[k][d]).collect()
                } else {
                    Vec::new()
                },
            };
            let (p, r) = (Interval::of(&placements.prelmse), Interval::of(&placements.relmse));
            let j = Interval::of(&placements.jod);
            let pd = Interval::of(&placements.prelmse_display);
            let flip = (!placements.flip.is_empty()).then(|| Interval::of(&placements.flip));
            out.push(Record {
                scene: scene.name().to_string(),
                method: method.to_string(),
                display: display.to_string(),
                taa,
                sigma,
                prelmse: p.mean,
                prelmse_ci95: p.ci95,
                relmse: r.mean,
                relmse_ci95: r.ci95,
                prelmse_display: pd.mean,
                prelmse_display_ci95: pd.ci95,
                jod: j.mean,
                jod_ci95: j.ci95,
                flip: flip.map(|f| f.mean),
                flip_ci95: flip.map(|f| f.ci95),
                seeds,
                placements,
                anatomy: (!dissected.is_empty()).then(|| Anatomy::mean(&dissected)),
            });
        }
    }
    out
}

/// The mask of `method` for eye sigma `sigma` made from `seed`, from `cache`
/// when made before with the same parameters.
pub fn method_mask(method: &str, sigma: f64, size: &EvalSize, cache: &Path, seed: u64) -> Result<Mask> {
    let t = size.tile;
    let fsot = |kernel: &str| -> Result<Method> {
        let mut s = Settings::new(KernelSpec::from_name(kernel, sigma, None, TAA_ALPHA, 60.0)?, seed);
        s.iterations = size.iterations;
        Ok(Method::Fsot(s))
    };
    let made_by = match method {
        "white" => Method::White,
        "fsot-spatial" => fsot("spatial")?,
        "ours-gaussian" => fsot("gaussian")?,
        "ours-taa" => fsot("taa")?,
        "ours-perceptual" => fsot("perceptual")?,
        "ours-perceptual-taa" => fsot("perceptual-taa")?,
        // STBN's energy weighs pairs of pixels, as the judge's filter
        // exp(-r^2 / sigma^2) convolved with itself does: exp(-r^2 / (2 sigma^2)),
        // STBN's exp(-r^2 / (2 s^2)) at s = sigma (its temporal sigma stays its
        // paper's 1.9 frames); vector masks by annealing.
        "stbn" => Method::Stbn { sigma, sigma_t: 1.9, passes: size.passes },
        // FAST's Gaussian exp(-r^2 / (2 s^2)) is a filter, matching the eye's
        // exp(-r^2 / sigma^2) at s = sigma / sqrt 2 (1.3435 for 1.9, as published;
        // FAST then weighs pairs by its autocorrelation).
        "fast" => Method::Fast {
            spec: FastSpec {
                spatial: Filter::Gaussian { sigma: sigma / std::f64::consts::SQRT_2 },
                ..FastSpec::default()
            },
            passes: size.passes,
        },
        other => return Err(Error::invalid(format!("unknown method `{other}`"))),
    };
    // Named by what the mask is made for: the swap peers by their energy (the
    // pixels' weights and the published FAST filters).
    let energy = match made_by {
        Method::Stbn { sigma, sigma_t, .. } => format!("-pairs{sigma}x{sigma_t}"),
        Method::Fast { .. } => "-published-filters".to_string(),
        _ => String::new(),
    };
    let name = format!(
        "mask-{method}{energy}-s{sigma}-{}x{}x{}-d{}-i{}-p{}-seed{seed}.exr",
        t.width, t.height, t.frames, t.dims, size.iterations, size.passes
    );
    let path = cache.join(name);
    if let Ok(mask) = fsot::io::exr::read(&path) {
        if mask.tile == t {
            return Ok(mask);
        }
    }
    let mask = make(&made_by, t, seed, None, &SwapDevice::Cpu, &mut |_, _| {})?.mask;
    fsot::io::atomic::make_folder(cache)?;
    fsot::io::exr::write(&mask, AtomicFile::create(&path)?)?;
    Ok(mask)
}

/// The scene files of the evaluation's scenes (`crates/fsot-cli/scenes/*.toml`).
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

/// The `fsot-planned` masks of a scene seen through `viewing` (the display's
/// eye, or a Gaussian), with TAA or not: the scene file's plan (on the
/// evaluation's tile where `size.plan_tile` says so; with `share` false, no
/// decision reads another's mask). Seeds come from `seed` and the mask's place
/// among the plan's masks of its shape, not from the scene, so masks of the
/// same settings are made once and read from `cache` by every scene.
pub fn planned_masks(
    scene: Scene,
    viewing: Spatial,
    taa: bool,
    share: bool,
    size: &EvalSize,
    cache: &Path,
    seed: u64,
) -> Result<PlannedMasks> {
    let plan = scene_plan(scene, viewing, taa, share, size)?;
    let mut out = PlannedMasks { masks: Vec::new(), reads: Vec::new(), shares: false, seconds: 0.0 };
    let cap = 10 * size.iterations;
    for (i, planned) in plan.masks.iter().enumerate() {
        let tile = plan.tile(planned)?;
        let mut planned = planned.clone();
        let same_shape =
            plan.masks[..i].iter().filter(|m| (m.dims, m.spp) == (planned.dims, planned.spp)).count();
        let key = fsot::core::rng::seed_key(
            0x9a11_0000 + (planned.dims * 1000 + planned.spp * 10 + same_shape) as u64,
        );
        planned.seed = fsot::core::rng::derive(key, seed as u32) as u64;
        let planned = &planned;
        let mut s = plan.settings(planned);
        let slug: String = s
            .kernel
            .describe()
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '.' { c } else { '_' })
            .collect();
        s.iterations = cap;
        let begins = if s.start.animates(s.until, &tile) { "animated" } else { "white" };
        let name = format!(
            "planned-{slug}-{}x{}x{}-d{}-spp{}-cap{cap}-{begins}-seed{}.exr",
            tile.width, tile.height, tile.frames, tile.dims, tile.spp, planned.seed
        );
        let path = cache.join(name);
        let cached = fsot::io::exr::read(&path).ok().filter(|m| m.tile == tile);
        let mask = match (cached, planned.white) {
            (Some(m), _) => m,
            (None, true) => Mask::white(tile, planned.seed),
            (None, false) => {
                let start = std::time::Instant::now();
                let m = fsot::optimize::run::optimize(tile, s, None)?;
                out.seconds += start.elapsed().as_secs_f64();
                fsot::io::atomic::make_folder(cache)?;
                fsot::io::exr::write(&m, AtomicFile::create(&path)?)?;
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

/// The plan of an evaluation scene's file seen through `viewing`, with TAA or not.
pub fn scene_plan(scene: Scene, viewing: Spatial, taa: bool, share: bool, size: &EvalSize) -> Result<Plan> {
    let text = SCENE_FILES
        .iter()
        .find(|(name, _)| *name == scene.name())
        .map(|s| s.1)
        .ok_or_else(|| Error::invalid(format!("no scene file for {}", scene.name())))?;
    let mut file = fsot::scene::file::Scene::parse(text, scene.name())
        .map_err(|e| Error::invalid(format!("the {} scene file: {e}", scene.name())))?;
    file.display.spatial = viewing;
    file.display.seen_on = match viewing {
        Spatial::Display { ppd } => format!("the judge's display: {ppd:.1} pixels per degree"),
        Spatial::Gaussian { sigma } => format!("the eye as a Gaussian of sigma {sigma} pixels"),
    };
    file.display.taa_alpha = taa.then_some(TAA_ALPHA);
    if size.plan_tile {
        let t = size.tile;
        file.size = Some((t.width, t.height, t.frames));
    }
    for g in &mut file.groups {
        g.share &= share;
    }
    Plan::new(&file, &CostModel::unmeasured())
}

/// Filtered references of one scene: per TAA setting, the frames after TAA
/// (or not) and what the eye sees of them; per display judged, what that
/// display's eye sees of them.
struct SceneReference {
    frames: [Vec<Vec<f64>>; 2],
    seen: [Vec<Vec<f64>>; 2],
    seen_on_display: Vec<[Vec<Vec<f64>>; 2]>,
}

/// How a scene is judged: the references, the eye, the first judged frame and
/// ColorVideoVDP on each display.
struct Judging<'a> {
    scene: Scene,
    size: &'a EvalSize,
    reference: SceneReference,
    eye: Eye,
    /// The eye of each display judged on, in the judges' order.
    display_eyes: &'a [Eye],
    start: usize,
    judges: &'a [Judge],
    /// FLIP at each display's pixels per degree, when asked for.
    flip: Option<&'a [Flip]>,
}

impl Judging<'_> {
    /// One render's pRelMSE and RelMSE in the TAA settings `judged` names
    /// (`[without, with]`), and its JOD on each of the displays `which`
    /// indexes; the frames (without and with TAA) too.
    fn measure(
        &self,
        image: Vec<Vec<f64>>,
        which: &[usize],
        judged: [bool; 2],
    ) -> Result<(SeedValues, crate::eval::pictures::Frames)> {
        let n = self.size.shot.image;
        let with_taa = taa(&image, TAA_ALPHA);
        let mut out = SeedValues::default();
        for (k, frames) in [&image, &with_taa].into_iter().enumerate().filter(|&(k, _)| judged[k]) {
            let r = &self.reference;
            let (p, rel) = relative_errors(frames, &r.frames[k], &r.seen[k], &self.eye, self.start, n);
            out.errors[k] = [p, rel];
            for &d in which {
                let eye = &self.display_eyes[d];
                let seen = &r.seen_on_display[d][k];
                out.display_errors[k].push(relative_errors(frames, &r.frames[k], seen, eye, self.start, n).0);
                let judge = &self.judges[d];
                let jod = match self.size.anatomy {
                    true => {
                        let a = anatomy(frames, &r.frames[k], self.start, n, judge)?;
                        let jod = a.jod;
                        out.anatomy[k].push(vec![a]);
                        jod
                    }
                    false => judge.jod(frames, &r.frames[k], self.start, n)?,
                };
                out.jods[k].push(jod);
                // FLIP judges the frames after TAA (a still-image metric).
                if let (Some(flips), 1) = (self.flip, k) {
                    out.flips[k].push(flips[d].judge(frames, &r.frames[k], self.start, n)?);
                }
            }
        }
        Ok((out, (image, with_taa)))
    }

    /// Every seed's values in the TAA settings `judged` names, on the
    /// displays `which` indexes: `render_with(seed index, placement seed)`
    /// gives the numbers of a render. The seeds run in parallel, each its
    /// own renders and judgments, and come back in their order (the values
    /// do not depend on the threads). The first render of the first seed is
    /// kept in `kept`.
    fn seeds(
        &self,
        seeds: u32,
        which: &[usize],
        judged: [bool; 2],
        render_with: impl Fn(u32, u64) -> Result<Vec<Vec<f64>>> + Sync,
        mut kept: Option<&mut Vec<crate::eval::pictures::Frames>>,
    ) -> Result<Vec<SeedValues>> {
        use rayon::prelude::*;
        let renders = self.size.renders.max(1);
        let keep = kept.is_some();
        let seed = |k: u32| -> Result<(SeedValues, Option<crate::eval::pictures::Frames>)> {
            let flips = if self.flip.is_some() { which.len() } else { 0 };
            let mut mean = SeedValues {
                display_errors: [vec![0.0; which.len()], vec![0.0; which.len()]],
                jods: [vec![0.0; which.len()], vec![0.0; which.len()]],
                flips: [Vec::new(), vec![0.0; flips]],
                anatomy: [vec![Vec::new(); which.len()], vec![Vec::new(); which.len()]],
                ..Default::default()
            };
            let mut first = None;
            for r in 0..renders {
                let image = render_with(k, 100 + 1000 * k as u64 + r as u64)?;
                let (v, frames) = self.measure(image, which, judged)?;
                for t in (0..2).filter(|&t| judged[t]) {
                    for (a, b) in mean.errors[t].iter_mut().zip(v.errors[t]) {
                        *a += b / renders as f64;
                    }
                    for (a, b) in mean.jods[t].iter_mut().zip(&v.jods[t]) {
                        *a += b / renders as f64;
                    }
                    for (a, b) in mean.display_errors[t].iter_mut().zip(&v.display_errors[t]) {
                        *a += b / renders as f64;
                    }
                    for (a, b) in mean.flips[t].iter_mut().zip(&v.flips[t]) {
                        *a += b / renders as f64;
                    }
                    for (a, b) in mean.anatomy[t].iter_mut().zip(&v.anatomy[t]) {
                        a.extend(b.iter().cloned());
                    }
                }
                if keep && k == 0 && r == 0 {
                    first = Some(frames);
                }
            }
            Ok((mean, first))
        };
        let done: Vec<_> = (0..seeds).into_par_iter().map(seed).collect::<Result<_>>()?;
        let mut values = Vec::with_capacity(done.len());
        for (mean, first) in done {
            if let (Some(keep), Some(frames)) = (kept.as_deref_mut(), first) {
                keep.push(frames);
            }
            values.push(mean);
        }
        Ok(values)
    }
}

/// Which methods a run measures: all of them, or those named (`fsot-planned`
/// names both planned records).
#[derive(Clone, Copy, Debug, Default)]
pub enum Only<'a> {
    #[default]
    All,
    Named(&'a [String]),
}

impl Only<'_> {
    pub fn includes(&self, method: &str) -> bool {
        match self {
            Only::All => true,
            Only::Named(names) => names.iter().any(|n| n == method),
        }
    }
}

/// Runs the evaluation of the methods `only` names (the given masks `extra`
/// among them); `log` gets a line per step.
#[allow(clippy::too_many_arguments)]
pub fn run_eval(
    size: &EvalSize,
    sigmas: &[f64],
    scenes: &[Scene],
    cache: &Path,
    pictures: Option<&Path>,
    extra: &[(String, Mask)],
    only: Only,
    mut log: impl FnMut(&str),
) -> Result<Vec<Record>> {
    let n = size.shot.image;
    let judges: Vec<Judge> =
        size.displays.iter().map(|d| Judge::new(d, 60.0, size.grey)).collect::<Result<_>>()?;
    let every: Vec<usize> = (0..judges.len()).collect();
    let ppds: Vec<f64> =
        size.displays.iter().map(|d| fsot::core::display::preset_ppd(d)).collect::<Result<_>>()?;
    let display_eyes: Vec<Eye> = ppds.iter().map(|&ppd| Eye::on_display(ppd, 60.0)).collect();
    let flips: Vec<Flip> = match size.flip {
        true => ppds.iter().map(|&ppd| Flip::at(ppd)).collect::<Result<_>>()?,
        false => Vec::new(),
    };
    for (eye, display) in display_eyes.iter().zip(&size.displays) {
        if n <= 2 * eye.margin {
            return Err(Error::invalid(format!("image {n} too small for the eye on {display}")));
        }
    }
    if size.seeds == 0 {
        return Err(Error::invalid("the evaluation needs at least one seed"));
    }
    // Placements shared unevenly between masks would count one mask's repeats
    // as independent in the interval.
    if size.planned && size.planned_masks != 1 && size.planned_masks != size.seeds {
        return Err(Error::invalid(format!(
            "fsot-planned makes 1 mask (judged at every placement) or one per seed ({}), not {}",
            size.seeds, size.planned_masks
        )));
    }
    let mut records = Vec::new();
    for &scene in scenes {
        let refs = references(scene, size.shot, size.reference_samples, Some(cache))?;
        log(&format!("reference of {} ready", scene.name()));
        for (sigma_index, &sigma) in sigmas.iter().enumerate() {
            let eye = Eye::new(sigma, 60.0);
            if n <= 2 * eye.margin {
                return Err(Error::invalid(format!("image {n} too small for the eye's sigma {sigma}")));
            }
            let start =
                display_eyes.iter().map(Eye::history).fold(size.warmup.max(eye.history()), usize::max);
            if start >= size.shot.frames {
                return Err(Error::invalid(format!(
                    "{} frames leave none to judge after {start}",
                    size.shot.frames
                )));
            }
            let taa_frames = taa(&refs, TAA_ALPHA);
            let seen_by = |eye: &Eye, frames: &Vec<Vec<f64>>| -> Vec<Vec<f64>> {
                (start..frames.len()).map(|f| eye.filter(frames, f, n)).collect()
            };
            let reference = SceneReference {
                seen: [seen_by(&eye, &refs), seen_by(&eye, &taa_frames)],
                seen_on_display: display_eyes
                    .iter()
                    .map(|e| [seen_by(e, &refs), seen_by(e, &taa_frames)])
                    .collect(),
                frames: [refs.clone(), taa_frames],
            };
            let flip = size.flip.then_some(&flips[..]);
            let judging = Judging {
                scene,
                size,
                reference,
                eye,
                display_eyes: &display_eyes,
                start,
                judges: &judges,
                flip,
            };
            // The first seed's first render of each method, for the pictures (first sigma only).
            let mut kept = Vec::new();
            let keep = pictures.is_some() && sigma_index == 0;
            let names: Vec<&str> = METHODS
                .iter()
                .copied()
                .chain(extra.iter().map(|e| e.0.as_str()))
                .filter(|m| only.includes(m))
                .collect();
            for method in names {
                let given = extra.iter().find(|e| e.0 == method).map(|e| &e.1);
                let masks: Vec<Mask> = match given {
                    Some(m) => vec![m.clone()],
                    None => (1..=size.seeds as u64)
                        .map(|seed| method_mask(method, sigma, size, cache, seed))
                        .collect::<Result<_>>()?,
                };
                let seeds = if given.is_some() { size.seeds } else { masks.len() as u32 };
                let values = judging.seeds(
                    seeds,
                    &every,
                    size.judged,
                    |k, placement| {
                        let mask = &masks[(k as usize).min(masks.len() - 1)];
                        Ok(render(scene, size.shot, &MaskSampler::new(mask, scene.dims(), placement)))
                    },
                    keep.then_some(&mut kept),
                )?;
                let made = records_of(
                    scene,
                    method,
                    sigma,
                    masks.len() as u32,
                    &values,
                    &size.displays,
                    size.judged,
                );
                for display in &size.displays {
                    let parts: Vec<String> = made
                        .iter()
                        .filter(|r| r.display == *display)
                        .map(|r| {
                            format!(
                                "{}: pRelMSE {:.4e} +- {:.1e}, JOD {:.3} +- {:.3}",
                                if r.taa { "TAA" } else { "no TAA" },
                                r.prelmse,
                                r.prelmse_ci95,
                                r.jod,
                                r.jod_ci95
                            )
                        })
                        .collect();
                    log(&format!(
                        "{} sigma {sigma} {method} on {display}: {}",
                        scene.name(),
                        parts.join("; ")
                    ));
                }
                records.extend(made);
            }
            if size.planned && only.includes("fsot-planned") {
                records.extend(planned_records(&judging, sigma, cache, &mut log)?);
            }
            if let (Some(dir), false) = (pictures, kept.is_empty()) {
                fsot::io::atomic::make_folder(dir)?;
                let r = &judging.reference;
                let refs = (&r.frames[0][..], &r.frames[1][..]);
                scene_pictures(dir, scene.name(), n, &judging.eye, refs, &kept)?;
            }
        }
    }
    Ok(records)
}

/// The records of `fsot-planned` (without and with TAA, each from its own plan,
/// and per display, each planned for that display) for one scene and sigma;
/// where the plan shares a mask between decisions, also
/// `fsot-planned-unshared`, the same plan with masks of their own, to show what
/// sharing costs.
fn planned_records(
    judging: &Judging,
    sigma: f64,
    cache: &Path,
    log: &mut impl FnMut(&str),
) -> Result<Vec<Record>> {
    let (scene, size) = (judging.scene, judging.size);
    let mut records = Vec::new();
    for (d, display) in size.displays.iter().enumerate() {
        let viewing = Spatial::Display { ppd: fsot::core::display::preset_ppd(display)? };
        let mut any_shares = false;
        for share in [true, false] {
            if !(share || any_shares && size.planned_unshared) {
                continue;
            }
            // Each TAA setting has its own plan (kernel); of each, the record of that setting.
            for (k, with_taa) in [false, true].into_iter().enumerate() {
                if !with_taa && !size.planned_without_taa || !size.judged[k] {
                    continue;
                }
                let judged = [!with_taa, with_taa];
                let planned: Vec<PlannedMasks> = (1..=size.planned_masks as u64)
                    .map(|seed| planned_masks(scene, viewing, with_taa, share, size, cache, seed))
                    .collect::<Result<_>>()?;
                any_shares |= planned[0].shares;
                let reads: Vec<Vec<Read>> = planned.iter().map(|p| p.reads()).collect();
                let values = judging.seeds(
                    size.seeds,
                    &[d],
                    judged,
                    |k, placement| {
                        Ok(render(
                            scene,
                            size.shot,
                            &MaskSampler::planned(&reads[k as usize % reads.len()], placement),
                        ))
                    },
                    None,
                )?;
                let method = if share { "fsot-planned" } else { "fsot-planned-unshared" };
                let masks = planned.len() as u32;
                let record = records_of(scene, method, sigma, masks, &values, &[display], judged).remove(0);
                let seconds: f64 = planned.iter().map(|p| p.seconds).sum();
                log(&format!(
                    "{} sigma {sigma} {method} on {display} ({}): pRelMSE {:.4e} +- {:.1e}, JOD {:.3} +- {:.3}; masks made in {seconds:.1} s{}",
                    scene.name(),
                    if with_taa { "TAA plan" } else { "no-TAA plan" },
                    record.prelmse,
                    record.prelmse_ci95,
                    record.jod,
                    record.jod_ci95,
                    if seconds == 0.0 { " (cached)" } else { "" }
                ));
                records.push(record);
            }
        }
    }
    Ok(records)
}

/// The records as JSON: a list of {"scene", "method", "taa", "sigma",
/// "prelmse", "prelmse_ci95", "relmse", "relmse_ci95", "prelmse_display",
/// "prelmse_display_ci95", "jod", "jod_ci95", "flip" and "flip_ci95" (when
/// judged), "seeds", "placements" (every placement's values, in order, by
/// the same names) and "anatomy" (when asked for)}.
pub fn to_json(records: &[Record]) -> Result<String> {
    let mut text = serde_json::to_string_pretty(records)
        .map_err(|e| Error::invalid(format!("cannot write the records as JSON: {e}")))?;
    text.push('\n');
    Ok(text)
}

/// Markdown tables laid out like the seed's Table 2: scenes x methods, per sigma
/// and TAA setting, pRelMSE as a ratio to white noise (white's absolute value
/// in its column) and ColorVideoVDP's JOD, each with the half-width of its 95%
/// interval; the best of a row is bold only where its interval does not overlap
/// the next best's.
pub fn to_markdown(records: &[Record]) -> String {
    let mut out = String::new();
    let mut sigmas: Vec<f64> = records.iter().map(|r| r.sigma).collect();
    sigmas.sort_by(|a, b| b.total_cmp(a));
    sigmas.dedup();
    let mut scenes: Vec<&str> = Vec::new();
    let mut methods: Vec<&str> = Vec::new();
    let mut displays: Vec<&str> = Vec::new();
    for r in records {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
        if !displays.contains(&r.display.as_str()) {
            displays.push(&r.display);
        }
    }
    for &display in &displays {
        for &sigma in &sigmas {
            for taa in [true, false] {
                if !records.iter().any(|r| r.taa == taa && r.sigma == sigma && r.display == display) {
                    continue;
                }
                let setting = if taa { "with TAA" } else { "without TAA" };
                let find = |scene: &str, m: &str| {
                    records.iter().find(|r| {
                        r.scene == scene
                            && r.method == m
                            && r.taa == taa
                            && r.sigma == sigma
                            && r.display == display
                    })
                };
                // Ratios to white noise where it was measured, absolute values otherwise.
                let scale = if methods.contains(&"white") {
                    "white: absolute; others: ratio to white"
                } else {
                    "absolute"
                };
                out += &format!(
                    "\n### pRelMSE on {display}, sigma {sigma}, {setting} ({scale}; +- the 95% interval)\n\n"
                );
                out += &table(
                    &scenes,
                    &methods,
                    |scene, m| {
                        let white = find(scene, "white").map(|r| r.prelmse);
                        find(scene, m).map(|r| Cell {
                            interval: Interval { mean: r.prelmse, ci95: r.prelmse_ci95 },
                            shown: Shown::Error { white },
                            placements: &r.placements.prelmse,
                        })
                    },
                    false,
                );
                out += &format!(
                    "\n### pRelMSE on {display}, the display's eye, {setting} (masks of sigma {sigma}; {scale}; +- the 95% interval)\n\n"
                );
                out += &table(
                    &scenes,
                    &methods,
                    |scene, m| {
                        let white = find(scene, "white").map(|r| r.prelmse_display);
                        find(scene, m).map(|r| Cell {
                            interval: Interval { mean: r.prelmse_display, ci95: r.prelmse_display_ci95 },
                            shown: Shown::Error { white },
                            placements: &r.placements.prelmse_display,
                        })
                    },
                    false,
                );
                out += &format!("\n### JOD on {display}, sigma {sigma}, {setting} (ColorVideoVDP; 10: no visible difference; +- the 95% interval)\n\n");
                out += &table(
                    &scenes,
                    &methods,
                    |scene, m| {
                        find(scene, m).map(|r| Cell {
                            interval: Interval { mean: r.jod, ci95: r.jod_ci95 },
                            shown: Shown::Fixed(3),
                            placements: &r.placements.jod,
                        })
                    },
                    true,
                );
                if records.iter().any(|r| r.flip.is_some() && r.display == display && r.taa == taa) {
                    out += &format!("\n### FLIP on {display}, sigma {sigma}, {setting} (mean FLIP error of the judged frames; 0: no difference; +- the 95% interval)\n\n");
                    out += &table(
                        &scenes,
                        &methods,
                        |scene, m| {
                            let r = find(scene, m)?;
                            Some(Cell {
                                interval: Interval { mean: r.flip?, ci95: r.flip_ci95? },
                                shown: Shown::Fixed(4),
                                placements: &r.placements.flip,
                            })
                        },
                        false,
                    );
                }
            }
        }
    }
    out
}

/// How a table shows a cell.
#[derive(Clone, Copy)]
enum Shown {
    /// A judge's score, at this many decimals.
    Fixed(usize),
    /// An error measure: a ratio to white noise's mean where white noise was
    /// measured (white's own cell absolute), else absolute; absolute values in
    /// scientific notation, as they span decades.
    Error { white: Option<f64> },
}

/// A table's cell: a method's interval, how it is shown, and the values per
/// placement it was made from (empty where not known).
struct Cell<'a> {
    interval: Interval,
    shown: Shown,
    placements: &'a [f64],
}

/// Whether `best` is ahead of `next` (higher when `higher_better`): placement
/// by placement where both were judged at the same placements (the 95%
/// interval of their differences clears zero), else side by side (their
/// intervals do not overlap).
fn ahead(best: &Cell, next: &Cell, higher_better: bool) -> bool {
    match Interval::difference(best.placements, next.placements) {
        Some(d) => d.sign() == Some(higher_better),
        None => !best.interval.overlaps(&next.interval),
    }
}

/// One table: a row per scene, a column per method; `cell` gives a method's
/// cell. The best (highest when `higher_better`) is bold where it is `ahead`
/// of the runner-up; with no runner-up (white noise is not ranked by an error
/// measure, whose column is its ratio to white), nothing is bold.
fn table<'a>(
    scenes: &[&str],
    methods: &[&str],
    cell: impl Fn(&str, &str) -> Option<Cell<'a>>,
    higher_better: bool,
) -> String {
    let mut out =
        format!("| scene | {} |\n| --- |{}\n", methods.join(" | "), " ---: |".repeat(methods.len()));
    for scene in scenes {
        let mut ranked: Vec<(&str, Cell)> = methods
            .iter()
            .filter(|m| **m != "white" || higher_better)
            .filter_map(|m| cell(scene, m).map(|c| (*m, c)))
            // A value that is not a number ranks nowhere (NaN would sort first).
            .filter(|(_, c)| c.interval.mean.is_finite() && c.interval.ci95.is_finite())
            .collect();
        ranked.sort_by(|a, b| {
            if higher_better {
                b.1.interval.mean.total_cmp(&a.1.interval.mean)
            } else {
                a.1.interval.mean.total_cmp(&b.1.interval.mean)
            }
        });
        let winner = match ranked.as_slice() {
            [best, next, ..] if ahead(&best.1, &next.1, higher_better) => Some(best.0),
            _ => None,
        };
        let cells: Vec<String> = methods
            .iter()
            .map(|m| match cell(scene, m) {
                None => "-".to_string(),
                Some(Cell { interval: i, shown, .. }) => {
                    let text = match shown {
                        Shown::Fixed(digits) => format!("{:.digits$} +- {:.digits$}", i.mean, i.ci95),
                        Shown::Error { white: Some(w) } if w > 0.0 && *m != "white" => {
                            format!("{:.3} +- {:.3}", i.mean / w, i.ci95 / w)
                        }
                        Shown::Error { .. } => format!("{:.3e} +- {:.1e}", i.mean, i.ci95),
                    };
                    if winner == Some(*m) {
                        format!("**{text}**")
                    } else {
                        text
                    }
                }
            })
            .collect();
        if cells.iter().all(|c| c == "-") {
            continue;
        }
        out += &format!("| {scene} | {} |\n", cells.join(" | "));
    }
    out
}

/// The records' anatomies as Markdown: per scene and TAA setting, a row per
/// method: its JOD, its error power per spatial and temporal band (a ratio to
/// white noise's where white noise was measured), and ColorVideoVDP's pooled
/// differences in the sustained and transient achromatic channels per band.
pub fn anatomy_markdown(records: &[Record]) -> String {
    use crate::eval::anatomy::{SPATIAL_EDGES, TEMPORAL_EDGES};
    let mut out = String::new();
    let mut scenes: Vec<&str> = Vec::new();
    for r in records.iter().filter(|r| r.anatomy.is_some()) {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let edges = |e: &[f64], unit: &str| -> Vec<String> {
        e.windows(2)
            .map(|w| format!("{}-{} {unit}", w[0], w[1].min(if unit == "Hz" { 30.0 } else { 0.71 })))
            .collect()
    };
    let mut displays: Vec<&str> = Vec::new();
    for r in records {
        if !displays.contains(&r.display.as_str()) {
            displays.push(&r.display);
        }
    }
    for display in displays {
        for &scene in &scenes {
            for taa in [true, false] {
                let rows: Vec<(&Record, &Anatomy)> = records
                    .iter()
                    .filter(|r| r.scene == scene && r.taa == taa && r.display == display)
                    .filter_map(|r| Some((r, r.anatomy.as_ref()?)))
                    .collect();
                let Some(&(_, first)) = rows.first() else { continue };
                let white = rows.iter().find(|(r, _)| r.method == "white").map(|&(_, a)| a.clone());
                let bands: Vec<String> =
                    first.band_frequencies.iter().map(|f| format!("{f:.2} cpd")).collect();
                let mut head = vec!["method".to_string(), "JOD".to_string()];
                head.extend(edges(&SPATIAL_EDGES, "c/px"));
                head.extend(edges(&TEMPORAL_EDGES, "Hz"));
                head.extend(bands.iter().map(|b| format!("sust. {b}")));
                head.extend(bands.iter().map(|b| format!("trans. {b}")));
                out += &format!(
                "\n### {scene} on {display}, {} (error power per band{}; ColorVideoVDP's weighted differences per band)\n\n",
                if taa { "with TAA" } else { "without TAA" },
                if white.is_some() { " as a ratio to white noise's" } else { "" }
            );
                out += &format!("| {} |\n|{}\n", head.join(" | "), " --- |".repeat(head.len()));
                for (r, a) in rows {
                    let ratio = |v: f64, w: Option<f64>| match w {
                        Some(w) if w > 0.0 => format!("{:.3}", v / w),
                        _ => format!("{v:.2e}"),
                    };
                    let mut cells = vec![r.method.clone(), format!("{:.3}", a.jod)];
                    cells.extend(
                        a.spatial
                            .iter()
                            .enumerate()
                            .map(|(k, &v)| ratio(v, white.as_ref().map(|w| w.spatial[k]))),
                    );
                    cells.extend(
                        a.temporal
                            .iter()
                            .enumerate()
                            .map(|(k, &v)| ratio(v, white.as_ref().map(|w| w.temporal[k]))),
                    );
                    for c in [0, 3] {
                        cells.extend(a.bands.get(c).into_iter().flatten().map(|v| format!("{v:.4}")));
                    }
                    out += &format!("| {} |\n", cells.join(" | "));
                }
            }
        }
    }
    out
}

/// Where the cache goes under an output folder.
pub fn cache_dir(out: &Path) -> PathBuf {
    out.join("cache")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells<'a>(values: &'a [(&'a str, f64, f64)]) -> impl Fn(&str, &str) -> Option<Cell<'a>> + 'a {
        move |_, m| {
            values.iter().find(|v| v.0 == m).map(|v| Cell {
                interval: Interval { mean: v.1, ci95: v.2 },
                shown: Shown::Fixed(2),
                placements: &[],
            })
        }
    }

    #[test]
    fn judged_at_the_same_placements_a_winner_is_bold_where_their_differences_clear_zero() {
        // Placements that move both methods alike: the intervals side by side
        // overlap, the differences (1, 0.9, 1.1) do not reach zero.
        let a: &'static [f64] = &[10.0, 20.0, 30.0];
        let b: &'static [f64] = &[9.0, 19.1, 28.9];
        let paired = |a: &'static [f64], b: &'static [f64]| {
            move |_: &str, m: &str| {
                let values: &'static [f64] = if m == "a" { a } else { b };
                Some(Cell { interval: Interval::of(values), shown: Shown::Fixed(2), placements: values })
            }
        };
        assert!(table(&["s"], &["a", "b"], paired(a, b), true).contains("**20.00 +- "));
        // Lower is better: b's errors are below a's at every placement.
        assert!(table(&["s"], &["a", "b"], paired(a, b), false).contains("**19.00 +- "));
        // Differences whose interval holds zero: nothing is bold.
        let c: &'static [f64] = &[9.0, 21.0, 29.5];
        assert!(!table(&["s"], &["a", "b"], paired(a, c), true).contains("**"));
    }

    #[test]
    fn only_a_winner_whose_interval_clears_the_runner_up_s_is_bold() {
        let apart = [("white", 5.0, 0.1), ("a", 7.0, 0.1), ("b", 6.0, 0.1)];
        assert!(table(&["s"], &["white", "a", "b"], cells(&apart), true).contains("**7.00 +- 0.10**"));
        let overlapping = [("a", 7.0, 0.6), ("b", 6.0, 0.6)];
        assert!(!table(&["s"], &["a", "b"], cells(&overlapping), true).contains("**"));
        // Lower is better for an error measure, whose ranking leaves white out.
        let errors = [("white", 1.0, 0.1), ("a", 0.5, 0.01), ("b", 0.7, 0.01)];
        assert!(table(&["s"], &["white", "a", "b"], cells(&errors), false).contains("**0.50 +- 0.01**"));
    }

    #[test]
    fn a_value_that_is_not_a_number_is_never_bold_and_ranks_nowhere() {
        let nan = [("a", 7.0, 0.1), ("b", f64::NAN, f64::NAN)];
        let t = table(&["s"], &["a", "b"], cells(&nan), true);
        assert!(!t.contains("**"), "one number has no runner-up: {t}");
        let three = [("a", 7.0, 0.1), ("b", f64::NAN, 0.1), ("c", 6.0, 0.1)];
        let t = table(&["s"], &["a", "b", "c"], cells(&three), true);
        assert!(t.contains("**7.00 +- 0.10**") && !t.contains("**NaN"), "{t}");
        let unbounded = [("a", 7.0, 0.1), ("b", 9.0, f64::INFINITY)];
        assert!(!table(&["s"], &["a", "b"], cells(&unbounded), true).contains("**"));
    }

    #[test]
    fn a_method_with_no_runner_up_is_not_bold() {
        let alone = [("white", 1.0, 0.1), ("stbn", 0.8, 0.8)];
        let t = table(&["s"], &["white", "stbn"], cells(&alone), false);
        assert!(!t.contains("**"), "{t}");
        let one = [("white", 5.0, 0.1), ("stbn", 7.0, 0.1)];
        assert!(
            table(&["s"], &["white", "stbn"], cells(&one), true).contains("**7.00 +- 0.10**"),
            "judged against white"
        );
        let missing = [("white", 5.0, 0.1)];
        assert!(!table(&["s"], &["white", "stbn"], cells(&missing), true).contains("**"));
    }
}
