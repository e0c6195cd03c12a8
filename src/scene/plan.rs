//! The planner: from a scene (what a renderer samples and how its frames are
//! seen) to the masks that pay off, each with the reason for it.
//!
//! - The kernel follows the display: TAA -> `perceptual-taa` at its alpha and frame
//!   rate, no TAA -> `taa` with the blend whose half-life is one 60 fps frame
//!   (`no_taa_blend`, 0.5 at 60 fps: the eye's integration over frames as the
//!   judge rewards it, measured against the eye's own temporal response), a
//!   still camera (frames accumulated) -> `spatial`.
//! - The kernel's spatial filter is the eye at the scene's display (its contrast
//!   sensitivity at the display's pixels per degree; `csf.rs`), or a Gaussian
//!   the scene gives in pixels.
//! - The tile: W = H from the scene or 128; T from the scene, or twice the TAA
//!   history that carries 95% of the blend's weight rounded up to a power of two
//!   (alpha 0.1 -> 64), or a quarter second (the eye's temporal response's span) without
//!   TAA (60 fps -> 16), or 16 for a still camera.
//! - Reading: decisions of two or more dimensions read masks of pairs (vector),
//!   or a scalar mask per dimension where the scene asks (`reading = "scalar"`).
//! - Each visible group gets masks of its own, one per pair of dimensions and one
//!   for a last single dimension (a 1-D decision a scalar mask, a 2-D one a 2-D
//!   mask, a 3-D one a pair and a single): renderers consume dimensions in pairs,
//!   and a mask's quality in directions no decision reads is wasted. An invisible
//!   group reads white noise (nothing is optimized for it).
//! - A part of a decision whose dimension and spp match a mask an earlier part
//!   owns reads that mask instead of a new one, at its own pixel and frame offset
//!   and with its own toroidal shift (the k-th reader at the k-th point of the R3
//!   and R_d sequences): measured to cost nothing against masks of its own
//!   (RESULTS.md, `fsot-planned-unshared`), at none of the time. A group with
//!   `share = false` owns all its masks and lends none.
//! - A scalar mask (one dimension) takes the eye at no fewer than
//!   `SCALAR_EYE_PPD` pixels per degree, `standard_4k`'s: for a 1-D decision
//!   the judges score a mask for `standard_fhd`'s sharper eye level with one
//!   for that wider eye on `standard_fhd` itself, and the wider eye's mask
//!   leaves far less error under a wider filter (RESULTS.md, the leads).
//! - Every optimized mask starts from the animated start (one frame optimized,
//!   set in motion by a Kronecker sequence; `Start::Animated`): against white
//!   noise, the masks the plateau rule then stops score better or level by
//!   every judge in every scene measured, with TAA and without, in fewer
//!   iterations (RESULTS.md, the leads).
//! - Every optimized mask runs until further iterations no longer pay
//!   (`Until::Plateau`); the estimate of its iterations is the measured stopping
//!   point of the rule, its time a cost model: a calibration run on this machine
//!   and backend scaled by the scaling suite's factors for dimension and spp.

use std::path::{Path, PathBuf};
use crate::optimize::clock::{self, Stamp};

use serde::Serialize;

use crate::core::kernel::{KernelSpec, Spatial};
use crate::core::mask::Mask;
use crate::core::step_rule::Plateau;
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::io::atomic::AtomicFile;
use crate::optimize::run::{CancelFlag, Checkpointing, Event, Outcome, Run, RunOptions};
use crate::optimize::settings::{recorded_axis_share, Settings, Start, Until, BUDGET_SECONDS, DEFAULT_CAP};
use crate::scene::file::{Display, Reading, Scene};

/// The most parts a plan holds: the include's plan block (`FSOT_MAX_PARTS`) of
/// this many parts, 32 + 32 x this bytes, is 64 KiB. Vulkan guarantees uniform
/// blocks of 16 KiB (511 parts); a larger block needs the device's
/// `maxUniformBufferRange`.
pub const MAX_BLOCK_PARTS: usize = 2047;

/// Tile width and height when the scene does not give them.
pub const DEFAULT_SIZE: usize = 128;
/// Iterations the plateau rule took from the animated start on the measured
/// tiles (`bench/results/plateau-start.txt`: 384 to 480 on 32x32x16 `taa`,
/// 64x64x16 `perceptual`, 64x64x32 `perceptual-taa` and a 128x128x64 scalar
/// mask): the plan's estimate.
pub const EXPECTED_ITERATIONS: u32 = 450;

/// The least pixels per degree a scalar mask's eye is taken at (`standard_4k`'s,
/// an eye of about 1.8 pixels). On `standard_fhd` (38 pixels per degree, an eye
/// of about 0.9 pixels) light-pick's scalar mask for this eye scored level with
/// the one for the display's own by ColorVideoVDP, about 1% higher by FLIP and
/// 5% by pRelMSE with the display's eye, and 27% lower by pRelMSE with a Gaussian of
/// sigma 2.1 pixels, by which the sharper eye's mask is behind FAST's
/// (RESULTS.md, the leads).
pub const SCALAR_EYE_PPD: f64 = 75.4;

/// One mask file of the plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlannedMask {
    /// File name in the output folder.
    pub file: String,
    /// Dimensions per sample.
    pub dims: usize,
    /// Samples per pixel and frame.
    pub spp: usize,
    /// White noise (nothing optimized).
    pub white: bool,
    /// The mask's seed, derived from the scene's and the file's names.
    pub seed: u64,
    /// Iterations the plateau rule is expected to take (0 for white noise).
    pub estimated_iterations: u32,
    /// Seconds making the mask is expected to take, by the cost model.
    pub estimated_seconds: f64,
    /// The kernel it is optimized for, in words (`KernelSpec::describe`).
    pub kernel: String,
    /// The kernel itself (`kernel` is its description).
    #[serde(skip)]
    pub spec: KernelSpec,
}

/// What one sampling decision reads.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Part {
    /// The mask file (its own or one it shares).
    pub mask: String,
    /// The decision's dimensions this part covers, from `first`.
    pub first: usize,
    /// How many of the decision's dimensions it covers.
    pub dims: usize,
    /// Pixel and frame offset at which the decision reads the mask.
    pub offset: [u32; 3],
    /// Toroidal (Cranley-Patterson) shift per dimension.
    pub shift: Vec<f32>,
    /// The group whose mask this part reads, when an earlier part owns it (a
    /// part of another group, or of its own: a decision of several pieces of
    /// one size reads one mask at several offsets).
    pub shares: Option<String>,
    /// The kernel the mask it reads is optimized for (None: white noise).
    pub kernel: Option<String>,
}

