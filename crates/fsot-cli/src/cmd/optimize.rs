//! `fsot optimize`: the optimizer with checkpoints and interruption, and the peers' methods.

use crate::*;
use fsot::io::atomic::same_file;

pub(crate) fn optimize(args: OptimizeArgs) -> Result<()> {
    set_threads(args.threads)?;
    if let Some(scene) = &args.scene {
        return super::plan::optimize_scene(&args, scene);
    }
    // The peers' methods read --sigma and --sigma-t as their own energy's.
    if args.method == Method::Fsot {
        args.kernel.check_flags_apply()?;
    }
    let spec = args.kernel.spec()?;
    if args.init.is_some() && args.start != StartArg::Auto {
        return Err(Error::invalid("--init and --start both say where the run starts: give one"));
    }
    let init = args.init.as_deref().map(fsot::Mask::open).transpose()?;
    let (w, h, t) = match (&args.size, &init) {
        (Some(s), _) => Tile::parse_size(s)?,
        (None, Some(m)) => (m.tile.width, m.tile.height, m.tile.frames),
        (None, None) => (64, 64, 16),
    };
    let dims = args.dims.or(init.as_ref().map(|m| m.tile.dims)).unwrap_or(2);
    let spp = args.spp.or(init.as_ref().map(|m| m.tile.spp)).unwrap_or(1);
    let tile = Tile::new(w, h, t, spp, dims)?;
    note_unused(&args, &tile);
    let until = match &args.budget {
        Some(text) => Until::Seconds(parse_seconds(text)?),
        None => parse_until(args.until.as_deref())?,
    };
    let iterations = args.iterations.unwrap_or(match until {
        Until::Iterations => fsot::optimize::settings::DEFAULT_ITERATIONS,
        _ => fsot::optimize::settings::DEFAULT_CAP,
    });
    if iterations == 0 {
        return Err(Error::invalid("--iterations must be at least 1"));
    }
    if let Some(share) = args.axis_share.filter(|s| !(0.0..=1.0).contains(s)) {
        return Err(Error::invalid(format!("--axis-share must be between 0 and 1, got {share:?}")));
    }
    // Check the output's kind and reserve it before the long work: a bad path or
    // a format that cannot hold d fails now.
    // --ktx2-format applies to the .ktx2 outputs, --out's or --also's.
    let is_ktx2 = |p: &std::path::Path| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("ktx2"));
    if let Some(f) = args.ktx2_format.as_deref() {
        if !is_ktx2(&args.out) && !args.also.iter().any(|p| is_ktx2(p)) {
            return Err(Error::invalid(format!(
                "a KTX2 format ({f}) was given, but neither --out nor --also names a .ktx2 file"
            )));
        }
    }
    let format_for = |p: &std::path::Path| args.ktx2_format.as_deref().filter(|_| is_ktx2(p));
    let file_kind = MaskFile::for_path(&args.out, dims, format_for(&args.out))?;
    let out = AtomicFile::create(&args.out)?;
    let also = args
        .also
        .iter()
        .map(|p| Ok((MaskFile::for_path(p, dims, format_for(p))?, AtomicFile::create(p)?)))
        .collect::<Result<Vec<_>>>()?;
    fsot::io::atomic::distinct(std::iter::once(&out).chain(also.iter().map(|(_, file)| file)))?;
    if let Some(dir) = &args.png {
        if let Some(file) = std::iter::once(&args.out).chain(&args.also).find(|o| same_file(o, dir)) {
            return Err(Error::invalid(format!(
                "--png {} is also the output {}: give the slices a folder of their own",
                dir.display(),
                file.display()
            )));
        }
        check_png_folder(dir, &tile)?;
    }
    if args.method != Method::Fsot {
        if args.checkpoint.is_some() || args.resume || args.axis_share.is_some() {
            return Err(Error::invalid("--checkpoint, --resume and --axis-share are for --method fsot"));
        }
        return make_baseline(&args, tile, spec, init.as_ref(), file_kind, out, also);
    }
    let mut settings = Settings::new(spec, args.seed.unwrap_or(0));
    settings.iterations = iterations;
    settings.until = until;
    settings.slices = args.slices;
    settings.start = match args.start {
        StartArg::Auto => fsot::Start::Auto,
        StartArg::Animated => fsot::Start::Animated,
        StartArg::White => fsot::Start::White,
        StartArg::Coarse => fsot::Start::Coarse,
    };
    if let Some(share) = args.axis_share {
        settings.axis_share = share;
        if dims == 1 {
            eprintln!("note: --axis-share does nothing at d = 1: every slice lies along the one axis");
        }
    }
    let mut run = Run::start(tile, settings, init.as_ref(), run_options(&args)?)?;
    eprintln!("backend: {}", run.note());
    if let (Some(from), Some(p)) = (run.resumed_from(), &args.checkpoint) {
        eprintln!("resumed from {} at iteration {from}", p.display());
    }
    let length = match until {
        Until::Iterations => format!("{iterations} iterations"),
        Until::Plateau(_) => format!("until iterations no longer pay (at most {iterations})"),
        Until::Objective(x) => {
            format!("until the objective is at most {x:e} (at most {iterations} iterations)")
        }
        Until::Seconds(s) => format!("for {s} s (at most {iterations} iterations)"),
        _ => format!("at most {iterations} iterations"),
    };
    let axes = match args.axis_share {
        Some(share) if dims >= 2 => format!(", {share} of them along one axis"),
        _ => String::new(),
    };
    eprintln!(
        "optimizing {} for kernel {}: {length} x {} slices{axes}",
        tile.describe(),
        spec.describe(),
        run.backend().slices_per_iteration()
    );
    if let Some(note) = run.start_note() {
        eprintln!("start: {note}");
    }
    let bar = iteration_bar(iterations, run.iteration());
    // Ctrl-C or SIGTERM from here on stops between iterations, after a checkpoint.
    let cancel = cmd::env::interrupt_flag()?;
    let start = Instant::now();
    let outcome = run.run(&cancel, &mut |event| match event {
        Event::Progress { iteration, objective, .. } => {
            bar.set_position(iteration as u64);
            if let Some(c) = objective {
                bar.set_message(format!("{c:.3e}"));
            }
        }
        Event::Checkpoint { .. } => {}
        Event::FellBack { error, at, backend, from, checkpoint } => {
            bar.suspend(|| {
                eprintln!("warning: the GPU failed at iteration {at}: {error}");
                let source = match checkpoint {
                    Some(p) => format!("its checkpoint {} (iteration {from})", p.display()),
                    None => "the start".to_string(),
                };
                eprintln!("backend: {backend}; continuing from {source}");
            });
            bar.set_position(from as u64);
        }
        _ => {}
    })?;
    bar.finish_and_clear();
    if let Outcome::Cancelled { iteration, saved } = outcome {
        match saved {
            Some(p) => eprintln!(
                "interrupted at iteration {iteration} of {iterations}: state saved to {}; continue with the same command and --resume",
                p.display()
            ),
            None => eprintln!(
                "interrupted at iteration {iteration} of {iterations}: nothing written, {} untouched (--checkpoint FILE makes runs resumable)",
                args.out.display()
            ),
        }
        return Err(Error::Interrupted);
    }
    let seconds = start.elapsed().as_secs_f64();
    let since_start = run.elapsed();
    let set_up = run.set_up();
    let (iterations, kind, report) = (run.iteration(), run.backend_kind(), run.report());
    let start_samples = run.start_samples()?;
    // A resumed run knows its start again only where it is made from the seed
    // or given (a white start, --init); an animated or coarse start is not kept.
    let s = run.settings();
    let cap = s.iterations;
    let start_lost = run
        .resumed_from()
        .filter(|_| init.is_none() && (s.start.animates(s.until, &tile) || s.start == fsot::Start::Coarse));
    let mut scored = Vec::new();
    // The outputs are written before the checkpoint goes: a failed write leaves
    // it to resume from.
    run.finish_with(|mask| {
        // Scored after the run, so that a time budget is the run's alone.
        let after = mask.samples.clone();
        scored = unless_interrupted(&cancel, &args.out, move || {
            scores(&tile, &[&start_samples, &after], spec, SCORE_SLICES)
        })?;
        write_outputs(&args, mask, (file_kind, out), also, &cancel)
    })?;
    let (before, after) = (scored[0], scored[1]);
    let before = match start_lost {
        None => format!("{:.4e} -> ", before.objective),
        Some(from) => format!("(resumed from iteration {from}: the start's not kept) "),
    };
    let printed = (|| -> Result<()> {
        outln!(
            "wrote {}: {}, kernel {}, {iterations} iterations in {seconds:.1} s ({}); objective {before}{:.4e} ({:.3} x white noise)",
            args.out.display(),
            tile.describe(),
            spec.describe(),
            kind.name(),
            after.objective,
            after.ratio()
        )?;
        if let Until::Seconds(budget) = until {
            // A run its cap ended before the budget did says so: more
            // iterations (--iterations) would have gone further.
            let capped = if iterations >= cap {
                format!(" at its cap of {iterations} iterations (--iterations)")
            } else {
                String::new()
            };
            outln!(
                "budget {budget} s: the run ended{capped} {since_start:.3} s after the process started ({:+.3} s); \
                 before the first iteration {:.3} s, of which the start {:.3} s and the backend {:.3} s",
                since_start - budget,
                since_start - seconds,
                set_up.start,
                set_up.backend
            )?;
        }
        Ok(())
    })();
    // The report's warnings and validation errors whether or not standard
    // output took the lines above; its error first.
    backend_report(&report).and(printed)
}

