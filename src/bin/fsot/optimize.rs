//! `fsot optimize`: the optimizer with checkpoints and interruption, and the peers' methods.

use super::*;

pub(crate) fn optimize(args: OptimizeArgs) -> Result<()> {
    set_threads(args.threads)?;
    let spec = args.kernel.spec()?;
    let init = args.init.as_deref().map(fsot::io::exr::read).transpose()?;
    let (w, h, t) = match (&args.size, &init) {
        (Some(s), _) => Tile::parse_size(s)?,
        (None, Some(m)) => (m.tile.width, m.tile.height, m.tile.frames),
        (None, None) => (64, 64, 16),
    };
    let dims = args.dims.or(init.as_ref().map(|m| m.tile.dims)).unwrap_or(2);
    let spp = args.spp.or(init.as_ref().map(|m| m.tile.spp)).unwrap_or(1);
    let tile = Tile::new(w, h, t, spp, dims)?;
    if args.iterations == 0 {
        return Err(Error::invalid("--iterations must be at least 1"));
    }
    // Reserve the outputs before the long work: a bad path fails now.
    let out = AtomicFile::create(&args.out)?;
    if let Some(dir) = &args.png {
        if dir.exists() && !dir.is_dir() {
            return Err(Error::invalid(format!("--png {} exists and is not a folder", dir.display())));
        }
    }
    if args.method != Method::Fsot {
        if args.checkpoint.is_some() || args.resume {
            return Err(Error::invalid("--checkpoint and --resume are for --method fsot"));
        }
        return make_baseline(&args, tile, spec, out);
    }
    let choice = match args.backend {
        Backend::Auto => BackendChoice::Auto,
        Backend::Cpu => BackendChoice::Cpu,
        Backend::Vulkan => BackendChoice::Vulkan,
    };
    let mut settings = Settings::new(spec, args.seed);
    settings.iterations = args.iterations;
    settings.slices = args.slices;
    let fingerprint = fsot::checkpoint::fingerprint(&tile, &settings);
    let saved = saved_state(&args, &fingerprint, &tile)?;
    let gpu = GpuOptions { deterministic: args.deterministic, profile: args.profile, transport: None };
    let Started { mut engine, note } =
        Engine::start(choice, tile, settings, init.as_ref(), args.device.clone(), gpu)?;
    eprintln!("{note}");
    if let (Some(state), Some(p)) = (&saved, &args.checkpoint) {
        engine.restore(state)?;
        eprintln!("resumed from {} at iteration {}", p.display(), state.iteration);
    }
    eprintln!(
        "optimizing {} for kernel {}: {} iterations x {} slices",
        tile.describe(),
        spec.describe(),
        args.iterations,
        engine.slices_per_iteration()
    );
    let start_samples = match &init {
        Some(m) => m.samples.clone(),
        None => Mask::white(tile, args.seed).samples,
    };
    let before = score(&Mask { tile, samples: start_samples, meta: vec![] }, spec, SCORE_SLICES);
    let bar = ProgressBar::new(args.iterations as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} iterations, {elapsed} elapsed, {eta} left, objective {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_position(engine.iteration() as u64);
    // Ctrl-C from here on stops between iterations, after saving a checkpoint.
    let interrupted = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        ctrlc::set_handler(move || flag.store(true, std::sync::atomic::Ordering::SeqCst))
            .map_err(|e| Error::invalid(format!("cannot catch Ctrl-C: {e}")))?;
    }
    let save = |engine: &Engine, path: &std::path::Path| -> Result<()> {
        fsot::checkpoint::write(path, &fingerprint, &engine.state()?)
    };
    let every = args.checkpoint_every.max(1);
    let mut next_checkpoint = engine.iteration() + every;
    let start = Instant::now();
    while !engine.finished() {
        if interrupted.load(std::sync::atomic::Ordering::SeqCst) {
            bar.finish_and_clear();
            match &args.checkpoint {
                Some(p) => {
                    save(&engine, p)?;
                    eprintln!(
                        "interrupted at iteration {} of {}: state saved to {}; continue with the same command and --resume",
                        engine.iteration(),
                        args.iterations,
                        p.display()
                    );
                }
                None => eprintln!(
                    "interrupted at iteration {} of {}: nothing written, {} untouched (--checkpoint FILE makes runs resumable)",
                    engine.iteration(),
                    args.iterations,
                    args.out.display()
                ),
            }
            return Err(Error::Interrupted);
        }
        let stepped = match &args.checkpoint {
            Some(_) => engine.step_up_to(next_checkpoint.saturating_sub(engine.iteration())),
            None => engine.step(),
        };
        let costs = match stepped {
            Ok(c) => c,
            // With --backend auto a GPU that fails mid-run hands over to the CPU
            // path, from the last checkpoint when there is one.
            Err(e) if choice == BackendChoice::Auto && engine.is_gpu() && e.is_device_failure() => {
                bar.suspend(|| eprintln!("warning: the GPU failed at iteration {}: {e}", engine.iteration()));
                let cpu = Engine::start(BackendChoice::Cpu, tile, settings, init.as_ref(), None, gpu)?;
                engine = cpu.engine;
                let from = match args.checkpoint.as_ref().filter(|p| p.exists()) {
                    Some(p) => {
                        engine.restore(&fsot::checkpoint::read(p, &fingerprint, &tile)?)?;
                        format!("its checkpoint {} (iteration {})", p.display(), engine.iteration())
                    }
                    None => "the start".to_string(),
                };
                bar.suspend(|| eprintln!("{}; continuing from {from}", cpu.note));
                bar.set_position(engine.iteration() as u64);
                next_checkpoint = engine.iteration() + every;
                continue;
            }
            Err(e) => return Err(e),
        };
        bar.inc(costs.len() as u64);
        if let Some(c) = costs.last() {
            bar.set_message(format!("{c:.3e}"));
        }
        if let Some(p) = &args.checkpoint {
            if engine.iteration() >= next_checkpoint && !engine.finished() {
                save(&engine, p)?;
                next_checkpoint = engine.iteration() + every;
            }
        }
    }
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    let mask = engine.mask()?;
    let after = score(&mask, spec, SCORE_SLICES);
    fsot::io::exr::write(&mask, out)?;
    if let Some(dir) = &args.png {
        let files = fsot::io::png::write(&mask, dir)?;
        eprintln!("wrote {} PNG slices into {}", files.len(), dir.display());
    }
    if let Some(p) = &args.checkpoint {
        if p.exists() {
            std::fs::remove_file(p).map_err(|e| {
                Error::io(format!("the run is complete, but removing {} failed", p.display()), e)
            })?;
        }
    }
    let backend = if engine.is_gpu() { "vulkan" } else { "cpu" };
    println!(
        "wrote {}: {}, kernel {}, {} iterations in {seconds:.1} s ({backend}); objective {:.4e} -> {:.4e} ({:.3} x white noise)",
        args.out.display(),
        tile.describe(),
        spec.describe(),
        engine.iteration(),
        before.objective,
        after.objective,
        after.ratio()
    );
    if let Engine::Gpu(run) = &engine {
        gpu_report(run, args.profile)?;
    }
    Ok(())
}