impl Part {
    /// A read of a mask the part's group owns: at no offset, no shift.
    fn own(mask: String, first: usize, dims: usize, kernel: Option<String>) -> Self {
        Self { mask, first, dims, offset: [0; 3], shift: vec![0.0; dims], shares: None, kernel }
    }
}

/// One sampling decision's plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlannedGroup {
    /// The scene group's name.
    pub name: String,
    /// Dimensions of the decision.
    pub dims: usize,
    /// Samples per pixel and frame.
    pub spp: usize,
    /// Its parts, in dimension order.
    pub parts: Vec<Part>,
    /// Why nothing is optimized for it, when nothing is.
    pub skipped: Option<String>,
    /// Why it is planned so, in words.
    pub reason: String,
}

/// A scene's plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Plan {
    /// The scene's name.
    pub scene: String,
    /// W, H, T of every mask.
    pub tile: [usize; 3],
    /// Why the tile has that size, in words.
    pub tile_reason: String,
    /// "scalar" or "vector", and why.
    pub reading: String,
    /// Why that reading, in words.
    pub reading_reason: String,
    /// The display's kernel, described (`KernelSpec::describe`); each mask's own,
    /// whose scalar masks' eye may be wider, is `PlannedMask::kernel`.
    pub kernel: String,
    /// Why that kernel, in words.
    pub kernel_reason: String,
    /// The backend the cost model was measured on, in words.
    pub backend: String,
    /// The scene's decisions, in the order the renderer consumes them.
    pub groups: Vec<PlannedGroup>,
    /// Every mask file to make.
    pub masks: Vec<PlannedMask>,
    /// Seconds making every mask is expected to take, by the cost model.
    pub estimated_seconds: f64,
    /// How the estimates were made, in words.
    pub cost_model: String,
    /// Seconds of wall time to make every mask in (the scene's `[plan]
    /// budget`), from the start of `Plan::execute` or `RunOptions::budget_from`;
    /// None: each mask runs until iterations no longer pay.
    pub budget: Option<f64>,
}

/// Without TAA, the half-life in seconds of the exponential blend that stands for
/// the eye's integration over frames: one frame at 60 fps. On light-pick's
/// scalar mask on `standard_4k` without TAA, blends of weight 0.3, 0.5, 0.7 and 1
/// (frames alone) per 60 fps frame scored 2.004, 2.024, 2.016 and 2.015 JOD,
/// and the eye's own temporal response (`perceptual`) 1.980 (RESULTS.md, the
/// leads).
pub const NO_TAA_HALF_LIFE: f64 = 1.0 / 60.0;

/// The blend weight per frame at `fps` whose half-life is `NO_TAA_HALF_LIFE`:
/// 1 - 2^(-1 / (fps NO_TAA_HALF_LIFE)), 0.5 at 60 fps.
pub fn no_taa_blend(fps: f64) -> f64 {
    1.0 - (-1.0 / (fps * NO_TAA_HALF_LIFE)).exp2()
}

/// The kernel a display calls for, and why.
pub fn kernel_for(display: &Display) -> Result<(KernelSpec, String)> {
    let (name, why) = match (display.animated, display.taa_alpha) {
        (false, _) => (
            "spatial",
            "a still camera: frames are accumulated, each frame's error is seen alone".to_string(),
        ),
        (true, Some(a)) => ("perceptual-taa", format!("TAA (alpha {a}) then the eye at {} fps", display.fps)),
        (true, None) => (
            "taa",
            format!(
                "no TAA: the eye's integration over frames as a blend of weight {:.3} per frame at {} fps (a half-life of {:.1} ms)",
                no_taa_blend(display.fps),
                display.fps,
                1e3 * NO_TAA_HALF_LIFE
            ),
        ),
    };
    let alpha = match display.taa_alpha {
        Some(a) => a,
        None => no_taa_blend(display.fps),
    };
    let spec = KernelSpec::from_name(name, crate::core::kernel::DEFAULT_SIGMA, None, alpha, display.fps)?;
    let spec = KernelSpec { spatial: display.spatial, ..spec };
    Ok((spec, format!("{why}; the eye: {}", display.seen_on)))
}

/// The kernel of a mask of `dims` dimensions under the plan's kernel `spec`: a
/// scalar mask's eye is taken at no fewer than `SCALAR_EYE_PPD` pixels per
/// degree; an eye the scene gives as a Gaussian is kept as given.
pub fn mask_kernel(spec: KernelSpec, dims: usize) -> KernelSpec {
    match spec.spatial {
        Spatial::Display { ppd } if dims == 1 && ppd < SCALAR_EYE_PPD => {
            KernelSpec { spatial: Spatial::Display { ppd: SCALAR_EYE_PPD }, ..spec }
        }
        _ => spec,
    }
}

/// The most frames the planner gives a tile.
const MAX_PLANNED_FRAMES: usize = 256;