/// `--until`: plateau, objective:X, or none (a fixed count).
fn parse_until(text: Option<&str>) -> Result<Until> {
    let Some(text) = text else { return Ok(Until::Iterations) };
    if text == "plateau" {
        return Ok(Until::Plateau(fsot::core::step_rule::Plateau::DEFAULT));
    }
    match text.strip_prefix("objective:").map(|x| x.trim().parse::<f64>()) {
        Some(Ok(x)) if x.is_finite() && x > 0.0 => Ok(Until::Objective(x)),
        _ => Err(Error::invalid(format!(
            "--until must be `plateau` or `objective:X` with X > 0, got {text:?}"
        ))),
    }
}

/// `--budget`: a wall time, `1s`, `500ms`, `2.5` (seconds) or `1m`.
pub(crate) fn parse_seconds(text: &str) -> Result<f64> {
    fsot::optimize::settings::parse_budget(text).map_err(|e| Error::invalid(format!("--budget {e}")))
}

/// The library run's options from the flags and the environment.
fn run_options(args: &OptimizeArgs) -> Result<RunOptions> {
    let checkpoint = match (&args.checkpoint, args.resume) {
        (None, true) => {
            return Err(Error::invalid("--resume needs --checkpoint FILE (the file to continue)"))
        }
        (None, false) => None,
        (Some(_), _) if args.checkpoint_every == 0 => {
            return Err(Error::invalid("--checkpoint-every must be at least 1"))
        }
        (Some(path), _) if std::iter::once(&args.out).chain(&args.also).any(|o| same_file(o, path)) => {
            return Err(Error::invalid(format!(
                "--checkpoint {} is also an output: give the run's state a file of its own",
                path.display()
            )))
        }
        (Some(path), resume) => {
            Some(Checkpointing { path: path.clone(), every: args.checkpoint_every, resume })
        }
    };
    let backend = args.backend.choice();
    let vulkan = VulkanOptions::default().deterministic(args.deterministic).profile(args.profile);
    Ok(RunOptions::default()
        .backend(backend)
        .device(env::device(args.device.clone()))
        .validation(env::validation())
        .vulkan(vulkan)
        .checkpoint(checkpoint)
        .budget_from(crate::process_start()))
}

