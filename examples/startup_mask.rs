//! A host that makes its blue-noise texture at start-up instead of shipping one:
//! the 64 x 64 x 32 two-dimensional mask (RG8, the size engines embed) for TAA,
//! made in the host's process through the library within a time budget, then
//! written as a KTX2 array texture (the bytes an engine would upload). The
//! kernel is `perceptual-taa` with the eye at `--display` (default
//! `standard_fhd`), as `fsot optimize` makes it. Prints the wall time from the
//! start of `main` to the texture's bytes and the iterations the budget
//! allowed, then with `--score` (outside the timed part) the mask's objective
//! as a fraction of white noise's. `--out` names a `.ktx2` file (the texture) or another file
//! `Mask::save` writes (`.exr`, as `fsot eval --mask` reads).
//!
//! cargo run --release --example startup_mask -- [--budget SECONDS] [--size WxHxT]
//!     [--dims D] [--display NAME|PPD] [--backend cpu|vulkan|auto] [--seed N] [--score]
//!     [--out FILE.ktx2]

use std::path::PathBuf;
use std::time::Instant;

use fsot::{BackendChoice, CancelFlag, KernelSpec, Run, RunOptions, Settings, TexelFormat, Tile, Until};

struct Args {
    budget: f64,
    size: (usize, usize, usize),
    dims: usize,
    backend: BackendChoice,
    seed: u64,
    display: String,
    score: bool,
    out: PathBuf,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        budget: 1.0,
        size: (64, 64, 32),
        dims: 2,
        backend: BackendChoice::Cpu,
        seed: 1,
        display: "standard_fhd".to_string(),
        score: false,
        out: PathBuf::from("startup-mask.ktx2"),
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--budget" => args.budget = value()?.parse().map_err(|e| format!("--budget: {e}"))?,
            "--size" => {
                let v = value()?;
                let n: Vec<usize> = v
                    .split('x')
                    .map(str::parse)
                    .collect::<Result<_, _>>()
                    .map_err(|e| format!("--size: {e}"))?;
                match n[..] {
                    [w, h, t] => args.size = (w, h, t),
                    _ => return Err(format!("--size takes WxHxT, got {v}")),
                }
            }
            "--dims" => args.dims = value()?.parse().map_err(|e| format!("--dims: {e}"))?,
            "--seed" => args.seed = value()?.parse().map_err(|e| format!("--seed: {e}"))?,
            "--out" => args.out = PathBuf::from(value()?),
            "--display" => args.display = value()?,
            "--score" => args.score = true,
            "--backend" => {
                args.backend = match value()?.as_str() {
                    "cpu" => BackendChoice::Cpu,
                    "vulkan" => BackendChoice::Vulkan,
                    "auto" => BackendChoice::Auto,
                    other => return Err(format!("--backend takes cpu, vulkan or auto, got {other}")),
                }
            }
            other => return Err(format!("unknown argument {other}")),
        }
    }
    Ok(args)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let begun = Instant::now();
    let args = parse()?;
    let (w, h, t) = args.size;
    let tile = Tile::new(w, h, t, 1, args.dims)?;
    let kernel = KernelSpec::named("perceptual-taa")?.on_display_named(&args.display)?;
    let settings = Settings::new(kernel, args.seed).iterations(100_000).until(Until::Seconds(args.budget));
    // The budget counts from the start of main: the host's own start-up is in it.
    let options = RunOptions::default().backend(args.backend).budget_from(begun);
    let mut run = Run::start(tile, settings, None, options)?;
    run.run(&CancelFlag::new(), &mut |_| {})?;
    let iterations = run.iteration();
    let backend = run.note().to_string();
    let mask = run.finish()?;
    let format = match args.dims {
        1 => TexelFormat::R8Unorm,
        2 => TexelFormat::R8G8Unorm,
        _ => TexelFormat::R8G8B8A8Unorm,
    };
    let texture = mask.ktx2(Some(format))?;
    let seconds = begun.elapsed().as_secs_f64();
    match args.out.extension().and_then(|e| e.to_str()) {
        Some("ktx2") => std::fs::write(&args.out, &texture)?,
        _ => mask.save(&args.out)?,
    }
    println!(
        "{}: {iterations} iterations, {seconds:.3} s from the start of main to the texture's {} bytes (budget {} s; {backend})",
        tile.describe(),
        texture.len(),
        args.budget
    );
    if args.score {
        let score = mask.score(kernel)?;
        println!("objective {:.4e}, {:.3} x white noise", score.objective, score.ratio());
    }
    println!("wrote {}", args.out.display());
    Ok(())
}