/// The tile's size, and why.
pub fn tile_size(scene: &Scene) -> ((usize, usize, usize), String) {
    if let Some(size) = scene.size {
        return (size, "as the scene gives it".into());
    }
    let d = &scene.display;
    let (t, why) = match (d.animated, d.taa_alpha) {
        (false, _) => (16, "a still camera: 16 frames to accumulate over".to_string()),
        (true, Some(a)) => {
            // Frames k with (1 - a)^k >= 5% carry 95% of the blend's weight
            // (ln_1p: 1 - a rounds to 1 for a tiny a).
            let frames = if a >= 1.0 { 1.0 } else { (0.05f64.ln() / (-a).ln_1p()).ceil() };
            // Twice that, so a pattern does not return within the history the
            // judge integrates: at alpha 0.1, T = 32 scored level with or up
            // to 0.06 JOD below T = 64 (RESULTS.md, the leads).
            let t = ((2.0 * frames).clamp(1.0, MAX_PLANNED_FRAMES as f64) as usize).next_power_of_two();
            let why = if 2.0 * frames > MAX_PLANNED_FRAMES as f64 {
                format!("TAA alpha {a}: more than {} frames carry 95% of the history; the most frames planned, {t}", MAX_PLANNED_FRAMES / 2)
            } else {
                format!("TAA alpha {a}: {frames} frames carry 95% of the history; twice that, rounded up to {t}")
            };
            (t, why)
        }
        (true, None) => {
            let frames = (0.25 * d.fps).ceil() as usize;
            let t = frames.clamp(1, MAX_PLANNED_FRAMES).next_power_of_two();
            (t, format!("no TAA: the eye's temporal response spans about a quarter second, {frames} frames, rounded up to {t}"))
        }
    };
    // Every mask within the values a tile holds: a mask has at most four
    // dimensions (a texel's), a visible group's at most two.
    let widest = scene
        .groups
        .iter()
        .map(|g| g.spp * g.dims.min(if g.visible { 2 } else { 4 }))
        .max()
        .unwrap_or(1)
        .max(1);
    let fits = crate::core::tile::MAX_VALUES / (DEFAULT_SIZE * DEFAULT_SIZE * widest);
    let (t, why) = match t > fits {
        // A power of two at most `fits` (which is at least 64: 64 spp x 4 dims).
        true => {
            let most = 1usize << fits.ilog2();
            (most, format!("{why}; at most {most}, so that a mask of {widest} values a pixel fits a tile"))
        }
        false => (t, why),
    };
    let wh = format!("{DEFAULT_SIZE} x {DEFAULT_SIZE} (default: the published masks' size, no repeat across a 128-pixel view)");
    ((DEFAULT_SIZE, DEFAULT_SIZE, t), format!("{wh}; T {why}"))
}

/// Per-point cost of an iteration relative to d = 2 (the scaling suite: 64x64x16,
/// `perceptual-taa`, CPU path, 2 cores; BENCHMARKS.md "How cost grows").
const DIMS_FACTOR: [f64; 8] = [0.52, 1.0, 1.04, 1.43, 2.37, 2.90, 4.28, 8.53];
/// Per-point cost relative to spp 1 (the same suite: 32x32x8, d = 2, spp 1 to 16).
const SPP_FACTOR: [(usize, f64); 5] = [(1, 1.0), (2, 0.73), (4, 0.60), (8, 0.58), (16, 0.63)];

/// Seconds per iteration: a calibration on this machine and backend, scaled by
/// the scaling suite's factors.
#[derive(Clone, Debug, PartialEq)]
pub struct CostModel {
    /// Seconds per point and iteration at d = 2, spp 1 (the calibration tile's).
    pub seconds_per_point: f64,
    /// The backend it was measured on, in words ("not measured" without a
    /// calibration).
    pub backend: String,
}

impl CostModel {
    /// Times a few iterations of a 32x32x8, d = 2 `perceptual-taa` run (after a
    /// warm-up) on the backend `options` choose; without a clock
    /// (wasm32-unknown-unknown), the model with no calibration.
    pub fn calibrate(options: &RunOptions) -> Result<Self> {
        if !clock::HAS_CLOCK {
            return Ok(Self { backend: "not measured: this platform has no clock".into(), ..Self::unmeasured() });
        }
        let tile = Tile::new(32, 32, 8, 1, 2)?;
        let mut settings = Settings::new(KernelSpec::from_name("perceptual-taa", 2.1, None, 0.1, 60.0)?, 1);
        settings.iterations = 40;
        let options = RunOptions { checkpoint: None, ..options.clone() };
        let mut run = Run::start(tile, settings, None, options)?;
        let never = CancelFlag::new();
        run.advance(8, &never, &mut |_| {})?;
        let start = Stamp::now();
        run.advance(40, &never, &mut |_| {})?;
        let seconds = start.seconds() / 32.0;
        Ok(Self { seconds_per_point: seconds / tile.points() as f64, backend: run.note().to_string() })
    }

    /// A model with no calibration (estimates of 0 s): for plans whose masks are
    /// made without asking how long they take.
    pub fn unmeasured() -> Self {
        Self { seconds_per_point: 0.0, backend: "not measured".into() }
    }

    /// An error unless the cost per point is finite and not negative: for a
    /// model whose public fields were set by hand. `Plan::new` checks its model.
    pub fn check(&self) -> Result<()> {
        match self.seconds_per_point.is_finite() && self.seconds_per_point >= 0.0 {
            true => Ok(()),
            false => Err(Error::invalid(format!(
                "a cost model's seconds per point must be finite and not negative, got {:?}",
                self.seconds_per_point
            ))),
        }
    }

    /// Estimated seconds per iteration on `tile`.
    pub fn seconds_per_iteration(&self, tile: &Tile) -> f64 {
        let d = DIMS_FACTOR[tile.dims.clamp(1, 8) - 1];
        let s = SPP_FACTOR.iter().rev().find(|(spp, _)| *spp <= tile.spp).map(|x| x.1).unwrap_or(1.0);
        self.seconds_per_point * tile.points() as f64 * d * s
    }
}

/// Whether `file` is a plain `NAME.exr`: no folder, not hidden, no drive, no NUL.
pub(crate) fn is_plain_mask_name(file: &str) -> bool {
    file.ends_with(".exr") && file.len() > 4 && !file.starts_with('.') && !file.contains(['/', '\\', ':', '\0'])
}

/// A stable seed per mask file, so a plan makes the same masks every time.
/// Where `Plan::execute` keeps the checkpoint of the mask `file` in `dir`:
/// `.NAME.ckpt` for `NAME.exr` (one `.exr` taken off, so that `a.exr` and
/// `a.exr.exr` keep checkpoints of their own).
pub fn checkpoint_path(dir: &Path, file: &str) -> PathBuf {
    dir.join(format!(".{}.ckpt", file.strip_suffix(".exr").unwrap_or(file)))
}

