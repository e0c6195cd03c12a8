//! The end-agnostic plateau schedule against fixed cosine runs: a CPU run stepped
//! until the plateau rule stops it, timed and judged by the independent
//! perceived-error test under TAA.
//!
//! cargo run --release --example plateau -- [kernel] [WxHxT] [decay_below] [stop_below] [factor]
use std::time::Instant;

use fsot::core::kernel::KernelSpec;
use fsot::core::objective::{score, SCORE_SLICES};
use fsot::core::step_rule::{Plateau, PlateauState};
use fsot::core::tile::Tile;
use fsot::optimize::backend::Backend;
use fsot::optimize::cpu::CpuRun;
use fsot::optimize::settings::Settings;
use fsot::quality::perceived::{ratio_to_white, TestSetup};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let kernel = args.get(1).map(String::as_str).unwrap_or("taa");
    let (w, h, t) = Tile::parse_size(args.get(2).map(String::as_str).unwrap_or("32x32x16"))?;
    let decay_below = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(Plateau::DEFAULT.decay_below);
    let stop_below = args.get(4).map(|s| s.parse()).transpose()?.unwrap_or(Plateau::DEFAULT.stop_below);
    let factor = args.get(5).map(|s| s.parse()).transpose()?.unwrap_or(Plateau::DEFAULT.factor);
    let rule = Plateau { decay_below, stop_below, factor, ..Plateau::DEFAULT };
    rule.check()?;
    let tile = Tile::new(w, h, t, 1, 2)?;
    let spec = KernelSpec::from_name(kernel, 2.1, None, 0.1, 60.0)?;
    let mut settings = Settings::new(spec, 7);
    settings.iterations = 20_000; // a cap only
    let mut run = CpuRun::new(tile, settings, None)?;
    let mut state = PlateauState::default();
    let start = Instant::now();
    let mut trace = Vec::new();
    loop {
        run.set_scale(Some(state.scale));
        let cost = run.step();
        if state.observe(&rule, cost) || run.finished() {
            break;
        }
        if state.count == 0 {
            trace.push(format!("{}:{}", run.iteration(), state.scale));
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    let mask = run.mask()?;
    println!(
        "{} {} {rule:?}: {} iterations, {seconds:.2} s, objective {:.5e}, perceived (TAA) {:.4}",
        tile.describe(),
        spec.describe(),
        run.iteration(),
        score(&mask, spec, SCORE_SLICES).objective,
        ratio_to_white(&mask, &TestSetup::default(), 4)
    );
    println!("windows (iteration:scale): {}", trace.join(" "));
    Ok(())
}