/// The progress bar of a run (hidden when stderr is not a terminal).
fn iteration_bar(iterations: u32, at: u32) -> ProgressBar {
    let bar = ProgressBar::new(iterations as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} iterations, {elapsed} elapsed, {eta} left, objective {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_position(at as u64);
    bar
}

/// After a run: skipped large classes, the profile, validation messages (an
/// error, before one writing the profile gave).
fn backend_report(report: &Report) -> Result<()> {
    if report.skipped_large_classes > 0 {
        eprintln!(
            "warning: {} large classes did not fit their buffer and were skipped",
            report.skipped_large_classes
        );
    }
    let printed = print_profile(report);
    let messages = &report.validation_messages;
    if !messages.is_empty() {
        eprintln!("{} validation messages:", messages.len());
        for m in messages.iter().take(10) {
            eprintln!("  {m}");
        }
        return Err(Error::invalid("the Vulkan validation layer reported errors"));
    }
    printed
}

/// The run's profile, where one was taken, on standard output.
fn print_profile(report: &Report) -> Result<()> {
    if let Some(p) = &report.profile {
        let per = |ns: f64| ns / p.iterations.max(1) as f64 * 1e-6;
        outln!(
            "profile ({} iterations, per iteration): transport {:.3} ms, large classes {:.3} ms, update {:.3} ms",
            p.iterations,
            per(p.transport_ns),
            per(p.large_ns),
            per(p.update_ns)
        )?;
        // The least bytes each pass must move, and the rate its time gives.
        let rate = |bytes: f64, ns: f64| {
            let ms = per(ns);
            if ms > 0.0 {
                format!("{:.2} MB, {:.1} GB/s", bytes * 1e-6, bytes / (ms * 1e-3) * 1e-9)
            } else {
                format!("{:.2} MB", bytes * 1e-6)
            }
        };
        outln!(
            "  least bytes per iteration (a model): transport {}; large classes {}; update {}",
            rate(p.transport_bytes, p.transport_ns),
            rate(p.large_bytes, p.large_ns),
            rate(p.update_bytes, p.update_ns)
        )?;
    }
    if let (Some(_), Some(transport)) = (&report.profile, &report.transport) {
        outln!("  transport: {transport}")?;
    }
    if let (Some(_), Some(choice)) = (&report.profile, &report.large_sort) {
        outln!("  large-class sort: {choice}")?;
    }
    Ok(())
}

/// Progress of a swap search, hidden when there is none (void-and-cluster).
pub(crate) fn swap_bar(passes: u32, shown: bool) -> ProgressBar {
    if !shown {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(passes as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} passes, {elapsed} elapsed, {eta} left, energy {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

/// The peers' methods: same tile, same files, time reported.
pub(crate) fn make_baseline(
    args: &OptimizeArgs,
    tile: Tile,
    spec: KernelSpec,
    init: Option<&fsot::Mask>,
    kind: MaskFile,
    out: AtomicFile,
    also: Vec<(MaskFile, AtomicFile)>,
) -> Result<()> {
    let swaps = args.method == Method::Fast || (args.method == Method::Stbn && tile.dims > 1);
    if swaps && !(1..=100_000).contains(&args.passes) {
        return Err(Error::invalid(format!("--passes must be in 1..=100000, got {}", args.passes)));
    }
    let method = match args.method {
        Method::White => fsot::peers::method::Method::White,
        Method::Stbn => {
            let sigma = args.kernel.sigma.unwrap_or(fsot::peers::stbn::DEFAULT_SIGMA);
            fsot::peers::method::Method::Stbn {
                sigma,
                sigma_t: args.kernel.sigma_t.unwrap_or(sigma),
                passes: args.passes,
            }
        }
        Method::Fast => fsot::peers::method::Method::Fast {
            spec: fsot::peers::fast::FastSpec {
                spatial: Filter::parse(&args.fast_spatial, false)?,
                temporal: Filter::parse(&args.fast_temporal, true)?,
                combine: Combine::parse(&args.fast_combine)
                    .map_err(|e| Error::invalid(format!("--fast-combine: {e}")))?,
            },
            passes: args.passes,
        },
        Method::Fsot => return Err(Error::invalid("fsot runs through the library run")),
    };
    // The swap searches go where --backend says, as fsot's runs do; white noise
    // and void-and-cluster are made on the CPU.
    let mut device = if method.swaps(&tile) {
        let (device, note) = fsot::peers::swap::swap_device(&run_options(args)?)?;
        eprintln!("backend: {note}");
        device
    } else {
        SwapDevice::Cpu
    };
    let start = Instant::now();
    let bar = swap_bar(args.passes, method.swaps(&tile));
    let seed = args.seed.unwrap_or(0);
    let mut on_pass = |_, e: f64| {
        bar.inc(1);
        bar.set_message(format!("{e:.6e}"));
    };
    let made = match fsot::peers::method::make(&method, tile, seed, init, &device, &mut on_pass) {
        // As fsot's runs do under auto: a GPU that cannot take the search (an
        // energy past its shaders' budget, a lost device) hands it to the CPU,
        // which starts it again.
        Err(e) if e.is_device_failure() && args.backend == Backend::Auto && device.kind() != "cpu" => {
            bar.reset();
            device = SwapDevice::Cpu;
            eprintln!("note: {e}; the search runs on the {}", device.describe());
            fsot::peers::method::make(&method, tile, seed, init, &device, &mut on_pass)?
        }
        made => made?,
    };
    bar.finish_and_clear();
    if let Some(note) = &made.note {
        eprintln!("{note}");
    }
    if let SwapDevice::Vulkan(ctx) = &device {
        backend_report(&Report { validation_messages: ctx.validation_messages(), ..Report::default() })?;
    }
    let mask = made.mask;
    let seconds = start.elapsed().as_secs_f64();
    let cancel = cmd::env::interrupt_flag()?;
    let scored = mask.clone();
    let s = unless_interrupted(&cancel, &args.out, move || score(&scored, spec, SCORE_SLICES))?;
    write_outputs(args, &mask, (kind, out), also, &cancel)?;
    outln!(
        "wrote {}: {}, method {}, {seconds:.1} s; objective under kernel {}: {:.4e} ({:.3} x white noise)",
        args.out.display(),
        tile.describe(),
        args.method.to_possible_value().map(|v| v.get_name().to_string()).unwrap_or_default(),
        spec.describe(),
        s.objective,
        s.ratio()
    )?;
    Ok(())
}

/// A note for each flag given that the method has no use for (the same flags
/// can then be given to every method).
fn note_unused(args: &OptimizeArgs, tile: &Tile) {
    let (fsot, fast) = (args.method == Method::Fsot, args.method == Method::Fast);
    let swaps = fast || (args.method == Method::Stbn && tile.dims > 1);
    let unused = [
        ("passes", "--passes", !swaps, "is for the swap methods (fast, stbn with d >= 2)"),
        ("fast_spatial", "--fast-spatial", !fast, "is for --method fast"),
        ("fast_temporal", "--fast-temporal", !fast, "is for --method fast"),
        ("fast_combine", "--fast-combine", !fast, "is for --method fast"),
        ("iterations", "--iterations", !fsot, "is for --method fsot"),
        ("slices", "--slices", !fsot, "is for --method fsot"),
        ("until", "--until", !fsot, "is for --method fsot"),
        ("budget", "--budget", !fsot, "is for --method fsot"),
        ("checkpoint_every", "--checkpoint-every", args.checkpoint.is_none(), "needs --checkpoint"),
    ];
    for (id, flag, idle, what) in unused {
        if idle && args.given.iter().any(|g| g == id) {
            eprintln!("note: {flag} does nothing here: it {what}");
        }
    }
}

/// `--png`'s folder, checked before the long work: an existing folder whose
/// slice files can each be replaced, or a folder that can be made.
fn check_png_folder(dir: &std::path::Path, tile: &Tile) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::invalid(format!("--png {} exists and is not a folder", dir.display())));
    }
    if dir.is_dir() {
        let names = fsot::io::png::names(tile);
        for name in &names {
            AtomicFile::create(&dir.join(name))?;
        }
        // Slices of another mask that these would not replace: the folder
        // would hold a mixed set.
        let mut stale: Vec<String> = std::fs::read_dir(dir)
            .map_err(|e| Error::invalid(format!("--png {}: cannot list it: {e}", dir.display())))?
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter(|n| n.starts_with("frame") && n.ends_with(".png") && !names.contains(n))
            .collect();
        stale.sort();
        if let Some(first) = stale.first() {
            return Err(Error::invalid(format!(
                "--png {} holds {first}{} of another mask's slices, which this mask's {} would not \
                 replace: remove them or give another folder",
                dir.display(),
                match stale.len() {
                    1 => String::new(),
                    n => format!(" and {} more", n - 1),
                },
                names.len()
            )));
        }
        return Ok(());
    }
    let parent = dir.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(std::path::Path::new("."));
    if !parent.is_dir() {
        return Err(Error::invalid(format!(
            "--png {}: {} is not a folder to make it in",
            dir.display(),
            parent.display()
        )));
    }
    // Reserving the folder's name as a file checks that its parent takes writes.
    AtomicFile::create(dir).map(drop)
}

/// Every output (`--out`, `--also`, `--png`'s slices) written in full before any
/// is renamed into place: one that cannot be written leaves every file as it was.
/// A Ctrl-C or SIGTERM that came while they were made stops before any is replaced.
fn write_outputs(
    args: &OptimizeArgs,
    mask: &fsot::Mask,
    out: (MaskFile, AtomicFile),
    also: Vec<(MaskFile, AtomicFile)>,
    cancel: &fsot::CancelFlag,
) -> Result<()> {
    let mut outputs = Vec::new();
    for (kind, file) in std::iter::once(out).chain(also) {
        let bytes = kind.encode(mask, file.target())?;
        outputs.push((file, bytes));
    }
    let files = outputs.len();
    if let Some(dir) = &args.png {
        outputs.extend(fsot::io::png::outputs(mask, dir, args.png_bits)?);
    }
    let slices = outputs.len() - files;
    if cancel.is_cancelled() {
        eprintln!("interrupted: nothing written, {} untouched", args.out.display());
        return Err(Error::Interrupted);
    }
    fsot::io::atomic::commit_all(outputs)?;
    if let Some(dir) = &args.png {
        eprintln!("wrote {slices} PNG slices into {}", dir.display());
    }
    Ok(())
}

/// `work` (scoring the mask for the report) on a thread of its own, so that a
/// Ctrl-C or SIGTERM ends the command at once instead of after it; nothing has
/// been written then.
fn unless_interrupted<T: Send + 'static>(
    cancel: &fsot::CancelFlag,
    out: &std::path::Path,
    work: impl FnOnce() -> T + Send + 'static,
) -> Result<T> {
    let worker = std::thread::spawn(work);
    while !worker.is_finished() {
        if cancel.is_cancelled() {
            eprintln!("interrupted while scoring the mask: nothing written, {} untouched", out.display());
            return Err(Error::Interrupted);
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    worker.join().map_err(|_| Error::invalid("scoring the mask failed"))
}