fn seed_of(scene: &str, file: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in scene.bytes().chain([0]).chain(file.bytes()) {
        h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The parts of a visible decision of `dims` dimensions: pairs then a single
/// (vector reading), or one per dimension (scalar reading).
fn split(dims: usize, reading: Reading) -> Vec<(usize, usize)> {
    match reading {
        Reading::Scalar => (0..dims).map(|first| (first, 1)).collect(),
        Reading::Vector => (0..dims).step_by(2).map(|first| (first, (dims - first).min(2))).collect(),
    }
}

/// The reading of a scene's decisions, and why.
pub fn reading_for(scene: &Scene) -> (Reading, String) {
    match scene.reading {
        Some(r) => (r, "as the scene gives it".into()),
        None => (
            Reading::Vector,
            "the default: masks of pairs of dimensions; judged by ColorVideoVDP a 2-D mask scores 0.04 to \
             0.49 JOD above a scalar mask per dimension in the 2-D to 4-D scenes under TAA (RESULTS.md, the leads)"
                .into(),
        ),
    }
}

/// Where the k-th extra reader (k >= 1) of a mask reads it: the k-th point of
/// the R3 sequence (Roberts' generalised golden ratio) scaled to the tile, so
/// readers' offsets stay far apart however many there are.
pub fn share_offset(k: u32, tile: [usize; 3]) -> [u32; 3] {
    let phi: f64 = 1.220_744_084_605_759_5; // x^4 = x + 1
    let mut out = [0u32; 3];
    for (j, (o, n)) in out.iter_mut().zip(tile).enumerate() {
        let a = phi.powi(-(j as i32 + 1));
        *o = (((k as f64 * a).fract() * n as f64) as u32).min(n as u32 - 1);
    }
    out
}

/// The toroidal shift of the k-th extra reader of a `dims`-dimensional mask: the
/// k-th point of the R_d sequence.
pub fn share_shift(k: u32, dims: usize) -> Vec<f32> {
    // phi_d: the positive root of x^(d+1) = x + 1.
    let mut phi = 2.0f64;
    for _ in 0..64 {
        phi = (1.0 + phi).powf(1.0 / (dims as f64 + 1.0));
    }
    // A fraction within 2^-25 of 1 would round to 1.0 in f32: kept below it.
    (0..dims).map(|j| ((k as f64 * phi.powi(-(j as i32 + 1))).fract() as f32).min(1.0 - f32::EPSILON / 2.0)).collect()
}

impl Plan {
    /// Plans a scene with the cost model `cost`.
    pub fn new(scene: &Scene, cost: &CostModel) -> Result<Self> {
        scene.check()?;
        cost.check()?;
        let (kernel, kernel_reason) = kernel_for(&scene.display)?;
        let (reading, reading_reason) = reading_for(scene);
        let ((w, h, t), tile_reason) = tile_size(scene);
        let mut groups = Vec::new();
        let mut masks: Vec<PlannedMask> = Vec::new();
        // Optimized masks other parts may read, and how many extra readers each has.
        struct Lender {
            file: String,
            group: String,
            dims: usize,
            spp: usize,
            readers: u32,
        }
        let mut lenders: Vec<Lender> = Vec::new();
        for g in &scene.groups {
            let mut parts = Vec::new();
            let (skipped, reason) = if !g.visible {
                // Masks of at most four dimensions (a texel's), as a renderer binds them.
                for first in (0..g.dims).step_by(4) {
                    let dims = (g.dims - first).min(4);
                    let file = match g.dims <= 4 {
                        true => format!("{}.exr", g.name),
                        false => format!("{}-{first}.exr", g.name),
                    };
                    masks.push(PlannedMask {
                        file: file.clone(),
                        dims,
                        spp: g.spp,
                        white: true,
                        seed: seed_of(&scene.name, &file),
                        estimated_iterations: 0,
                        estimated_seconds: 0.0,
                        kernel: "none (white noise)".into(),
                        spec: kernel,
                    });
                    parts.push(Part::own(file, first, dims, None));
                }
                (Some("not visible: white noise".to_string()), "its error is not seen directly".to_string())
            } else {
                let pieces = split(g.dims, reading);
                for &(first, dims) in &pieces {
                    let lender = lenders.iter_mut().find(|l| l.dims == dims && l.spp == g.spp && g.share);
                    if let Some(l) = lender {
                        l.readers += 1;
                        parts.push(Part {
                            mask: l.file.clone(),
                            first,
                            dims,
                            offset: share_offset(l.readers, [w, h, t]),
                            shift: share_shift(l.readers, dims),
                            shares: Some(l.group.clone()),
                            kernel: masks.iter().find(|m| m.file == l.file).map(|m| m.kernel.clone()),
                        });
                        continue;
                    }
                    let file = match pieces.len() {
                        1 => format!("{}.exr", g.name),
                        _ => format!("{}-{first}.exr", g.name),
                    };
                    let tile = Tile::new(w, h, t, g.spp, dims)?;
                    let per = cost.seconds_per_iteration(&tile);
                    let spec = mask_kernel(kernel, dims);
                    masks.push(PlannedMask {
                        file: file.clone(),
                        dims,
                        spp: g.spp,
                        white: false,
                        seed: seed_of(&scene.name, &file),
                        estimated_iterations: EXPECTED_ITERATIONS,
                        estimated_seconds: per * EXPECTED_ITERATIONS as f64,
                        kernel: spec.describe(),
                        spec,
                    });
                    if g.share {
                        lenders.push(Lender {
                            file: file.clone(),
                            group: g.name.clone(),
                            dims,
                            spp: g.spp,
                            readers: 0,
                        });
                    }
                    parts.push(Part::own(file, first, dims, Some(spec.describe())));
                }
                let what = match (g.dims, reading) {
                    (1, _) => "a 1-D decision: a scalar mask".to_string(),
                    (d, Reading::Scalar) => format!("a {d}-D decision: a scalar mask per dimension"),
                    (2, Reading::Vector) => "a 2-D decision: a 2-D mask".to_string(),
                    (d, Reading::Vector) => format!(
                        "a {d}-D decision, read in pairs as renderers consume it: a 2-D mask per pair{}",
                        if d % 2 == 1 { " and a scalar mask" } else { "" }
                    ),
                };
                // A scalar mask of its own for an eye wider than the display's.
                let wider = parts.iter().any(|p| p.shares.is_none() && p.dims == 1)
                    && mask_kernel(kernel, 1) != kernel;
                let shared: Vec<String> = parts
                    .iter()
                    .filter_map(|p| p.shares.as_ref().map(|s| format!("{} ({s}'s)", p.mask)))
                    .collect();
                let reason = match (shared.is_empty(), g.share) {
                    (true, true) => format!("{what} of its own"),
                    (true, false) => format!("{what} of its own (share = false)"),
                    (false, _) => format!(
                        "{what}, sharing {}: as good as a mask of its own, measured, at none of the time",
                        shared.join(", ")
                    ),
                };
                let reason = match wider {
                    true => format!(
                        "{reason}; scalar masks are made for the eye at {SCALAR_EYE_PPD} pixels per degree (for a 1-D decision a sharper eye is seen no better and leaves more error under a wider filter)"
                    ),
                    false => reason,
                };
                (None, reason)
            };
            groups.push(PlannedGroup {
                name: g.name.clone(),
                dims: g.dims,
                spp: g.spp,
                parts,
                skipped,
                reason,
            });
        }
        if let Some(budget) = scene.budget {
            // Under a budget each mask's share of it is its share of the work
            // per iteration, so every mask gets about as many iterations.
            let tiles: Vec<Option<Tile>> = masks
                .iter()
                .map(|m| (!m.white).then(|| Tile::new(w, h, t, m.spp, m.dims)).transpose())
                .collect::<Result<_>>()?;
            let shares = budget_shares(budget, &tiles);
            for ((m, tile), share) in masks.iter_mut().zip(&tiles).zip(shares) {
                if let Some(tile) = tile {
                    let per = cost.seconds_per_iteration(tile);
                    m.estimated_seconds = share;
                    m.estimated_iterations = if per > 0.0 { (share / per) as u32 } else { 0 };
                }
            }
        }
        let estimated_seconds = masks.iter().map(|m| m.estimated_seconds).sum();
        let cost_model = match scene.budget {
            Some(b) => format!(
                "a budget of {b} s, shared by the masks in proportion to their work per iteration; iterations at {:.3e} s per point and iteration at d = 2, measured here, times the scaling suite's factors for d and spp",
                cost.seconds_per_point
            ),
            None => format!(
                "{:.3e} s per point and iteration at d = 2, measured here, times the scaling suite's factors for d and spp; {EXPECTED_ITERATIONS} iterations each (where the plateau rule stopped on the measured tiles)",
                cost.seconds_per_point
            ),
        };
        let plan = Self {
            scene: scene.name.clone(),
            tile: [w, h, t],
            tile_reason,
            reading: match reading {
                Reading::Scalar => "scalar".into(),
                Reading::Vector => "vector".into(),
            },
            reading_reason,
            kernel: kernel.describe(),
            kernel_reason,
            backend: cost.backend.clone(),
            groups,
            masks,
            estimated_seconds,
            cost_model,
            budget: scene.budget,
        };
        plan.check()?;
        Ok(plan)
    }

    /// The settings of an optimized mask of the plan (under a budget its run
    /// ends at the time `Plan::execute` gives it).
    pub fn settings(&self, mask: &PlannedMask) -> Settings {
        let mut s = Settings::new(mask.spec, mask.seed);
        s.iterations = DEFAULT_CAP;
        s.until = Until::Plateau(Plateau::DEFAULT);
        s.start = Start::Animated;
        s
    }

    /// The tile of a mask of the plan.
    pub fn tile(&self, mask: &PlannedMask) -> Result<Tile> {
        Tile::new(self.tile[0], self.tile[1], self.tile[2], mask.spp, mask.dims)
    }

    /// An error unless the plan is one `Plan::new` could make: for a plan
    /// whose public fields were set by hand. At least one mask; each named
    /// `NAME.exr`, a plain file name (no folder, not hidden), once; each of a
    /// valid tile and kernel, of one spp, read by some part; at least one group, each
    /// with parts, at most `MAX_BLOCK_PARTS` parts in all, every part reading
    /// a mask of the plan, within its dimensions, with a shift in [0, 1) each; a
    /// budget of a millisecond to a day. `Plan::new` checks the plan it makes,
    /// `Plan::execute` and `make_plan_into_image` the plan they are given.
    pub fn check(&self) -> Result<()> {
        if self.masks.is_empty() {
            return Err(Error::invalid("a plan without masks"));
        }
        for (k, m) in self.masks.iter().enumerate() {
            if !is_plain_mask_name(&m.file) {
                return Err(Error::invalid(format!(
                    "a plan's mask file must be a plain NAME.exr, got {:?}",
                    m.file
                )));
            }
            if self.masks[..k].iter().any(|o| o.file == m.file) {
                return Err(Error::invalid(format!("a plan names the mask {} twice", m.file)));
            }
            self.tile(m)?;
            m.spec.check()?;
            if m.spp != self.masks[0].spp {
                return Err(Error::invalid(format!(
                    "a plan's masks share one spp: {} has {}, {} has {}",
                    self.masks[0].file, self.masks[0].spp, m.file, m.spp
                )));
            }
        }
        if self.groups.is_empty() {
            return Err(Error::invalid("a plan without groups"));
        }
        let parts: usize = self.groups.iter().map(|g| g.parts.len()).sum();
        if parts > MAX_BLOCK_PARTS {
            return Err(Error::invalid(format!(
                "{parts} parts (a part per mask each group reads), more than a plan block holds ({MAX_BLOCK_PARTS})"
            )));
        }
        for g in &self.groups {
            if g.parts.is_empty() {
                return Err(Error::invalid(format!("group {} reads no mask", g.name)));
            }
            for p in &g.parts {
                let mask = self.masks.iter().find(|m| m.file == p.mask).ok_or_else(|| {
                    Error::invalid(format!("group {} reads {}, which the plan does not make", g.name, p.mask))
                })?;
                if p.dims == 0 || p.dims > mask.dims || p.shift.len() != p.dims {
                    return Err(Error::invalid(format!(
                        "group {} reads {} dimensions of {} (d = {}) with {} shifts",
                        g.name,
                        p.dims,
                        p.mask,
                        mask.dims,
                        p.shift.len()
                    )));
                }
                if !p.shift.iter().all(|s| (0.0..1.0).contains(s)) {
                    return Err(Error::invalid(format!("group {}: a shift outside [0, 1): {:?}", g.name, p.shift)));
                }
            }
        }
        let read = |m: &PlannedMask| self.groups.iter().flat_map(|g| &g.parts).any(|p| p.mask == m.file);
        if let Some(m) = self.masks.iter().find(|m| !read(m)) {
            return Err(Error::invalid(format!("the plan makes {}, which no group reads", m.file)));
        }
        if let Some(b) = self.budget.filter(|b| !BUDGET_SECONDS.contains(b)) {
            return Err(Error::invalid(format!("a plan's budget must be a millisecond to a day, got {b:?} s")));
        }
        Ok(())
    }
}

/// What running a plan tells its observer.
#[derive(Debug)]
#[non_exhaustive]
pub enum PlanEvent<'a> {
    /// Mask `index` of the plan's masks starts (`iteration` when it resumes).
    Start {
        /// Index in `Plan::masks`.
        index: usize,
        /// The mask's file name.
        file: &'a str,
        /// The iteration its run starts from (0 unless it resumes).
        iteration: u32,
        /// Where its run goes, in words, and why when not where it was asked
        /// to (`Run::note`: a GPU that failed as the run started).
        backend: &'a str,
    },
    /// Its run's event.
    Run {
        /// Index in `Plan::masks`.
        index: usize,
        /// The event of the mask's run.
        event: Event<'a>,
    },
    /// It is written.
    Done {
        /// Index in `Plan::masks`.
        index: usize,
        /// The mask's file name.
        file: &'a str,
        /// Iterations its run did in all.
        iterations: u32,
        /// Seconds spent stepping its run (a step shared with other runs counts
        /// in full for each).
        seconds: f64,
    },
}

/// What a made mask took.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Made {
    /// The mask's file name.
    pub file: String,
    /// Iterations the mask took (0 for white noise).
    pub iterations: u32,
    /// Seconds spent stepping its run (0 for white noise and masks already made).
    pub seconds: f64,
}

