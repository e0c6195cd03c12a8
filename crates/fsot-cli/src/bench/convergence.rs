//! Error against run time and iterations, per backend, on one problem and seed:
//! checkpoints of one run (its schedule planned for the last checkpoint), each
//! judged by `fsot score`'s objective (ratio to white noise), by the
//! independent perceived-error test (`quality::perceived`), and by the pRelMSE
//! of one evaluation scene under TAA (ratio to the mean of four white-noise
//! masks). Time counts the
//! optimisation only; judging is done with the clock stopped.

use std::path::Path;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::eval::render::{references, render, taa, MaskSampler, Shot};
use crate::eval::scenes::Scene;
use fsot::core::kernel::KernelSpec;
use fsot::core::mask::Mask;
use fsot::core::objective::{score, SCORE_SLICES};
use fsot::core::tile::Tile;
use fsot::error::Result;
use fsot::optimize::backend::{BackendChoice, BackendKind};
use fsot::optimize::run::{CancelFlag, Run, RunOptions};
use fsot::optimize::settings::Settings;
use fsot::optimize::vulkan::VulkanOptions;
use fsot::quality::eye::Eye;
use fsot::quality::metric::relative_errors;
use fsot::quality::perceived::{perceived_error, TestSetup};

/// One checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Point {
    pub backend: String,
    pub machine: String,
    pub iteration: u32,
    /// Host wall time of the optimisation (submissions and waits included).
    pub seconds: f64,
    /// Vulkan: the GPU's own time, from timestamp queries around every pass.
    pub gpu_seconds: Option<f64>,
    /// `fsot score` objective / white noise's.
    pub objective_ratio: f64,
    /// pRelMSE of the scene under TAA / white noise's.
    pub prelmse_ratio: f64,
    /// The independent perceived-error test (animated
    /// integrands, TAA, the eye; `eval::perceived`) / white noise's.
    pub perceived_ratio: f64,
}

impl Point {
    pub const CSV_HEADER: &'static str =
        "backend,machine,iteration,seconds,gpu_seconds,objective_ratio,prelmse_ratio,perceived_ratio";

    fn machine_quoted(&self) -> String {
        self.machine.replace('"', "'")
    }

    fn gpu_cell(&self, digits: usize, none: &str) -> String {
        self.gpu_seconds.map(|s| format!("{s:.digits$}")).unwrap_or_else(|| none.to_string())
    }

    pub fn markdown_row(&self) -> String {
        format!(
            "| {} | {} | {} | {:.3} | {} | {:.3} | {:.3} | {:.3} |",
            self.backend,
            self.machine,
            self.iteration,
            self.seconds,
            self.gpu_cell(4, "-"),
            self.objective_ratio,
            self.prelmse_ratio,
            self.perceived_ratio
        )
    }

    pub fn csv_row(&self) -> String {
        format!(
            "{},\"{}\",{},{:.6},{},{:.6},{:.6},{:.6}",
            self.backend,
            self.machine_quoted(),
            self.iteration,
            self.seconds,
            self.gpu_cell(6, ""),
            self.objective_ratio,
            self.prelmse_ratio,
            self.perceived_ratio
        )
    }
}

/// The scene judge: a soft shadow, 64 x 64, TAA, the eye at sigma 2.1.
pub struct SceneJudge {
    scene: Scene,
    shot: Shot,
    warmup: usize,
    reference: Vec<Vec<f64>>,
    seen_reference: Vec<Vec<f64>>,
    eye: Eye,
    white: f64,
    perceived_white: f64,
}

impl SceneJudge {
    pub fn new(tile: Tile, cache: Option<&Path>) -> Result<Self> {
        let scene = Scene::SoftShadow;
        let shot = Shot { image: 64, frames: 80 };
        let warmup = 48;
        let reference = taa(&references(scene, shot, 256, cache)?, crate::eval::suite::TAA_ALPHA);
        let eye = Eye::new(2.1, 60.0);
        let seen_reference = (warmup..shot.frames).map(|f| eye.filter(&reference, f, shot.image)).collect();
        let mut judge =
            Self { scene, shot, warmup, reference, seen_reference, eye, white: 1.0, perceived_white: 1.0 };
        judge.white = (0..4).map(|s| judge.prelmse(&Mask::white(tile, 50 + s))).sum::<f64>() / 4.0;
        judge.perceived_white = (0..3)
            .map(|s| perceived_error(&Mask::white(tile, 1000 + s), &TestSetup::default(), 1))
            .sum::<f64>()
            / 3.0;
        Ok(judge)
    }

    /// pRelMSE of the scene rendered with the mask, under TAA (mean of three
    /// renders with different shifts: the soft shadow's error sits in few pixels,
    /// so one render is noisy).
    pub fn prelmse(&self, mask: &Mask) -> f64 {
        (7..10).map(|seed| self.prelmse_once(mask, seed)).sum::<f64>() / 3.0
    }

    fn prelmse_once(&self, mask: &Mask, seed: u64) -> f64 {
        let n = self.shot.image;
        let frames =
            taa(&render(self.scene, self.shot, &MaskSampler::new(mask, self.scene.dims(), seed)), 0.1);
        relative_errors(&frames, &self.reference, &self.seen_reference, &self.eye, self.warmup, n).0
    }