/// The checkpoint rules: `--resume` needs `--checkpoint`, which must then hold a
/// checkpoint of this very run; without `--resume` an existing checkpoint is left
/// alone (an error), and the path must be writable before the work starts.
fn saved_state(
    args: &OptimizeArgs,
    fingerprint: &str,
    tile: &Tile,
) -> Result<Option<fsot::optimize::RunState>> {
    let Some(path) = &args.checkpoint else {
        return match args.resume {
            true => Err(Error::invalid("--resume needs --checkpoint FILE (the file to continue)")),
            false => Ok(None),
        };
    };
    if args.checkpoint_every == 0 {
        return Err(Error::invalid("--checkpoint-every must be at least 1"));
    }
    let saved = match args.resume {
        true => Some(fsot::checkpoint::read(path, fingerprint, tile)?),
        false => None,
    };
    if !args.resume && path.exists() {
        return Err(Error::invalid(format!(
            "checkpoint {} exists: continue it with --resume, or remove it to start over",
            path.display()
        )));
    }
    AtomicFile::create(path)?; // a checkpoint that cannot be written fails now
    Ok(saved)
}

/// After a Vulkan run: skipped large classes, the profile, validation messages.
fn gpu_report(run: &fsot::gpu::optimizer::GpuRun, profile: bool) -> Result<()> {
    if run.overflowed() > 0 {
        eprintln!("warning: {} large classes did not fit their buffer and were skipped", run.overflowed());
    }
    if profile {
        let p = &run.profile;
        let per = |ns: f64| ns / p.iterations.max(1) as f64 * 1e-6;
        println!(
            "profile ({} iterations, per iteration): transport {:.3} ms, large classes {:.3} ms, update {:.3} ms",
            p.iterations,
            per(p.transport_ns),
            per(p.large_ns),
            per(p.update_ns)
        );
    }
    let messages = run.validation_messages();
    if !messages.is_empty() {
        eprintln!("{} validation messages:", messages.len());
        for m in messages.iter().take(10) {
            eprintln!("  {m}");
        }
        return Err(Error::invalid("the Vulkan validation layer reported errors"));
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
    out: AtomicFile,
) -> Result<()> {
    let swaps = args.method == Method::Fast || (args.method == Method::Stbn && tile.dims > 1);
    if swaps && !(1..=100_000).contains(&args.passes) {
        return Err(Error::invalid(format!("--passes must be in 1..=100000, got {}", args.passes)));
    }
    let start = Instant::now();
    let mask = match args.method {
        Method::White => {
            let mut m = Mask::white(tile, args.seed);
            m.set_meta("version", env!("CARGO_PKG_VERSION"));
            m
        }
        Method::Stbn => {
            let sigma = args.kernel.sigma.unwrap_or(fsot::baselines::stbn::DEFAULT_SIGMA);
            let sigma_t = args.kernel.sigma_t.unwrap_or(sigma);
            let bar = swap_bar(args.passes, tile.dims > 1);
            let mask = fsot::baselines::stbn::stbn_mask_with(
                tile,
                sigma,
                sigma_t,
                args.passes,
                args.seed,
                |_, e| {
                    bar.inc(1);
                    bar.set_message(format!("{e:.6e}"));
                },
            )?;
            bar.finish_and_clear();
            mask
        }
        Method::Fast => {
            let spec = fsot::baselines::fast::FastSpec {
                spatial: Filter::parse(&args.fast_spatial, false)?,
                temporal: Filter::parse(&args.fast_temporal, true)?,
                combine: Combine::parse(&args.fast_combine)?,
            };
            let bar = swap_bar(args.passes, true);
            let (mask, report) =
                fsot::baselines::fast::fast_mask(tile, &spec, args.passes, args.seed, |_, e| {
                    bar.inc(1);
                    bar.set_message(format!("{e:.6e}"));
                })?;
            bar.finish_and_clear();
            eprintln!(
                "{} ({} neighbours per pixel): loss {:.6e} -> {:.6e}, {} of {} proposed swaps taken ({} re-evaluated)",
                spec.describe(),
                report.offsets,
                report.start_energy,
                report.trace.last().copied().unwrap_or(report.start_energy),
                report.accepted,
                report.proposed,
                report.recomputed
            );
            mask
        }
        Method::Fsot => unreachable!("handled by optimize"),
    };
    let seconds = start.elapsed().as_secs_f64();
    let s = score(&mask, spec, SCORE_SLICES);
    fsot::io::exr::write(&mask, out)?;
    if let Some(dir) = &args.png {
        let files = fsot::io::png::write(&mask, dir)?;
        eprintln!("wrote {} PNG slices into {}", files.len(), dir.display());
    }
    println!(
        "wrote {}: {}, method {:?}, {seconds:.1} s; objective under kernel {}: {:.4e} ({:.3} x white noise)",
        args.out.display(),
        tile.describe(),
        args.method,
        spec.describe(),
        s.objective,
        s.ratio()
    );
    Ok(())
}