/// The plan as a renderer reads it (`plan.json`): per group, the mask it reads
/// (its first part's), the offset and shift, the kernel, the iterations of the
/// masks it reads and the seconds making the masks it owns took.
#[derive(Serialize)]
struct PlanFile<'a> {
    scene: &'a str,
    tile: [usize; 3],
    kernel: &'a str,
    groups: Vec<GroupFile<'a>>,
}

#[derive(Serialize)]
struct GroupFile<'a> {
    name: &'a str,
    dims: usize,
    spp: usize,
    mask: &'a str,
    offset: [u32; 3],
    shift: &'a [f32],
    /// Every mask the group reads, in dimension order (more than one when split).
    parts: Vec<PartFile<'a>>,
    kernel: Option<&'a str>,
    iterations: Option<u32>,
    seconds: Option<f64>,
    skipped: Option<&'a str>,
}

/// A part as `plan.json` gives it: with `layer`, the first layer of its mask
/// where the plan's masks are stacked in one array image (`write_plan`: in the
/// order the parts first read them, T x spp layers each).
#[derive(Serialize)]
struct PartFile<'a> {
    #[serde(flatten)]
    part: &'a Part,
    layer: usize,
}

impl Plan {
    /// Makes every mask of the plan into `dir` (each written atomically), then
    /// `dir/plan.json`. The optimized masks run side by side
    /// (`Run::run_together`): on Vulkan, on one device, a batch of each in one
    /// submission; on the CPU, one after the other. Each checkpoints to
    /// `dir/.NAME.ckpt` (every `every` iterations and when cancelled); with
    /// `resume`, masks already written are kept (and checkpoints left beside
    /// them removed once the plan is made) and checkpoints are continued; a
    /// plan under a budget takes no checkpoints and refuses `resume`.
    /// Under a budget (`Plan::budget`, counted from `options.budget_from` or
    /// from this call) the runs take no checkpoints: on one device they all end
    /// at the budget's end; on the CPU each starts as the one before it ends
    /// and ends at its share of what is left of the budget.
    #[allow(clippy::too_many_arguments)]
    pub fn execute(
        &self,
        dir: &Path,
        options: &RunOptions,
        every: u32,
        resume: bool,
        cancel: &CancelFlag,
        on: &mut dyn FnMut(PlanEvent),
    ) -> Result<Outcome> {
        self.check()?;
        if every == 0 {
            return Err(Error::invalid("checkpoints every 0 iterations: give at least 1"));
        }
        if resume && self.budget.is_some() {
            return Err(Error::invalid(
                "a plan under a time budget takes no checkpoints, so there is nothing to resume: \
                 its masks are made again within the budget",
            ));
        }
        if self.budget.is_some() {
            clock::needs_clock("a plan's time budget")?;
        }
        let origin = options.budget_from.map_or_else(Stamp::now, Stamp::at);
        crate::io::atomic::make_folder(dir)?;
        let plan_file = AtomicFile::create(&dir.join("plan.json"))?;
        let mut made: Vec<Option<Made>> = vec![None; self.masks.len()];
        // The masks to make (their indices) and, by index, their files reserved;
        // the white masks with theirs.
        let mut todo: Vec<usize> = Vec::new();
        let mut whites: Vec<(usize, Tile, AtomicFile)> = Vec::new();
        let mut outs: Vec<Option<AtomicFile>> = Vec::new();
        let mut stale: Vec<std::path::PathBuf> = Vec::new();
        for (index, m) in self.masks.iter().enumerate() {
            outs.push(None);
            let path = dir.join(&m.file);
            let out = AtomicFile::create(&path)?;
            let tile = self.tile(m)?;
            if m.white {
                whites.push((index, tile, out));
                continue;
            }
            if resume {
                if let Some(done) = already_made(&path, &tile, &self.settings(m)) {
                    // Made in full: a checkpoint left beside it (of a later run
                    // of the same settings, stopped) has nothing to add; it goes
                    // once the plan is made.
                    stale.push(checkpoint_path(dir, &m.file));
                    made[index] = Some(Made { file: m.file.clone(), iterations: done, seconds: 0.0 });
                    continue;
                }
            }
            todo.push(index);
            outs[index] = Some(out);
        }
        // The device and each run's end, before any file is written.
        let runs = match todo.is_empty() {
            true => None,
            false => {
                // One Vulkan device for the plan, opened once.
                // A cancel cuts short a mask's animated start too.
                let options = RunOptions {
                    budget_from: origin.instant(),
                    cancel_start: Some(cancel.clone()),
                    ..crate::optimize::run::shared_context(options)?
                };
                let together = crate::optimize::run::shares_device(&options);
                // Each display's eye fitted now (about a tenth of a second each, once
                // per process), not out of the share of the first mask that uses it.
                for &i in &todo {
                    if let Spatial::Display { ppd } = self.masks[i].spec.spatial {
                        crate::core::csf::mixture(ppd);
                    }
                }
                let ends = self.run_ends(&todo, origin, together)?;
                Some((options, together, ends))
            }
        };
        // A plan.json of an earlier plan would describe the masks this one
        // replaces: it goes just before the first of them is written (through a
        // link, the file the link leads to, which this plan's replaces once every
        // mask is made). A run stopped before then leaves the folder as it was;
        // so does one that fails as its runs start (a checkpoint that exists or
        // does not fit): the white masks are written last.
        let mut earlier = Earlier { path: dir.join("plan.json"), gone: false };
        if let Some((options, together, ends)) = runs {
            // Side by side, or (under a budget, on the CPU) one after the other,
            // each started as the one before it ends.
            let batches: Vec<&[usize]> = match (self.budget, together) {
                (Some(_), false) => todo.chunks(1).collect(),
                _ => vec![&todo[..]],
            };
            let mut first = 0; // the place in `todo` (and `ends`) of the batch's first mask
            for batch in batches {
                let mut runs = Vec::new();
                for (&index, &end) in batch.iter().zip(&ends[first..]) {
                    let m = &self.masks[index];
                    let run = self.start_run(dir, m, end, &options, every, resume)?;
                    on(PlanEvent::Start { index, file: &m.file, iteration: run.iteration(), backend: run.note() });
                    runs.push(run);
                }
                first += batch.len();
                let outcome =
                    self.run_batch(&mut runs, batch, &mut outs, &mut made, &mut earlier, cancel, on)?;
                if let Outcome::Cancelled { .. } = outcome {
                    return Ok(outcome);
                }
            }
        }
        for (index, tile, out) in whites {
            earlier.remove()?;
            let mut mask = Mask::white(tile, self.masks[index].seed);
            mask.set_meta("version", env!("CARGO_PKG_VERSION"));
            crate::io::exr::write(&mask, out)?;
            made[index] = Some(Made { file: self.masks[index].file.clone(), iterations: 0, seconds: 0.0 });
        }
        let made: Vec<Made> = made.into_iter().flatten().collect();
        plan_file.commit(self.document(&made)?.as_bytes())?;
        for checkpoint in stale.iter().filter(|c| c.is_file()) {
            std::fs::remove_file(checkpoint)
                .map_err(|e| Error::invalid(format!("cannot remove {}: {e}", checkpoint.display())))?;
        }
        Ok(Outcome::Reached)
    }

