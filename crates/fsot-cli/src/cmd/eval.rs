//! `fsot eval`: the evaluation over animated scenes.

use crate::*;

/// The most mask seeds (placements of a published mask) `--seeds` takes: a bound
/// on a mistyped count, about three hours of renders per method on 2 cores.
const MAX_SEEDS: u32 = 10_000;

pub(crate) fn eval_command(args: EvalArgs) -> Result<()> {
    use fsot_cli::eval::robustness;
    use fsot_cli::eval::scenes::SCENES;
    use fsot_cli::eval::suite::{cache_dir, run_eval, to_json, to_markdown, EvalSize};
    // The seed's two columns in the full run; the first alone in --quick.
    let sigmas = match (&args.sigma[..], args.quick) {
        ([], true) => vec![2.1],
        ([], false) => vec![2.1, 1.9],
        (given, _) => given.to_vec(),
    };
    for &s in &sigmas {
        if !(0.01..=8.0).contains(&s) {
            return Err(Error::invalid(format!("--sigma must be in [0.01, 8], got {s:?}")));
        }
    }
    let scenes: Vec<_> = if args.scenes.is_empty() {
        SCENES.to_vec()
    } else {
        args.scenes
            .iter()
            .map(|name| {
                SCENES.iter().copied().find(|s| s.name() == name).ok_or_else(|| {
                    let names: Vec<_> = SCENES.iter().map(|s| s.name()).collect();
                    Error::invalid(format!("unknown scene `{name}` (one of {})", names.join(", ")))
                })
            })
            .collect::<Result<_>>()?
    };
    // Masks to measure besides the methods, read before anything is written.
    let mut own = Vec::new();
    for spec in &args.masks {
        let (name, file) = spec
            .split_once('=')
            .filter(|(n, f)| !n.is_empty() && !f.is_empty())
            .ok_or_else(|| Error::invalid(format!("--mask {spec:?}: expected NAME=FILE")))?;
        let taken = fsot_cli::eval::suite::METHODS.contains(&name) || name.starts_with("published-");
        if taken || name.starts_with("fsot-planned") || own.iter().any(|(n, _)| n == name) {
            return Err(Error::invalid(format!("--mask {spec:?}: the name {name} is taken")));
        }
        own.push((name.to_string(), fsot::Mask::open(file)?));
    }
    let mut size = if args.quick { EvalSize::quick() } else { EvalSize::full() };
    size.anatomy = args.anatomy;
    size.flip = args.flip;
    size.grey = match args.grey {
        GreyArg::Luminance => fsot_cli::eval::jod::Grey::Luminance,
        GreyArg::Rgb => fsot_cli::eval::jod::Grey::Rgb,
    };
    size.judged = match args.taa {
        TaaArg::Both => [true, true],
        TaaArg::With => [false, true],
        TaaArg::Without => [true, false],
    };
    if let Some(i) = args.iterations {
        if !(1..=1_000_000).contains(&i) {
            return Err(Error::invalid(format!("--iterations must be in 1..=1000000, got {i}")));
        }
        size.iterations = i;
    }
    if let Some(k) = args.seeds {
        if !(2..=MAX_SEEDS).contains(&k) {
            return Err(Error::invalid(format!(
                "--seeds must be in 2..={MAX_SEEDS} (an interval needs two), got {k}"
            )));
        }
        size.seeds = k;
        if args.quick {
            size.planned_masks = k;
        }
    }
    if let Some(k) = args.planned_masks {
        if k != 1 && k != size.seeds {
            return Err(Error::invalid(format!(
                "--planned-masks must be 1 (one mask judged at every placement) or the seeds, {} \
                 (a mask per seed), got {k}",
                size.seeds
            )));
        }
        size.planned_masks = k;
    }
    if !args.display.is_empty() {
        let names = colorvideovdp::DisplayModel::names()
            .map_err(|e| Error::invalid(format!("ColorVideoVDP: {e}")))?;
        let mut chosen = Vec::new();
        for d in &args.display {
            let name = names.iter().copied().find(|n| n == d).ok_or_else(|| {
                Error::invalid(format!("unknown display {d:?}; one of {}", names.join(", ")))
            })?;
            if !chosen.contains(&name) {
                chosen.push(name);
            }
        }
        size.displays = chosen;
    }
    let planned_measured = args.methods.is_empty() || args.methods.iter().any(|m| m == "fsot-planned");
    if size.planned && planned_measured {
        for d in &size.displays {
            fsot::core::display::preset_ppd(d).map_err(|_| {
                Error::invalid(format!(
                    "fsot-planned needs the geometry of display {d:?}, which fsot does not know"
                ))
            })?;
        }
    }
    if let Some(p) = args.passes {
        if !(1..=100_000).contains(&p) {
            return Err(Error::invalid(format!("--passes must be in 1..=100000, got {p}")));
        }
        size.passes = p;
    }
    let start = Instant::now();
    let mut published = Vec::new();
    if let Some(dir) = &args.peers {
        for (name, file) in [
            ("published-stbn", "real_stbn.png"),
            ("published-fast", "real_uniform_gauss_1.3435_exponential_0.1_0.1_product.png"),
        ] {
            published.push((name.to_string(), fsot::io::stacked_png::read(&dir.join(file))?));
        }
    }
    published.extend(own);
    let pictures = args.out.join("pictures");
    let cache = cache_dir(&args.out);
    let known: Vec<&str> = fsot_cli::eval::suite::METHODS
        .iter()
        .copied()
        .chain(published.iter().map(|p| p.0.as_str()))
        .chain(["fsot-planned"])
        .collect();
    if let Some(unknown) = args.methods.iter().find(|m| !known.contains(&m.as_str())) {
        return Err(Error::invalid(format!(
            "--methods: unknown method `{unknown}` (one of {})",
            known.join(", ")
        )));
    }
    // Every flag and input is checked; now the folder is made and the outputs
    // reserved, before the long work: a bad path fails here, a bad flag left
    // nothing behind.
    fsot::io::atomic::make_folder(&args.out)?;
    let md = AtomicFile::create(&args.out.join("results.md"))?;
    let js = AtomicFile::create(&args.out.join("results.json"))?;
    let rb = AtomicFile::create(&args.out.join("robustness.json"))?;
    let extra = args.json.as_ref().map(|p| AtomicFile::create(p)).transpose()?;
    let anatomy_file = args.anatomy.then(|| AtomicFile::create(&args.out.join("anatomy.md"))).transpose()?;
    let only = match args.methods.is_empty() {
        true => fsot_cli::eval::suite::Only::All,
        false => fsot_cli::eval::suite::Only::Named(&args.methods),
    };
    let records = run_eval(&size, &sigmas, &scenes, &cache, Some(&pictures), &published, only, |line| {
        eprintln!("{line}")
    })?;
    // Judges that differ from the optimizer, on the sigma 2.1 column's masks
    // (every method's, in both TAA settings: not with --methods or --taa).
    let robust = match sigmas.contains(&robustness::MADE_FOR_SIGMA)
        && args.methods.is_empty()
        && args.taa == TaaArg::Both
    {
        true => {
            let r = robustness::run_robustness(&size, &scenes, &cache, |line| eprintln!("{line}"))?;
            rb.commit(format!("{}\n", serde_json::to_string_pretty(&r).unwrap_or_default()).as_bytes())?;
            robustness::to_markdown(&r)
        }
        false => String::new(),
    };
    let json = to_json(&records)?;
    let t = size.tile;
    let table = format!(
        "# fsot eval{}\n\nfsot {} (commit {}) on {}.\n\nMasks {}x{}x{}, d = {}, {} iterations (fsot) or {} passes (swap methods); images {} x {}, {} frames, \
         {} warm-up, {} mask seeds per method with {} render{} each (fsot-planned: {} mask{} per setting at the seeds' placements), references {} samples per pixel; TAA alpha 0.1; eps 0.01; \
         JOD: ColorVideoVDP (colorvideovdp {}) on the {} display{} at 60 fps, frames after the warm-up, tone-mapped by the \
         reference's brightest pixel and sRGB-encoded, grey as {}.{} Run time {:.0} s.\n{}",
        if args.quick { " --quick" } else { "" },
        env!("CARGO_PKG_VERSION"),
        env!("FSOT_COMMIT"),
        fsot_cli::bench::machine::cpu_description(),
        t.width,
        t.height,
        t.frames,
        t.dims,
        size.iterations,
        size.passes,
        size.shot.image,
        size.shot.image,
        size.shot.frames,
        size.warmup,
        size.seeds,
        size.renders,
        if size.renders == 1 { "" } else { "s" },
        size.planned_masks,
        if size.planned_masks == 1 { "" } else { "s" },
        size.reference_samples,
        fsot_cli::eval::jod::CRATE_VERSION,
        size.displays.join(" and "),
        if size.displays.len() > 1 { "s" } else { "" },
        match size.grey {
            fsot_cli::eval::jod::Grey::Luminance => "one luminance channel",
            fsot_cli::eval::jod::Grey::Rgb => "three equal RGB channels",
        },
        match (args.taa, size.planned && !size.planned_without_taa) {
            (TaaArg::With, _) => " Judged with TAA only.",
            (TaaArg::Without, _) => " Judged without TAA only.",
            (TaaArg::Both, true) => " fsot-planned: the TAA plan only (its no-TAA plan left out for time).",
            (TaaArg::Both, false) => "",
        },
        start.elapsed().as_secs_f64(),
        to_markdown(&records) + &robust
    );
    md.commit(table.as_bytes())?;
    if let Some(f) = anatomy_file {
        let text = format!(
            "# fsot eval: the error's anatomy\n\nfsot {} (commit {}); judged on {}; bands as in crates/fsot-cli/src/eval/anatomy.rs.\n{}",
            env!("CARGO_PKG_VERSION"),
            env!("FSOT_COMMIT"),
            size.displays.join(" and "),
            fsot_cli::eval::suite::anatomy_markdown(&records)
        );
        f.commit(text.as_bytes())?;
    }
    js.commit(json.as_bytes())?;
    if let Some(f) = extra {
        f.commit(json.as_bytes())?;
    }
    outln!("{table}")?;
    Ok(())
}
