//! `fsot plan`: what a scene needs, with the reasons; `fsot optimize --scene`
//! runs it.

use crate::*;
use fsot::scene::file::Scene;
use fsot::scene::plan::{CostModel, Plan, PlanEvent};

pub(crate) fn plan_command(args: PlanArgs) -> Result<()> {
    let scene = read_scene(&args.scene, args.budget.as_deref())?;
    let options = RunOptions::default()
        .backend(args.backend.choice())
        .device(env::device(args.device.clone()))
        .validation(env::validation());
    let cost = CostModel::calibrate(&options)?;
    let plan = Plan::new(&scene, &cost)?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&plan).map_err(|e| Error::invalid(e.to_string()))?)?;
    } else {
        out!("{}", describe(&plan))?;
    }
    Ok(())
}

/// The scene file, with `--budget` (when given) in place of its own budget.
fn read_scene(path: &std::path::Path, budget: Option<&str>) -> Result<Scene> {
    let mut scene = Scene::read(path)?;
    if let Some(text) = budget {
        scene.budget = Some(super::optimize::parse_seconds(text)?);
    }
    Ok(scene)
}

/// The plan in words.
pub(crate) fn describe(plan: &Plan) -> String {
    let [w, h, t] = plan.tile;
    let mut s = format!(
        "scene {}: tile {w}x{h}x{t} ({}); reading {} ({}); kernel {} ({}); backend {}\n",
        plan.scene,
        plan.tile_reason,
        plan.reading,
        plan.reading_reason,
        plan.kernel,
        plan.kernel_reason,
        plan.backend
    );
    for g in &plan.groups {
        let reads: Vec<String> = g
            .parts
            .iter()
            .map(|p| {
                let at = match p.shares {
                    Some(_) => format!(" at offset {:?}, shift {:.4?}", p.offset, p.shift),
                    None => String::new(),
                };
                format!("{} (dims {}..{}){at}", p.mask, p.first, p.first + p.dims)
            })
            .collect();
        s += &format!(
            "  {} (d = {}, spp {}): reads {}; {}{}\n",
            g.name,
            g.dims,
            g.spp,
            reads.join(", "),
            g.reason,
            g.skipped.as_ref().map(|k| format!(" [skipped: {k}]")).unwrap_or_default()
        );
    }
    for m in plan.masks.iter().filter(|m| !m.white) {
        let kernel = match m.kernel == plan.kernel {
            true => String::new(),
            false => format!(", kernel {}", m.kernel),
        };
        s += &format!(
            "  mask {}: d = {}, spp {}{kernel}, about {} iterations, about {:.1} s\n",
            m.file, m.dims, m.spp, m.estimated_iterations, m.estimated_seconds
        );
    }
    s += &format!("  total: about {:.1} s ({})\n", plan.estimated_seconds, plan.cost_model);
    if let Some(b) = plan.budget {
        s += &format!("  budget: {b} s from the start, each mask ending at its share (no checkpoints)\n");
        // The estimates are this machine's (the command line calibrates).
        let starved: Vec<&str> = plan
            .masks
            .iter()
            .filter(|m| !m.white && m.estimated_iterations == 0)
            .map(|m| m.file.as_str())
            .collect();
        if !starved.is_empty() {
            s += &format!(
                "  the budget is too short here for one iteration of {}: each such mask is its animated start \
                 (one frame optimized, set in motion), which takes its own time past the budget\n",
                starved.join(", ")
            );
        }
    }
    s
}