    /// Where each run of the masks `indices` ends, in seconds from `origin`,
    /// under the plan's budget: on one device every run at its end; on the CPU
    /// each at the end of its share of what is left of it. None: no budget.
    pub(crate) fn run_ends(&self, indices: &[usize], origin: Stamp, together: bool) -> Result<Vec<Option<f64>>> {
        let Some(budget) = self.budget else { return Ok(vec![None; indices.len()]) };
        if together {
            return Ok(vec![Some(budget); indices.len()]);
        }
        let spent = origin.seconds();
        let tiles: Vec<Option<Tile>> =
            indices.iter().map(|&i| self.tile(&self.masks[i]).map(Some)).collect::<Result<_>>()?;
        let mut end = spent.max(f64::MIN_POSITIVE);
        let mut ends: Vec<Option<f64>> = budget_shares((budget - spent).max(0.0), &tiles)
            .into_iter()
            .map(|share| {
                end += share;
                // The sum of the shares may round past the budget itself.
                Some(end.min(budget))
            })
            .collect();
        // ... or short of it: the last run ends at the budget.
        if let Some(last) = ends.last_mut() {
            *last = Some(budget);
        }
        Ok(ends)
    }

    /// Starts the run of mask `m`: ending at `end` seconds from the budget's
    /// origin, or (no budget) by the plateau rule with checkpoints into `dir`.
    fn start_run(
        &self,
        dir: &Path,
        m: &PlannedMask,
        end: Option<f64>,
        options: &RunOptions,
        every: u32,
        resume: bool,
    ) -> Result<Run> {
        let mut settings = self.settings(m);
        let mut options = options.clone();
        match end {
            Some(seconds) => settings.until = Until::Seconds(seconds),
            None => {
                let path = checkpoint_path(dir, &m.file);
                let resume = resume && path.exists();
                options.checkpoint = Some(Checkpointing { path, every, resume });
            }
        }
        Run::start(self.tile(m)?, settings, None, options)
    }

