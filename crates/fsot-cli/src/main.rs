//! The `fsot` command line: its flags here, each command in its own file.

mod cmd;

use cmd::env;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::{Args, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use fsot::core::kernel::{KernelSpec, DEFAULT_ALPHA, DEFAULT_FPS, DEFAULT_SIGMA};
use fsot::core::objective::{score, scores, SCORE_SLICES};
use fsot::core::tile::Tile;
use fsot::error::{Error, Result};
use fsot::io::atomic::AtomicFile;
use fsot::io::MaskFile;
use fsot::optimize::backend::{BackendChoice, Report};
use fsot::optimize::run::{Checkpointing, Event, Outcome, Run, RunOptions};
use fsot::optimize::settings::{Settings, Until};
use fsot::optimize::vulkan::VulkanOptions;
use fsot::peers::fast::{Combine, Filter};
use fsot::peers::swap::SwapDevice;

#[derive(Parser)]
#[command(
    name = "fsot",
    version = concat!(env!("CARGO_PKG_VERSION"), " (", env!("FSOT_COMMIT"), ")"),
    about = "Perceptually optimized spatio-temporal sample masks (filtered sliced optimal transport)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Optimize a mask and write it (.exr, .ktx2 or .h by --out's extension; PNG
    /// slices with --png).
    Optimize(Box<OptimizeArgs>),
    /// Print the filtered sliced-Wasserstein objective of a mask, on a fixed set of
    /// slices, beside that of white noise of the same shape.
    Score(ScoreArgs),
    /// The numerical stress suite: long runs, float32 GPU against the float64 CPU
    /// path, a million contributions into one value, extreme settings and shapes,
    /// ties, determinism. Exits non-zero if any check fails.
    Stress(StressArgs),
    /// Benchmarks that print figures.
    Bench(BenchArgs),
    /// Render animated scenes with every method's mask, with and without TAA,
    /// and measure the perceptual error (pRelMSE) and RelMSE.
    Eval(EvalArgs),
    /// What a scene file needs: per sampling decision, the mask it reads and why,
    /// the kernel and tile, and the estimated time on this machine and backend.
    Plan(PlanArgs),
}

#[derive(Args)]
struct PlanArgs {
    /// The scene file (TOML; see docs/scene-plans.md).
    scene: PathBuf,
    /// Print the plan as JSON.
    #[arg(long)]
    json: bool,
    /// The backend the time estimate is for.
    #[arg(long, value_enum, default_value = "auto")]
    backend: Backend,
    /// Vulkan device: index or part of its name [default: FSOT_DEVICE, else the
    /// first discrete GPU].
    #[arg(long)]
    device: Option<String>,
    /// Plan every mask within this wall time (1s, 500ms, 2m) instead of the
    /// scene's `[plan]` budget, or without one, until iterations no longer pay.
    #[arg(long)]
    budget: Option<String>,
}

