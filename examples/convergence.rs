//! Time to quality of the CPU path: fresh runs of N iterations for several N, each
//! timed (optimization only) and judged by the independent perceived-error test
//! under TAA (ratio to white noise) and by `fsot score`'s objective.
//!
//! cargo run --release --example convergence -- [kernel] [WxHxT] [rule: momentum|adam] [N...]
use std::time::Instant;

use fsot::core::kernel::KernelSpec;
use fsot::core::objective::{score, SCORE_SLICES};
use fsot::core::step_rule::StepRule;
use fsot::core::tile::Tile;
use fsot::optimize::cpu::CpuRun;
use fsot::optimize::settings::Settings;
use fsot::quality::perceived::{ratio_to_white, TestSetup};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let kernel = args.get(1).map(String::as_str).unwrap_or("taa");
    let (w, h, t) = Tile::parse_size(args.get(2).map(String::as_str).unwrap_or("32x32x16"))?;
    let rule = match args.get(3).map(String::as_str).unwrap_or("momentum") {
        "adam" => StepRule::DEFAULT_ADAM,
        _ => StepRule::DEFAULT,
    };
    let counts: Vec<u32> = if args.len() > 4 {
        args[4..].iter().map(|s| s.parse()).collect::<Result<_, _>>()?
    } else {
        vec![5, 10, 20, 50, 100, 200, 500, 1000]
    };
    let tile = Tile::new(w, h, t, 1, 2)?;
    let spec = KernelSpec::from_name(kernel, 2.1, None, 0.1, 60.0)?;
    let setup = TestSetup::default();
    println!(
        "# {} kernel {} rule {:?}, {} threads",
        tile.describe(),
        spec.describe(),
        rule,
        rayon::current_num_threads()
    );
    println!(
        "# slices {:?} (FSOT_SLICES), step {:?} beta {:?} (FSOT_STEP, FSOT_BETA)",
        std::env::var("FSOT_SLICES").ok(),
        std::env::var("FSOT_STEP").ok(),
        std::env::var("FSOT_BETA").ok()
    );
    println!("iterations,seconds,objective,perceived_taa_ratio");
    for n in counts {
        let mut settings = Settings::new(spec, 7);
        settings.iterations = n;
        settings.rule = rule;
        // Exploration knobs: FSOT_SLICES (slices per iteration), FSOT_STEP and
        // FSOT_BETA (the momentum rule's step and beta).
        if let Some(v) = std::env::var("FSOT_SLICES").ok().and_then(|v| v.parse().ok()) {
            settings.slices = Some(v);
        }
        if let StepRule::Momentum { step, beta } = &mut settings.rule {
            if let Some(v) = std::env::var("FSOT_STEP").ok().and_then(|v| v.parse().ok()) {
                *step = v;
            }
            if let Some(v) = std::env::var("FSOT_BETA").ok().and_then(|v| v.parse().ok()) {
                *beta = v;
            }
        }
        let mut run = CpuRun::new(tile, settings, None)?;
        let start = Instant::now();
        while !run.finished() {
            run.step();
        }
        let seconds = start.elapsed().as_secs_f64();
        let mask = fsot::optimize::backend::Backend::mask(&run)?;
        let objective = score(&mask, spec, SCORE_SLICES).objective;
        let ratio = ratio_to_white(&mask, &setup, 4);
        println!("{n},{seconds:.3},{objective:.5e},{ratio:.4}");
    }
    Ok(())
}
