//! Tuning harness: optimizes one tile under several step rules and reports time,
//! objective and the independent perceived-error ratio (TAA) along the way.
//! cargo run --release --example tune -- [kernel] [iterations] [rule...]
use fsot::eval::perceived::{ratio_to_white, TestSetup};
use fsot::kernel::KernelSpec;
use fsot::optimize::{Run, Settings};
use fsot::optimizer::StepRule;
use fsot::problem::Tile;
use std::time::Instant;

fn parse_rule(s: &str) -> StepRule {
    let parts: Vec<&str> = s.split(':').collect();
    let num = |i: usize| parts[i].parse::<f32>().unwrap();
    match parts[0] {
        "m" => StepRule::Momentum { step: num(1), beta: num(2) },
        "adam" => StepRule::Adam { lr: num(1), beta1: 0.9, beta2: 0.99, eps: 1e-8 },
        _ => panic!("rule m:step:beta or adam:lr"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kernel = args.get(1).map(|s| s.as_str()).unwrap_or("taa");
    let iterations: u32 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(500);
    let hits: Option<u32> = std::env::var("SLICES").ok().map(|s| s.parse().unwrap());
    let rules: Vec<StepRule> = if args.len() > 3 { args[3..].iter().map(|s| parse_rule(s)).collect() } else { vec![StepRule::DEFAULT] };
    let tile = Tile::new(32, 32, 16, 1, 2).unwrap();
    let setup = TestSetup::default();
    let spec = KernelSpec::from_name(kernel, 2.1, None, 0.1, 60.0).unwrap();
    let white = fsot::mask::Mask::white(tile, 7);
    println!("white ratio {:.3}", ratio_to_white(&white, &setup, 4));
    for rule in rules {
        let mut settings = Settings::new(spec, 7);
        settings.iterations = iterations;
        settings.rule = rule;
        settings.slices = hits;
        let mut run = Run::new(tile, settings, None).unwrap();
        let start = Instant::now();
        let mut last = 0.0;
        while !run.finished() {
            last = run.step();
            let i = run.iteration();
            if i % (iterations / 4).max(1) == 0 {
                let m = run.mask();
                println!("{rule:?} it {i} t {:.1}s obj {last:.3e} ratio {:.3}", start.elapsed().as_secs_f64(), ratio_to_white(&m, &setup, 4));
            }
        }
        let _ = last;
    }
}