    pub fn ratio(&self, mask: &Mask) -> f64 {
        self.prelmse(mask) / self.white
    }

    /// The independent test's ratio to white noise (as `ratio_to_white`, with
    /// the white-noise figure computed once).
    pub fn perceived_ratio(&self, mask: &Mask) -> f64 {
        perceived_error(mask, &TestSetup::default(), 1) / self.perceived_white
    }
}

/// Iterations of the untimed warm-up run before each backend's timed run.
pub const WARM_UP_ITERATIONS: u32 = 2;

/// Runs the problem on one backend to the last checkpoint, judging each, after
/// an untimed warm-up run of WARM_UP_ITERATIONS. `base`: the device and
/// validation settings (its backend and Vulkan options are set here).
pub fn convergence(
    choice: BackendChoice,
    base: &RunOptions,
    tile: Tile,
    spec: KernelSpec,
    seed: u64,
    checkpoints: &[u32],
    judge: &SceneJudge,
) -> Result<Vec<Point>> {
    let last = *checkpoints.iter().max().unwrap_or(&1);
    // From white noise: the backends are compared on the optimizer's own
    // iterations, which an animated start's one-frame run would blur.
    let mut settings = Settings::new(spec, seed).start(fsot::Start::White);
    settings.iterations = last;
    // Profiled: timestamps around every pass give the GPU's own time.
    let vulkan = VulkanOptions::default().profile(true);
    let options = base.clone().backend(choice).vulkan(vulkan);
    // An untimed warm-up of the same problem first, so that one-time costs are
    // not counted as the optimisation's: llvmpipe compiles each shader at its
    // first dispatch, and the CPU path's thread pool starts.
    let mut warm_up = settings;
    warm_up.iterations = WARM_UP_ITERATIONS;
    Run::start(tile, warm_up, None, options.clone())?.advance(
        WARM_UP_ITERATIONS,
        &CancelFlag::new(),
        &mut |_| {},
    )?;
    let mut run = Run::start(tile, settings, None, options)?;
    let kind = run.backend_kind();
    let machine = match kind {
        BackendKind::Vulkan => run.note().trim_start_matches("vulkan on ").to_string(),
        BackendKind::Cpu => super::machine::cpu_description(),
    };
    let judge_at = |run: &Run, elapsed: Duration| -> Result<Point> {
        let mask = run.backend().mask()?;
        Ok(Point {
            backend: kind.name().to_string(),
            machine: machine.clone(),
            iteration: run.iteration(),
            seconds: elapsed.as_secs_f64(),
            gpu_seconds: run.report().profile.map(|p| p.seconds()),
            objective_ratio: score(&mask, spec, SCORE_SLICES).ratio(),
            prelmse_ratio: judge.ratio(&mask),
            perceived_ratio: judge.perceived_ratio(&mask),
        })
    };
    let mut elapsed = Duration::ZERO;
    let mut points = vec![judge_at(&run, elapsed)?];
    let mut sorted: Vec<u32> = checkpoints.iter().copied().filter(|&c| c > 0).collect();
    sorted.sort_unstable();
    sorted.dedup();
    for c in sorted {
        let start = Instant::now();
        run.advance(c, &CancelFlag::new(), &mut |_| {})?;
        elapsed += start.elapsed();
        points.push(judge_at(&run, elapsed)?);
    }
    let messages = run.report().validation_messages;
    if !messages.is_empty() {
        return Err(fsot::error::Error::invalid(format!(
            "the Vulkan validation layer reported {} message(s), the first: {}",
            messages.len(),
            messages[0]
        )));
    }
    Ok(points)
}

/// Seconds to reach `level` (a ratio) by linear interpolation between
/// checkpoints, or None if never reached.
pub fn time_to(points: &[Point], level: f64, value: impl Fn(&Point) -> f64) -> Option<f64> {
    let first = points.iter().position(|p| value(p) <= level)?;
    if first == 0 {
        return Some(points[0].seconds);
    }
    let (a, b) = (&points[first - 1], &points[first]);
    let t = (value(a) - level) / (value(a) - value(b));
    Some(a.seconds + t * (b.seconds - a.seconds))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(seconds: f64, v: f64) -> Point {
        Point {
            backend: "cpu".into(),
            machine: String::new(),
            iteration: 0,
            seconds,
            gpu_seconds: None,
            objective_ratio: v,
            prelmse_ratio: v,
            perceived_ratio: v,
        }
    }

    #[test]
    fn time_to_a_level_interpolates_between_checkpoints() {
        let points = [p(0.0, 1.0), p(1.0, 0.8), p(3.0, 0.4)];
        assert_eq!(time_to(&points, 0.9, |p| p.objective_ratio), Some(0.5));
        assert_eq!(time_to(&points, 0.6, |p| p.objective_ratio), Some(2.0));
        assert_eq!(time_to(&points, 0.3, |p| p.objective_ratio), None);
        assert_eq!(time_to(&points, 1.5, |p| p.objective_ratio), Some(0.0));
    }
}