    /// Runs `runs` (of the masks `batch`) side by side to their ends, writing
    /// each mask into its reserved file (`outs`, by mask index) as its run
    /// ends, so that a cancel keeps what is made.
    #[allow(clippy::too_many_arguments)]
    fn run_batch(
        &self,
        runs: &mut [Run],
        batch: &[usize],
        outs: &mut [Option<AtomicFile>],
        made: &mut [Option<Made>],
        earlier: &mut Earlier,
        cancel: &CancelFlag,
        on: &mut dyn FnMut(PlanEvent),
    ) -> Result<Outcome> {
        // (Both observers speak through `on`, never at once.)
        let on = std::cell::RefCell::new(on);
        Run::run_together(
            runs,
            cancel,
            &mut |r, event| (*on.borrow_mut())(PlanEvent::Run { index: batch[r], event }),
            &mut |r, run| {
                let index = batch[r];
                let file = &self.masks[index].file;
                // With Vulkan's validation layer on, any message means a fault: stop.
                if let Some(first) = run.report().validation_messages.first() {
                    return Err(Error::invalid(format!(
                        "the Vulkan validation layer reported, making {file}: {first}"
                    )));
                }
                let out = outs[index].take().ok_or_else(|| Error::invalid(format!("{file} ended twice")))?;
                let (iterations, seconds) = (run.iteration(), run.seconds());
                // Written before its checkpoint goes: a failed write leaves the
                // checkpoint to resume from.
                run.finish_in_place_with(|mask| {
                    earlier.remove()?;
                    crate::io::exr::write(mask, out)
                })?;
                (*on.borrow_mut())(PlanEvent::Done { index, file, iterations, seconds });
                made[index] = Some(Made { file: file.clone(), iterations, seconds });
                Ok(())
            },
        )
    }