#[derive(Args)]
struct EvalArgs {
    /// Small tiles, images and sample counts, for a quick run.
    #[arg(long)]
    quick: bool,
    /// Also write the records as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Folder for the tables (results.md, results.json) and the cache of masks
    /// and references.
    #[arg(long, default_value = "eval-out")]
    out: PathBuf,
    /// Eye sigmas to evaluate [default: 2.1 and 1.9, as in the tables of Korać et al. 2023; 2.1 with --quick].
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    sigma: Vec<f64>,
    /// Mask seeds per method (each with its own renders), 2 to 10000; a published
    /// mask is judged at as many placements [default: 3 with --quick, else 5].
    #[arg(long, allow_negative_numbers = true)]
    seeds: Option<u32>,
    /// Masks `fsot-planned` makes per display and TAA setting, each judged at
    /// its share of the seeds' placements [default: 1, judged at every
    /// placement as the published masks are; the seeds with --quick].
    #[arg(long)]
    planned_masks: Option<u32>,
    /// ColorVideoVDP's display model for the JOD; repeatable (or comma-separated):
    /// every render is judged on each, and `fsot-planned` plans for each
    /// [default: standard_4k, the metric's own default].
    #[arg(long, value_delimiter = ',')]
    display: Vec<String>,
    /// Only these scenes (comma-separated names) [default: all].
    #[arg(long, value_delimiter = ',')]
    scenes: Vec<String>,
    /// Only these methods (comma-separated: the table's names, `published-stbn`
    /// and `published-fast` with --peers, the names of --mask, `fsot-planned`)
    /// [default: all].
    #[arg(long, value_delimiter = ',')]
    methods: Vec<String>,
    /// How the grey frames reach ColorVideoVDP: `luminance` (one channel, which
    /// the metric feeds to its achromatic and colour-opponent channels alike) or
    /// `rgb` (three equal channels, as a display shows grey: achromatic only).
    #[arg(long, value_enum, default_value = "rgb")]
    grey: GreyArg,
    /// Which TAA settings to judge: `both`, or `with` or `without` alone (half
    /// the judging; `fsot-planned` makes only that setting's masks).
    #[arg(long, value_enum, default_value = "both")]
    taa: TaaArg,
    /// Also judge the frames after TAA by FLIP (Andersson et al. 2020, NVIDIA's
    /// LDR-FLIP at each display's pixels per degree), a still-image metric built
    /// another way than ColorVideoVDP.
    #[arg(long)]
    flip: bool,
    /// Also dissect each method's error into anatomy.md: its power per spatial and
    /// temporal frequency band, and ColorVideoVDP's differences per channel and band.
    #[arg(long)]
    anatomy: bool,
    /// Also measure the published scalar masks found in this folder
    /// (real_stbn.png, real_uniform_gauss_1.3435_exponential_0.1_0.1_product.png),
    /// as `published-stbn` and `published-fast`.
    #[arg(long)]
    peers: Option<PathBuf>,
    /// Also measure this mask file (.exr or .ktx2), as method NAME; repeatable.
    #[arg(long = "mask", value_name = "NAME=FILE")]
    masks: Vec<String>,
    /// Iterations of fsot's masks [default: 500 with --quick, else 1000].
    #[arg(long, allow_negative_numbers = true)]
    iterations: Option<u32>,
    /// Passes of the swap methods' masks [default: 8 with --quick, else 32].
    #[arg(long, allow_negative_numbers = true)]
    passes: Option<u32>,
}

#[derive(Args)]
struct BenchArgs {
    /// One suite only; without it: convergence of the CPU path and of Vulkan on
    /// the same problem, and time to quality.
    #[command(subcommand)]
    suite: Option<BenchSuite>,
    /// A small problem, for a quick run.
    #[arg(long)]
    quick: bool,
    /// Also write the figures as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Folder for convergence.md, convergence.csv, convergence.png and the cache
    /// [default: bench-out].
    #[arg(long)]
    out: Option<PathBuf>,
}

impl BenchArgs {
    /// `--out`, or its default.
    fn out_dir(&self) -> &std::path::Path {
        self.out.as_deref().unwrap_or(std::path::Path::new("bench-out"))
    }
}

/// One GPU kernel measured on its own.
#[derive(Args)]
struct KernelBench {
    /// Input size, at most 2^28.
    #[arg(long, default_value_t = 1 << 20, allow_negative_numbers = true)]
    n: u32,
    /// Timed runs (median reported), after two warm-up runs; at most 10000.
    #[arg(long, default_value_t = 10, allow_negative_numbers = true)]
    repeats: u32,
    /// Vulkan device: index or part of its name [default: FSOT_DEVICE, else
    /// the first discrete GPU].
    #[arg(long)]
    device: Option<String>,
}