/// `fsot optimize --scene SCENE --out DIR`: the plan's masks and plan.json.
pub(crate) fn optimize_scene(args: &OptimizeArgs, path: &std::path::Path) -> Result<()> {
    let refused = [
        (args.method != Method::Fsot, "--method"),
        (args.init.is_some(), "--init"),
        (args.checkpoint.is_some(), "--checkpoint (a scene's runs checkpoint into the output folder)"),
        (
            args.size.is_some() || args.dims.is_some() || args.spp.is_some(),
            "--size, --dims and --spp (the scene gives them)",
        ),
        (
            args.iterations.is_some() || args.until.is_some(),
            "--iterations and --until (each mask stops when iterations no longer pay)",
        ),
        (!args.also.is_empty(), "--also (each mask is written into the folder --out)"),
        (args.start != StartArg::Auto, "--start (a plan's masks start from the animated start)"),
        (args.axis_share.is_some(), "--axis-share (a plan gives a channel read alone a scalar mask)"),
        (
            args.kernel.any_given(),
            "--kernel, --display, --sigma, --sigma-t, --alpha or --fps (the scene's [display] sets the eye and the kernel)",
        ),
        (args.png.is_some(), "--png (a plan writes EXR, and KTX2 with --ktx2-format)"),
        (args.seed.is_some(), "--seed (each mask's seed comes from the scene's and the file's names)"),
        (args.slices.is_some(), "--slices (each mask draws the default slices for its tile)"),
    ];
    if let Some((_, flag)) = refused.iter().find(|(bad, _)| *bad) {
        return Err(Error::invalid(format!("--scene does not take {flag}")));
    }
    let mask_file =
        args.out.extension().is_some_and(|e| ["exr", "ktx2", "h"].contains(&&*e.to_string_lossy()));
    if mask_file || (args.out.exists() && !args.out.is_dir()) {
        return Err(Error::invalid(format!(
            "with --scene, --out names a folder, not {}",
            args.out.display()
        )));
    }
    if args.checkpoint_every == 0 {
        return Err(Error::invalid("--checkpoint-every must be at least 1"));
    }
    let scene = read_scene(path, args.budget.as_deref())?;
    let options = RunOptions::default()
        .backend(args.backend.choice())
        .device(env::device(args.device.clone()))
        .validation(env::validation())
        .vulkan(VulkanOptions::default().deterministic(args.deterministic))
        .budget_from(crate::process_start());
    let cost = CostModel::calibrate(&options)?;
    let plan = Plan::new(&scene, &cost)?;
    eprint!("{}", describe(&plan));
    // KTX2 beside each mask: every format checked before any work.
    let ktx2: Vec<Option<fsot::io::ktx2::Format>> = plan
        .masks
        .iter()
        .map(|m| args.ktx2_format.as_deref().map(|f| fsot::io::ktx2::format_for(m.dims, Some(f))).transpose())
        .collect::<Result<_>>()?;
    // And each KTX2 output reserved where the folder exists already (a folder or
    // a device in its place is refused here, not after the work); in a new
    // folder nothing can be in the way.
    let ktx2_path = |m: &fsot::scene::plan::PlannedMask| args.out.join(&m.file).with_extension("ktx2");
    let mut ktx2_out: Vec<Option<AtomicFile>> = plan
        .masks
        .iter()
        .zip(&ktx2)
        .map(|(m, f)| match (f, args.out.is_dir()) {
            (Some(_), true) => AtomicFile::create(&ktx2_path(m)).map(Some),
            _ => Ok(None),
        })
        .collect::<Result<_>>()?;
    let estimated: u64 = plan.masks.iter().map(|m| m.estimated_iterations as u64).sum();
    let bar = ProgressBar::new(estimated.max(1));
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos} iterations (about {len} planned), {elapsed} elapsed, {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let cancel = cmd::env::interrupt_flag()?;
    // Iterations of each mask so far (the masks run side by side).
    let mut done = vec![0u64; plan.masks.len()];
    // Each mask's backend, said when it is not the last one said (the plan's,
    // above): a GPU that failed as a mask's run started.
    let mut said = plan.backend.clone();
    let outcome =
        plan.execute(&args.out, &options, args.checkpoint_every, args.resume, &cancel, &mut |e| match e {
            PlanEvent::Start { index, iteration, backend, .. } => {
                done[index] = iteration as u64;
                bar.set_position(done.iter().sum());
                if backend != said {
                    bar.suspend(|| eprintln!("{}: backend {backend}", plan.masks[index].file));
                    said = backend.to_string();
                }
            }
            PlanEvent::Run { index, event: Event::Progress { iteration, .. } } => {
                done[index] = iteration as u64;
                bar.set_position(done.iter().sum());
                bar.set_message(plan.masks[index].file.clone());
            }
            PlanEvent::Run { index, event: Event::FellBack { error, at, backend, from, .. } } => {
                done[index] = from as u64;
                bar.suspend(|| {
                    eprintln!(
                        "warning: the GPU failed at iteration {at} of {}: {error}; continuing on {backend} from iteration {from}",
                        plan.masks[index].file
                    )
                });
            }
            PlanEvent::Run { .. } => {}
            PlanEvent::Done { file, iterations, seconds, .. } => {
                bar.suspend(|| eprintln!("{file}: {iterations} iterations in {seconds:.1} s"));
            }
            _ => {}
        })?;
    bar.finish_and_clear();
    let ended = crate::process_start().elapsed().as_secs_f64();
    if let Outcome::Cancelled { iteration, .. } = outcome {
        match plan.budget {
            // Runs under a budget take no checkpoints.
            Some(_) => eprintln!(
                "interrupted at iteration {iteration} of a mask: the masks already made are in {}; a plan under a budget takes no checkpoints, so the same command (without --resume) makes them all again within it",
                args.out.display()
            ),
            None => eprintln!(
                "interrupted at iteration {iteration} of a mask: its state is saved in {}; continue with the same command and --resume",
                args.out.display()
            ),
        }
        return Err(Error::Interrupted);
    }
    for ((m, format), reserved) in plan.masks.iter().zip(&ktx2).zip(&mut ktx2_out) {
        if let Some(format) = format {
            let mask = fsot::io::exr::read(&args.out.join(&m.file))?;
            let out = match reserved.take() {
                Some(out) => out,
                None => AtomicFile::create(&ktx2_path(m))?,
            };
            fsot::io::ktx2::write(&mask, *format, out)?;
        }
    }
    let also = if args.ktx2_format.is_some() { " (each also as KTX2)" } else { "" };
    outln!("wrote {} masks{also} and plan.json into {}", plan.masks.len(), args.out.display())?;
    if let Some(budget) = plan.budget {
        outln!(
            "budget {budget} s: the masks were made {ended:.3} s after the process started ({:+.3} s)",
            ended - budget
        )?;
    }
    Ok(())
}