    /// `plan.json` with what making each mask took.
    pub fn document(&self, made: &[Made]) -> Result<String> {
        self.check()?;
        let took = |file: &str| made.iter().find(|m| m.file == file);
        // The stacked image's layers: each mask in the order the parts first
        // read it (as `SamplerPlan::from_plan` stacks them), T x spp each.
        let mut stacked: Vec<(&str, usize)> = Vec::new();
        let mut next = 0;
        for p in self.groups.iter().flat_map(|g| &g.parts) {
            if !stacked.iter().any(|(m, _)| *m == p.mask) {
                stacked.push((&p.mask, next));
                if let Some(m) = self.masks.iter().find(|m| m.file == p.mask) {
                    let tile = self.tile(m)?;
                    next += tile.frames * tile.spp;
                }
            }
        }
        let layer = |mask: &str| stacked.iter().find(|(m, _)| *m == mask).map_or(0, |&(_, l)| l);
        let groups = self
            .groups
            .iter()
            .map(|g| {
                let first = &g.parts[0];
                // Each mask it reads once, however many of its parts read it.
                let mut read: Vec<&Made> = g.parts.iter().filter_map(|p| took(&p.mask)).collect();
                read.sort_by(|a, b| a.file.cmp(&b.file));
                read.dedup_by(|a, b| a.file == b.file);
                // What making it took counts once, for the group that owns the mask.
                let own: Vec<&Made> =
                    g.parts.iter().filter(|p| p.shares.is_none()).filter_map(|p| took(&p.mask)).collect();
                let optimized = g.skipped.is_none();
                GroupFile {
                    name: &g.name,
                    dims: g.dims,
                    spp: g.spp,
                    mask: &first.mask,
                    offset: first.offset,
                    shift: &first.shift,
                    parts: g.parts.iter().map(|p| PartFile { part: p, layer: layer(&p.mask) }).collect(),
                    kernel: first.kernel.as_deref().filter(|_| optimized),
                    iterations: optimized.then(|| read.iter().map(|m| m.iterations).sum()),
                    seconds: optimized.then(|| own.iter().fold(0.0, |a, m| a + m.seconds)),
                    skipped: g.skipped.as_deref(),
                }
            })
            .collect();
        let file = PlanFile { scene: &self.scene, tile: self.tile, kernel: &self.kernel, groups };
        let mut text = serde_json::to_string_pretty(&file)
            .map_err(|e| Error::invalid(format!("cannot write the plan as JSON: {e}")))?;
        text.push('\n');
        Ok(text)
    }
}

/// A budget of `seconds` shared by masks of `tiles` (None: nothing to make) in
/// proportion to their work per iteration.
fn budget_shares(seconds: f64, tiles: &[Option<Tile>]) -> Vec<f64> {
    let unit = CostModel { seconds_per_point: 1.0, backend: String::new() };
    let work: Vec<f64> = tiles.iter().map(|t| t.as_ref().map_or(0.0, |t| unit.seconds_per_iteration(t))).collect();
    let all: f64 = work.iter().sum();
    work.iter().map(|w| if all > 0.0 { seconds * w / all } else { 0.0 }).collect()
}

/// An earlier plan's `plan.json`, removed once, before the first mask of this
/// plan replaces one it describes.
struct Earlier {
    path: PathBuf,
    gone: bool,
}

impl Earlier {
    /// Removes the file, or the file it links to; nothing to remove is fine.
    fn remove(&mut self) -> Result<()> {
        if std::mem::replace(&mut self.gone, true) {
            return Ok(());
        }
        let target = std::fs::canonicalize(&self.path).unwrap_or_else(|_| self.path.clone());
        match std::fs::remove_file(&target) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                Err(Error::io(format!("removing the earlier {}", self.path.display()), e))
            }
            _ => Ok(()),
        }
    }
}

/// The iterations of a mask already written by this very plan (same tile, seed
/// and kernel), if there is one at `path`.
fn already_made(path: &Path, tile: &Tile, settings: &Settings) -> Option<u32> {
    let mask = crate::io::exr::read(path).ok()?;
    let animated = settings.start.animates(settings.until, tile);
    let same = mask.tile == *tile
        && mask.meta("budget_seconds").is_none()
        && mask.meta("seed") == Some(settings.seed.to_string().as_str())
        && mask.meta("kernel") == Some(settings.kernel.describe().as_str())
        && (mask.meta("start") == Some("animated")) == animated
        && mask.meta("axis_share").map(str::to_string) == recorded_axis_share(tile, settings);
    same.then(|| mask.meta("iterations").and_then(|i| i.parse().ok())).flatten()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::atomic::AtomicFile;
    use crate::optimize::settings::run_mask;

    #[test]
    fn a_day_s_budget_shared_by_many_masks_ends_none_of_them_past_the_day() {
        let groups: String =
            (0..7).map(|k| format!("[[group]]\nname = \"g{k}\"\ndims = {}\nshare = false\n", 1 + k % 3)).collect();
        let text = format!("[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n[plan]\nbudget = 86400\n{groups}");
        let scene = Scene::parse(&text, "day").unwrap();
        let plan = Plan::new(&scene, &CostModel { seconds_per_point: 1e-6, backend: String::new() }).unwrap();
        let all: Vec<usize> = (0..plan.masks.len()).collect();
        let ends = plan.run_ends(&all, Stamp::now(), false).unwrap();
        assert_eq!(ends.len(), plan.masks.len());
        assert!(ends.iter().all(|e| matches!(e, Some(s) if *s <= 86400.0)), "{ends:?}");
        assert_eq!(ends.last().copied().flatten(), Some(86400.0), "the last ends at the budget");
    }

    #[test]
    fn a_mask_made_with_another_axis_share_is_not_already_made() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.exr");
        let tile = Tile::new(4, 4, 2, 1, 2).unwrap();
        let plan = Settings::new(KernelSpec::named("taa").unwrap(), 3);
        let write = |s: &Settings| {
            let mask = run_mask(&tile, s, 7, 16, Mask::white(tile, 1).samples);
            crate::io::exr::write(&mask, AtomicFile::create(&path).unwrap()).unwrap();
        };
        write(&plan);
        assert_eq!(already_made(&path, &tile, &plan), Some(7));
        write(&plan.axis_share(0.85));
        assert_eq!(already_made(&path, &tile, &plan), None);
        assert_eq!(already_made(&path, &tile, &plan.axis_share(0.85)), Some(7));
        // Made under a budget: not what a run without one makes.
        let mut budgeted = run_mask(&tile, &plan, 7, 16, Mask::white(tile, 1).samples);
        budgeted.set_meta("budget_seconds", "1");
        crate::io::exr::write(&budgeted, AtomicFile::create(&path).unwrap()).unwrap();
        assert_eq!(already_made(&path, &tile, &plan), None);
    }
}