#[derive(Subcommand)]
enum BenchSuite {
    /// Pairs per second of the Vulkan radix sort and of the CPU sort, same keys
    /// (N: pairs of 32-bit keys and 32-bit payloads).
    Sort(KernelBench),
    /// Contributions per second of the GPU gradient scatter (fixed point and float
    /// atomics) and of the CPU path's (N contributions into N/16 accumulators).
    Scatter(KernelBench),
    /// One configuration of the scaling suite (run by `fsot bench` in a child
    /// process, so its peak memory is its own).
    #[command(hide = true)]
    ScalingOne {
        /// W x H x T.
        #[arg(long)]
        size: String,
        /// Dimensions per sample.
        #[arg(long)]
        dims: usize,
        /// Samples per pixel.
        #[arg(long)]
        spp: usize,
        /// Timed iterations.
        #[arg(long)]
        iterations: u32,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum TaaArg {
    /// Judge the frames with TAA and without.
    Both,
    /// Only after TAA.
    With,
    /// Only without TAA.
    Without,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum GreyArg {
    Luminance,
    Rgb,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum KernelName {
    /// Frames independent (Salaün et al. 2022 per frame).
    Spatial,
    /// Symmetric temporal Gaussian (akin to STBN).
    Gaussian,
    /// TAA: exponential moving average with blend weight --alpha.
    Taa,
    /// FovVideoVDP temporal response at --fps.
    Perceptual,
    /// TAA, then the eye: the paper's full model.
    PerceptualTaa,
}

impl KernelName {
    fn as_str(&self) -> &'static str {
        match self {
            KernelName::Spatial => "spatial",
            KernelName::Gaussian => "gaussian",
            KernelName::Taa => "taa",
            KernelName::Perceptual => "perceptual",
            KernelName::PerceptualTaa => "perceptual-taa",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum StartArg {
    /// `animated` with --budget, `white` otherwise.
    Auto,
    /// One frame optimized under the kernel's spatial filter, set in motion over
    /// the frames by a Kronecker sequence (a low-discrepancy sequence at each pixel).
    Animated,
    /// White noise.
    White,
    /// With --budget only: a quarter of the tile (half its width and height) made
    /// first in three quarters of the budget, laid out 2x2 with each copy rotated
    /// in value, then the whole tile refined: further within a budget too short
    /// for the whole tile, but the copies keep the quarter's structure.
    Coarse,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Method {
    /// fsot's optimizer (filtered sliced optimal transport) under --kernel.
    Fsot,
    /// Independent uniform samples (seeded).
    White,
    /// Spatiotemporal blue noise (Wolfe et al. 2022): energy = 2-D Gaussian in
    /// the frame + 1-D Gaussian over time, sigma --sigma and --sigma-t (default
    /// 1.9); scalar masks (d = 1) by void-and-cluster, vector masks by
    /// simulated annealing of swaps (--passes).
    Stbn,
    /// Filter-adapted masks (FAST, Donnelly et al. 2024): greedy swaps for the
    /// filter --fast-spatial x --fast-temporal (--fast-combine), --passes.
    Fast,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Backend {
    /// Vulkan when a device is there, else the CPU (says which).
    Auto,
    /// The multi-threaded CPU path (the reference).
    Cpu,
    /// Vulkan compute.
    Vulkan,
}

impl Backend {
    fn choice(self) -> BackendChoice {
        match self {
            Backend::Auto => BackendChoice::Auto,
            Backend::Cpu => BackendChoice::Cpu,
            Backend::Vulkan => BackendChoice::Vulkan,
        }
    }
}

#[derive(Args, Clone)]
struct KernelArgs {
    /// Temporal filter of the kernel [default: perceptual-taa].
    #[arg(long, value_enum)]
    kernel: Option<KernelName>,
    /// The display the mask is seen on; the kernel's spatial filter is the eye's
    /// contrast sensitivity at its pixels per degree: a number (pixels per
    /// degree), a display's name (standard_fhd, standard_4k, sdr_4k_30,
    /// standard_phone, ...) or WxH:DIAGONALin:DISTANCEm (e.g. 2560x1440:27in:0.7m)
    /// [default: standard_fhd, unless --sigma is given].
    #[arg(long, conflicts_with = "sigma")]
    display: Option<String>,
    /// Spatial Gaussian exp(-r^2 / sigma^2), in pixels, instead of the display's
    /// eye [for --method stbn: its energy's sigma, default 1.9].
    #[arg(long, allow_negative_numbers = true)]
    sigma: Option<f64>,
    /// Temporal sigma of the gaussian kernel, in frames [default: --sigma, else 2.1].
    #[arg(long, allow_negative_numbers = true)]
    sigma_t: Option<f64>,
    /// TAA blend weight of the current frame, in [0.0001, 1] [default: 0.1].
    #[arg(long, allow_negative_numbers = true)]
    alpha: Option<f64>,
    /// Frame rate for the perceptual filter [default: 60].
    #[arg(long, allow_negative_numbers = true)]
    fps: Option<f64>,
}

/// An error for a flag the kernel (perceptual-taa when none is named) has no
/// use for: `--sigma-t` but for gaussian, `--alpha` without TAA, `--fps`
/// without the eye's response.
fn kernel_flags_apply(kernel: Option<KernelName>, sigma_t: bool, alpha: bool, fps: bool) -> Result<()> {
    use KernelName::*;
    let kernel = kernel.unwrap_or(PerceptualTaa);
    let unused = [
        ("--sigma-t", sigma_t && kernel != Gaussian, "the gaussian kernel's temporal width"),
        (
            "--alpha",
            alpha && !matches!(kernel, Taa | PerceptualTaa),
            "TAA's blend weight (kernels taa and perceptual-taa)",
        ),
        (
            "--fps",
            fps && !matches!(kernel, Perceptual | PerceptualTaa),
            "the frame rate of the eye's response (kernels perceptual and perceptual-taa)",
        ),
    ];
    match unused.iter().find(|(_, unused, _)| *unused) {
        Some((flag, _, what)) => {
            Err(Error::invalid(format!("{flag} sets {what}; --kernel {} has none", kernel.as_str())))
        }
        None => Ok(()),
    }
}

impl KernelArgs {
    fn spec(&self) -> Result<KernelSpec> {
        kernel_spec(
            self.kernel.unwrap_or(KernelName::PerceptualTaa).as_str(),
            self.display.as_deref(),
            self.sigma,
            self.sigma_t,
            self.alpha.unwrap_or(DEFAULT_ALPHA),
            self.fps.unwrap_or(DEFAULT_FPS),
        )
    }

    /// An error for a flag the kernel has no use for (`kernel_flags_apply`).
    fn check_flags_apply(&self) -> Result<()> {
        kernel_flags_apply(self.kernel, self.sigma_t.is_some(), self.alpha.is_some(), self.fps.is_some())
    }

    /// Whether any flag of the kernel was given.
    fn any_given(&self) -> bool {
        self.kernel.is_some()
            || self.display.is_some()
            || self.sigma.is_some()
            || self.sigma_t.is_some()
            || self.alpha.is_some()
            || self.fps.is_some()
    }
}

/// The kernel of `name`: a Gaussian of `sigma` pixels when given, else the eye
/// on `display` (by default `fsot::core::display::DEFAULT_DISPLAY`).
fn kernel_spec(
    name: &str,
    display: Option<&str>,
    sigma: Option<f64>,
    sigma_t: Option<f64>,
    alpha: f64,
    fps: f64,
) -> Result<KernelSpec> {
    let spec = KernelSpec::from_name(name, sigma.unwrap_or(DEFAULT_SIGMA), sigma_t, alpha, fps)?;
    match sigma {
        Some(_) => Ok(spec),
        None => spec
            .on_display(fsot::core::display::parse(display.unwrap_or(fsot::core::display::DEFAULT_DISPLAY))?),
    }
}

#[derive(Args)]
struct OptimizeArgs {
    /// Tile size W x H x T (pixels x pixels x frames; W x H: one frame) [default: 64x64x16, or the
    /// --init file's].
    #[arg(long)]
    size: Option<String>,
    /// Dimensions per sample, 1 to 8 [default: 2, or the --init file's].
    #[arg(long, allow_negative_numbers = true)]
    dims: Option<usize>,
    /// Samples per pixel and frame, 1 to 64 [default: 1, or the --init file's].
    #[arg(long, allow_negative_numbers = true)]
    spp: Option<usize>,
    /// How to make the mask.
    #[arg(long, value_enum, default_value = "fsot")]
    method: Method,
    #[command(flatten)]
    kernel: KernelArgs,
    /// Iterations of the optimizer [default: 1000]; with --until, the most it may take
    /// [default: 10000].
    #[arg(long, allow_negative_numbers = true)]
    iterations: Option<u32>,
    /// Stop by a rule instead of after a count: `plateau` (when further iterations
    /// no longer pay: the step halves whenever a 32-iteration window gains less
    /// than 1% on the last, and the run ends at the smallest step when a window
    /// gains less than 0.2%) or `objective:X` (once a window's mean objective
    /// estimate is at most X).
    #[arg(long)]
    until: Option<String>,
    /// The best mask reachable in this wall time (`1s`, `500ms`, `2.5s`, `1m`; at
    /// most a day),
    /// counted from the process's start (setting up the backend included): the
    /// step size follows the cosine schedule over the time, or over the
    /// --iterations cap where that is further, and the run ends at
    /// most about one iteration past it. --iterations caps it [default: 10000].
    /// With --scene: every mask of the plan within it (instead of the scene's
    /// `[plan]` budget).
    #[arg(long, conflicts_with = "until", allow_negative_numbers = true)]
    budget: Option<String>,
    /// Where the optimizer starts without --init (--init takes a mask of the
    /// tile, or of one frame of it, which is then set in motion as `animated` does);
    /// with --scene every mask starts `animated`.
    #[arg(long, value_enum, default_value = "auto")]
    start: StartArg,
    /// Slices per iteration, at most 2^24 [default: enough for each sample to be in
    /// 16 classes per iteration].
    #[arg(long, allow_negative_numbers = true)]
    slices: Option<u32>,
    /// The share of slices along one coordinate, 0 to 1 (d >= 2): higher spreads
    /// each channel read alone better (a 1-D decision on the first channel), at
    /// the cost of the channels read together [default: 0.35].
    #[arg(long, allow_negative_numbers = true)]
    axis_share: Option<f64>,
    /// Random seed: the same seed gives a bit-identical mask (on Vulkan with
    /// --deterministic) [default: 0].
    #[arg(long, allow_negative_numbers = true)]
    seed: Option<u64>,
    /// Where to run.
    #[arg(long, value_enum, default_value = "auto")]
    backend: Backend,
    /// Vulkan device: index or part of its name [default: FSOT_DEVICE, else the
    /// first discrete GPU].
    #[arg(long)]
    device: Option<String>,
    /// Vulkan: accumulate in 64-bit fixed point, bit-identical run to run (the
    /// CPU path always is).
    #[arg(long)]
    deterministic: bool,
    /// Vulkan: print the time per pass (timestamp queries).
    #[arg(long)]
    profile: bool,
    /// Worker threads for the CPU path, 1 to 1024 [default: every core].
    #[arg(long, allow_negative_numbers = true)]
    threads: Option<usize>,
    /// Start from this mask (.exr or .ktx2, written by fsot or laid out the same way); with
    /// --method fast, the swaps rearrange its values.
    #[arg(long)]
    init: Option<PathBuf>,
    /// Swap methods (stbn with d >= 2, fast): passes of as many proposed swaps
    /// as pixels.
    #[arg(long, default_value_t = 32, allow_negative_numbers = true)]
    passes: u32,
    /// FAST spatial filter: none, gaussian:SIGMA, box:N or binomial:N.
    #[arg(long, default_value = "gaussian:1.3435")]
    fast_spatial: String,
    /// FAST temporal filter: none, gaussian:SIGMA, box:N, binomial:N or
    /// ema:ALPHA:BETA (blend alpha, history reset beta).
    #[arg(long, default_value = "ema:0.1:0.1")]
    fast_temporal: String,
    /// FAST: `product` (one separable filter) or `sum:W` (W x spatial loss +
    /// (1 - W) x temporal loss).
    #[arg(long, default_value = "product")]
    fast_combine: String,
    /// Save the run's state (samples, optimizer state) to this file every
    /// --checkpoint-every iterations and on Ctrl-C; removed when the run completes.
    #[arg(long)]
    checkpoint: Option<PathBuf>,
    /// Iterations between checkpoints.
    #[arg(long, default_value_t = 100, allow_negative_numbers = true)]
    checkpoint_every: u32,
    /// Continue from --checkpoint: run the command that wrote it again, with
    /// --resume added. On the CPU path the result is bit-identical to an
    /// uninterrupted run.
    #[arg(long)]
    resume: bool,
    /// Make every mask a scene file plans (see `fsot plan`) into the folder --out,
    /// with plan.json; each mask stops when further iterations no longer pay.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Output file, by its extension: .exr (every value exact), .ktx2 (a 2-D array
    /// texture, one layer per frame and sample) or .h (a C header); with --scene, the output
    /// folder.
    #[arg(long, default_value = "mask.exr")]
    out: PathBuf,
    /// Also write the same mask to this file, by its extension as --out; repeatable
    /// (e.g. --out m.ktx2 --also m.exr keeps the exact values beside the texture).
    #[arg(long, value_name = "FILE")]
    also: Vec<PathBuf>,
    /// KTX2 format: r8_unorm, r8g8_unorm, r8g8b8a8_unorm, r16_unorm, r16g16_unorm,
    /// r16g16b16a16_unorm, r32_sfloat, r32g32_sfloat, r32g32b32a32_sfloat or auto
    /// [default: auto, 16-bit UNORM with channels for d]. With --scene: also write
    /// NAME.ktx2 beside each NAME.exr.
    #[arg(long)]
    ktx2_format: Option<String>,
    /// Also write PNG slices into this folder.
    #[arg(long)]
    png: Option<PathBuf>,
    /// Bits per channel of the PNG slices: 16, or 8 (the published masks' depth).
    #[arg(long, default_value_t = 16, value_parser = parse_png_bits, requires = "png")]
    png_bits: u32,
    /// The flags given on the command line (by their ids), for the notes on
    /// those the method has no use for.
    #[arg(skip)]
    given: Vec<String>,
}

#[derive(Args)]
struct StressArgs {
    /// Small sizes (seconds) instead of the full ones (100k-iteration runs, minutes).
    #[arg(long)]
    quick: bool,
    /// CPU only, even where a Vulkan device is present.
    #[arg(long)]
    cpu_only: bool,
    /// Vulkan device: index or part of its name [default: FSOT_DEVICE, else the
    /// first discrete GPU, else any device, lavapipe included].
    #[arg(long)]
    device: Option<String>,
    /// Markdown table of the figures.
    #[arg(long, default_value = "stress.md")]
    out: PathBuf,
}

#[derive(Args)]
struct ScoreArgs {
    /// The mask to score (.exr or .ktx2).
    mask: PathBuf,
    /// The kernel to score with [default: the one recorded in the mask's
    /// attributes; perceptual-taa when a kernel flag below is given alone].
    #[arg(long, value_enum)]
    kernel: Option<KernelName>,
    /// The display's eye as the spatial filter (as for `fsot optimize`)
    /// [default: standard_fhd when choosing the kernel here without --sigma].
    #[arg(long, conflicts_with = "sigma")]
    display: Option<String>,
    /// Spatial Gaussian exp(-r^2 / sigma^2), in pixels, instead of the display's eye.
    #[arg(long, allow_negative_numbers = true)]
    sigma: Option<f64>,
    /// Temporal sigma of the gaussian kernel, in frames [default: --sigma, else 2.1].
    #[arg(long, allow_negative_numbers = true)]
    sigma_t: Option<f64>,
    /// TAA blend weight of the current frame [default: 0.1 when choosing the kernel here].
    #[arg(long, allow_negative_numbers = true)]
    alpha: Option<f64>,
    /// Frame rate for the perceptual filter [default: 60 when choosing the kernel here].
    #[arg(long, allow_negative_numbers = true)]
    fps: Option<f64>,
    /// Slices in the fixed scoring set.
    #[arg(long, default_value_t = SCORE_SLICES)]
    slices: u32,
}

/// When the process started (as `main` began): what a time budget counts from.
static STARTED: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();

fn process_start() -> Instant {
    *STARTED.get_or_init(Instant::now)
}

fn main() -> ExitCode {
    process_start();
    let matches = <Cli as clap::CommandFactory>::command().get_matches();
    let mut cli = <Cli as clap::FromArgMatches>::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    if let (Command::Optimize(args), Some(("optimize", sub))) = (&mut cli.command, matches.subcommand()) {
        args.given = sub
            .ids()
            .filter(|id| sub.value_source(id.as_str()) == Some(clap::parser::ValueSource::CommandLine))
            .map(|id| id.to_string())
            .collect();
    }
    let result = match cli.command {
        Command::Optimize(args) => cmd::optimize::optimize(*args),
        Command::Score(args) => cmd::score::score_command(args),
        Command::Stress(args) => cmd::stress::stress_command(args),
        Command::Bench(args) => cmd::bench::bench_command(args),
        Command::Eval(args) => cmd::eval::eval_command(args),
        Command::Plan(args) => cmd::plan::plan_command(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Error::Interrupted) => ExitCode::from(130),
        Err(e) => {
            eprintln!("error: {e}{}", hint(&e));
            ExitCode::FAILURE
        }
    }
}

/// What the command line adds to a library error: the flag that helps.
fn hint(e: &Error) -> &'static str {
    match e {
        _ if e.is_out_of_device_memory() => " (or --backend cpu)",
        Error::CheckpointExists(_) => " (--resume continues it)",
        _ => "",
    }
}

/// The most worker threads `--threads` starts.
const MAX_THREADS: usize = 1024;

fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(n) = threads {
        if !(1..=MAX_THREADS).contains(&n) {
            return Err(Error::invalid(format!("--threads must be 1 to {MAX_THREADS}, got {n}")));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| Error::invalid(format!("cannot start {n} threads: {e}")))?;
    }
    Ok(())
}

fn parse_png_bits(text: &str) -> std::result::Result<u32, String> {
    match text {
        "8" => Ok(8),
        "16" => Ok(16),
        _ => Err(format!("PNG slices hold 8 or 16 bits per channel, not {text}")),
    }
}
