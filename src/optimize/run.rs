//! A run of the optimizer, owned by the library whatever calls it (the command
//! line, a benchmark, a renderer): it picks the backend (`auto | cpu | vulkan`)
//! and says why, falls back to the CPU path when a GPU fails mid-run (from the
//! last checkpoint), writes checkpoints every N iterations and when cancelled,
//! resumes from one, stops when the caller's cancel flag is set, and reports
//! progress through a callback.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::core::animate::{animate, lay_out};
use crate::core::kernel::{KernelSpec, Temporal};
use crate::core::mask::Mask;
use crate::core::step_rule::{progress, schedule_between, Plateau, PlateauState, FROM_MASK_START};
use crate::core::tile::Tile;
use crate::error::{Error, Result};
use crate::io::atomic::AtomicFile;
use crate::optimize::backend::{Backend, BackendChoice, BackendKind, Report};
use crate::optimize::checkpoint;
use crate::optimize::clock::{self, Stamp};
use crate::optimize::cpu::CpuRun;
use crate::optimize::settings::{
    check_axis_share, RunState, Settings, Start, Until, COARSE_BUDGET_SHARE, MAX_BUDGET_SECONDS, COARSE_MIN_QUARTER, SPATIAL_BUDGET_SHARE,
    SPATIAL_ITERATIONS,
};
#[cfg(feature = "vulkan")]
use crate::optimize::vulkan::{VulkanOptions, VulkanRun};
#[cfg(feature = "vulkan")]
use crate::vk::{Context, ContextOptions};

/// Checkpoints of a run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Checkpointing {
    /// The checkpoint file: written atomically every `every` iterations and when
    /// the run is cancelled, removed when the run completes.
    pub path: PathBuf,
    /// Iterations between checkpoints, at least 1.
    pub every: u32,
    /// Continue from the checkpoint at `path` (which must be this very run's).
    /// Without it an existing file at `path` is refused, never overwritten.
    pub resume: bool,
}

/// How a run is made. Built from the default with the setters:
///
/// ```
/// use fsot::{BackendChoice, RunOptions};
/// let options = RunOptions::default().backend(BackendChoice::Cpu).validation(false);
/// assert_eq!(options.backend, BackendChoice::Cpu);
/// ```
#[derive(Clone, Default)]
#[non_exhaustive]
pub struct RunOptions {
    /// Where the run may go [default: `Auto`].
    pub backend: BackendChoice,
    /// The Vulkan device: its index or part of its name [default: the first
    /// discrete GPU]. A device named here is taken by `Auto` whatever its type.
    pub device: Option<String>,
    /// Work on this context (a renderer's wrapped device, or one the caller made)
    /// instead of making one; `Auto` then takes it whatever its type.
    #[cfg(feature = "vulkan")]
    pub context: Option<Context>,
    /// Vulkan's validation layer on (its messages in `Run::report`).
    pub validation: bool,
    /// How a Vulkan run works.
    #[cfg(feature = "vulkan")]
    pub vulkan: VulkanOptions,
    /// Checkpoints of the run; None: no checkpoints.
    pub checkpoint: Option<Checkpointing>,
    /// The instant a time budget (`Until::Seconds`) counts from [default: when
    /// `Run::start` begins]: a host's own start (its process's), or a plan's, so
    /// that the budget covers the work before the run too.
    pub budget_from: Option<Instant>,
    /// A flag that cuts short the work `Run::start` does before the run (an
    /// animated or a coarse start): set then, `Run::start` ends with
    /// `Error::Interrupted` and saves nothing (resumed, the start is made again).
    pub cancel_start: Option<CancelFlag>,
}

impl RunOptions {
    /// Where the run may go.
    pub fn backend(mut self, backend: BackendChoice) -> Self {
        self.backend = backend;
        self
    }

    /// The Vulkan device by index or part of its name.
    pub fn device(mut self, device: Option<String>) -> Self {
        self.device = device;
        self
    }

    /// Work on this context (a renderer's wrapped device) instead of making one.
    #[cfg(feature = "vulkan")]
    pub fn context(mut self, context: Option<Context>) -> Self {
        self.context = context;
        self
    }

    /// Vulkan's validation layer on or off.
    pub fn validation(mut self, on: bool) -> Self {
        self.validation = on;
        self
    }

    /// How a Vulkan run works.
    #[cfg(feature = "vulkan")]
    pub fn vulkan(mut self, vulkan: VulkanOptions) -> Self {
        self.vulkan = vulkan;
        self
    }

    /// Checkpoints of the run, or none.
    pub fn checkpoint(mut self, checkpoint: Option<Checkpointing>) -> Self {
        self.checkpoint = checkpoint;
        self
    }

    /// The instant a time budget counts from (see `budget_from`).
    pub fn budget_from(mut self, from: Instant) -> Self {
        self.budget_from = Some(from);
        self
    }

    /// A flag that cuts short the start's own work (see `cancel_start`).
    pub fn cancel_start(mut self, cancel: CancelFlag) -> Self {
        self.cancel_start = Some(cancel);
        self
    }
}

/// What a run tells its observer.
#[derive(Debug)]
#[non_exhaustive]
pub enum Event<'a> {
    /// Iterations done; the objective estimate of the last one.
    Progress {
        /// Iterations done.
        iteration: u32,
        /// The run's length, or its cap under a stopping rule.
        iterations: u32,
        /// The last iteration's objective estimate; None when the step gave none.
        objective: Option<f64>,
    },
    /// A checkpoint was written.
    Checkpoint {
        /// Iterations done when it was written.
        iteration: u32,
        /// The checkpoint file.
        path: &'a Path,
    },
    /// The GPU failed at iteration `at`; the run goes on on `backend` from
    /// iteration `from` (its checkpoint's, or 0).
    FellBack {
        /// The GPU's error.
        error: &'a Error,
        /// Iterations done when the GPU failed.
        at: u32,
        /// The backend the run continues on, in words.
        backend: &'a str,
        /// The iteration the run goes on from.
        from: u32,
        /// The checkpoint it goes on from; None: from iteration 0.
        checkpoint: Option<&'a Path>,
    },
}

/// How `Run::advance` ended.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Outcome {
    /// The asked iteration was reached.
    Reached,
    /// The cancel flag was set: stopped between iterations, the state saved to
    /// `saved` when checkpointing.
    Cancelled {
        /// Iterations done when it stopped.
        iteration: u32,
        /// The checkpoint the state was saved to; None without checkpoints.
        saved: Option<PathBuf>,
    },
}

/// The state a checkpoint of this very run holds, checked against the run it
/// would resume: an error naming the file where it is not one this run reaches.
fn read_saved(path: &Path, fingerprint: &str, tile: &Tile, settings: &Settings) -> Result<RunState> {
    let state = checkpoint::read(path, fingerprint, tile)?;
    state.check(tile, settings).map_err(|e| Error::bad_file(path, format!("cannot resume: {e}")))?;
    Ok(state)
}

/// A flag the caller sets to stop a run between iterations (a renderer wires its
/// own; the command line sets it on Ctrl-C and SIGTERM).
#[derive(Clone, Debug, Default)]
pub struct CancelFlag(Arc<AtomicBool>);

impl CancelFlag {
    /// A flag not yet set.
    pub fn new() -> Self {
        Self::default()
    }
    /// Sets the flag (for every clone): a run given it stops between iterations.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }
    /// Whether the flag is set.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

/// A step (one submission on the GPU) is sized from the pace of the step before
/// it to last about this long, so that cancelling and the progress report answer
/// within it even where an iteration takes seconds (a large tile on lavapipe).
/// A GPU's batch (32 iterations) lasts far less.
const STEP_SECONDS: f64 = 0.5;

/// A time budget's scale is updated at least this many times over it.
const BUDGET_STEPS: f64 = 32.0;

/// The least time the one-frame run of an animated start is given.
const MIN_SPATIAL_SECONDS: f64 = 1e-3;

/// An optimization in progress, on whichever backend it was given.
pub struct Run {
    tile: Tile,
    settings: Settings,
    init: Option<Mask>,
    /// The start was a mask the caller gave (`Run::start`'s `init`), not one
    /// the settings' `start` made.
    given_start: bool,
    /// The mask of an ended run, read back from the GPU by `settle`.
    ended: Option<Mask>,
    options: RunOptions,
    backend: Box<dyn Backend>,
    note: String,
    /// How a coarse start was made, in words.
    start_note: Option<String>,
    fingerprint: String,
    resumed_from: Option<u32>,
    next_checkpoint: u32,
    /// The end-agnostic schedule of a run that stops by a rule, and where it stands.
    plateau: Option<(Plateau, PlateauState)>,
    /// The stopping rule ended the run.
    stopped: bool,
    /// The backend evaluates the stopping rule itself (Vulkan, on the device);
    /// otherwise this run does, once per window.
    rule_on_backend: bool,
    /// Seconds spent stepping this run (a step shared with other runs counts in
    /// full for each).
    busy: f64,
    /// Seconds per iteration of the last step; None before the first step,
    /// which then takes one iteration.
    pace: Option<f64>,
    /// Under `Until::Seconds`: when the first iteration began (the schedule's
    /// time runs from there to the deadline).
    iterating_since: Option<Instant>,
    /// What a time budget counts from: `RunOptions::budget_from`, or when
    /// `Run::start` began.
    begun: Stamp,
    /// How long `Run::start` took, and on what.
    set_up: SetUp,
}

/// Where `Run::start` spent its time, in seconds: what a run does before its
/// first iteration, which a time budget counts too.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SetUp {
    /// Making the start's samples: an animated or coarse start (next to
    /// nothing for white noise, a mask handed in or a checkpoint, which the
    /// backend makes or reads itself).
    pub start: f64,
    /// Starting the backend: for Vulkan the context (unless one was handed
    /// in), the pipelines, the buffers and the upload; for the CPU its tables.
    pub backend: f64,
}

impl Run {
    /// Starts a run: checks the checkpoint rules (before any long work), picks the
    /// backend, and resumes from the checkpoint when asked.
    pub fn start(tile: Tile, settings: Settings, init: Option<&Mask>, options: RunOptions) -> Result<Self> {
        let begun = options.budget_from.map_or_else(Stamp::now, Stamp::at);
        if settings.iterations == 0 {
            return Err(Error::invalid("iterations must be at least 1"));
        }
        tile.check()?;
        settings.kernel.check()?;
        settings.rule.check()?;
        if let Some(p) = settings.until.plateau() {
            p.check()?;
        }
        check_axis_share(settings.axis_share)?;
        if let Until::Objective(x) = settings.until {
            if !(x.is_finite() && x > 0.0) {
                return Err(Error::invalid(format!("an objective to stop at must be finite and above 0, got {x:?}")));
            }
        }
        match settings.until {
            Until::Seconds(s) if !(s.is_finite() && s > 0.0 && s <= MAX_BUDGET_SECONDS) => {
                return Err(Error::invalid(format!(
                    "a time budget must be more than 0 and at most {MAX_BUDGET_SECONDS} seconds, got {s:?}"
                )))
            }
            Until::Seconds(_) if !clock::HAS_CLOCK => clock::needs_clock("a time budget")?,
            Until::Seconds(_) if options.checkpoint.is_some() => {
                return Err(Error::invalid(
                    "a run under a time budget takes no checkpoints: it is made again within its budget",
                ))
            }
            _ => {}
        }
        if settings.start == Start::Coarse && !matches!(settings.until, Until::Seconds(_)) {
            return Err(Error::invalid("a coarse start divides a time budget: it takes one (`Until::Seconds`, --budget)"));
        }
        // A run from a given mask is another run than its settings' start
        // would make (and that start does not run).
        let given_start = init.is_some();
        let fingerprint = match given_start {
            true => checkpoint::fingerprint(&tile, &Settings { start: Start::White, ..settings }) + "; start a given mask",
            false => checkpoint::fingerprint(&tile, &settings),
        };
        let saved = saved_state(options.checkpoint.as_ref(), &fingerprint, &tile, &settings)?;
        let left = match settings.until {
            Until::Seconds(s) => Some(s - begun.seconds()),
            _ => None,
        };
        let started;
        let mut start_note = None;
        let making_start = Stamp::now();
        let init = match (init, &saved, settings.start) {
            (None, None, Start::Coarse) => {
                let (mask, note) = coarse_start(tile, &settings, left.unwrap_or(0.0), &options)?;
                interrupted(&options)?;
                start_note = Some(note);
                started = mask;
                Some(&started)
            }
            (None, None, start) if start.animates(settings.until, &tile) => {
                started = animated_start(tile, &settings, left, &options)?;
                interrupted(&options)?;
                Some(&started)
            }
            _ => init,
        };
        let starting_backend = Stamp::now();
        let (mut backend, note) = start_backend(tile, settings, init, &options)?;
        if let Some(state) = &saved {
            backend.restore(state)?;
        }
        let set_up = SetUp {
            start: starting_backend.seconds_since(making_start),
            backend: starting_backend.seconds(),
        };
        let plateau = schedule(&settings, saved.as_ref());
        let resumed_from = saved.map(|s| s.iteration);
        let every = options.checkpoint.as_ref().map(|c| c.every).unwrap_or(u32::MAX);
        let next_checkpoint = backend.iteration().saturating_add(every);
        let mut run = Self {
            tile,
            settings,
            init: init.cloned(),
            given_start,
            ended: None,
            options,
            backend,
            note,
            start_note,
            fingerprint,
            resumed_from,
            next_checkpoint,
            plateau,
            stopped: false,
            rule_on_backend: false,
            busy: 0.0,
            pace: None,
            iterating_since: None,
            begun,
            set_up,
        };
        match run.hand_over_rule() {
            Ok(()) => {}
            // The GPU failed taking the rule: the run starts on the CPU path.
            Err(e) if run.can_fall_back(&e) => {
                run.fall_back(&e, &mut |_| {})?;
                run.note = format!("{} (the GPU failed as the run started: {e})", run.note);
            }
            Err(e) => return Err(e),
        }
        Ok(run)
    }

    /// Hands the stopping rule, where it stands, to a backend that evaluates it
    /// itself (on the GPU); otherwise the run keeps it.
    fn hand_over_rule(&mut self) -> Result<()> {
        let target = match self.settings.until {
            Until::Objective(t) => Some(t),
            _ => None,
        };
        self.rule_on_backend = match &self.plateau {
            Some((rule, state)) => self.backend.adopt_plateau(rule, state, target)?,
            None => false,
        };
        Ok(())
    }

    /// The stopping rule is evaluated by the backend (on the GPU), not by the host.
    pub fn rule_on_device(&self) -> bool {
        self.rule_on_backend
    }

    /// The backend in words, and why it was chosen when not the one asked for.
    pub fn note(&self) -> &str {
        &self.note
    }
    /// How a coarse start was made, in words (None for other starts).
    pub fn start_note(&self) -> Option<&str> {
        self.start_note.as_deref()
    }
    /// The iteration the run resumed from, when it did.
    pub fn resumed_from(&self) -> Option<u32> {
        self.resumed_from
    }
    internal! {
        /// The samples the run started from: its initial mask (an animated
        /// start's), or white noise drawn from the seed.
        fn start_samples(&self) -> Result<Vec<f32>> {
            crate::optimize::settings::initial_samples(&self.tile, &self.settings, self.init.as_ref())
        }
    }
    /// Where the run goes: the CPU or Vulkan (`note` says why).
    pub fn backend_kind(&self) -> BackendKind {
        self.backend.kind()
    }
    /// What the backend reports so far: its time per pass (with
    /// `VulkanOptions::profile`), the validation layer's messages (with
    /// `RunOptions::validation`; a run that has any should not be trusted),
    /// large classes skipped.
    ///
    /// ```
    /// use fsot::{BackendChoice, BackendKind, CancelFlag, KernelSpec, Run, RunOptions, Settings, Tile};
    /// let tile = Tile::new(8, 8, 4, 1, 2)?;
    /// let settings = Settings::new(KernelSpec::named("perceptual-taa")?, 1).iterations(4);
    /// let options = RunOptions::default().backend(BackendChoice::Cpu);
    /// let mut run = Run::start(tile, settings, None, options)?;
    /// run.run(&CancelFlag::new(), &mut |_| {})?;
    /// assert_eq!(run.backend_kind(), BackendKind::Cpu);
    /// assert!(run.report().validation_messages.is_empty());
    /// # Ok::<(), fsot::Error>(())
    /// ```
    pub fn report(&self) -> Report {
        self.backend.report()
    }
    internal! {
        fn backend(&self) -> &dyn Backend {
            self.backend.as_ref()
        }
    }
    internal! {
        fn backend_mut(&mut self) -> &mut dyn Backend {
            self.backend.as_mut()
        }
    }
    /// The tile being optimized.
    pub fn tile(&self) -> &Tile {
        &self.tile
    }
    /// The settings the run was started with.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }
    /// Iterations done.
    pub fn iteration(&self) -> u32 {
        self.backend.iteration()
    }
    /// The run's length reached, or its stopping rule ended it.
    pub fn finished(&self) -> bool {
        self.stopped || self.iteration() >= self.settings.iterations
    }
    /// The iterations asked for: the run's length, or its cap under a stopping rule.
    pub fn iterations(&self) -> u32 {
        self.settings.iterations
    }

    /// Runs to the end (see `advance`).
    pub fn run(&mut self, cancel: &CancelFlag, on: &mut dyn FnMut(Event)) -> Result<Outcome> {
        self.advance(self.settings.iterations, cancel, on)
    }

    /// Runs until iteration `to` (at most the run's length), checkpointing on the
    /// way; stops between iterations when `cancel` is set. A GPU that fails under
    /// `BackendChoice::Auto` hands over to the CPU path, from the last checkpoint.
    pub fn advance(&mut self, to: u32, cancel: &CancelFlag, on: &mut dyn FnMut(Event)) -> Result<Outcome> {
        let to = to.min(self.settings.iterations);
        loop {
            while self.iteration() < to && !self.stopped {
                if self.out_of_time() {
                    self.stopped = true;
                    break;
                }
                if cancel.is_cancelled() {
                    let saved = self.save()?;
                    return Ok(Outcome::Cancelled { iteration: self.iteration(), saved });
                }
                // The GPU may fail in an iteration or reading its state back
                // for a checkpoint.
                let stepped = self.step_once(to, on);
                self.or_fall_back(stepped, on)?;
            }
            // Ended: its mask read back now, where a failure can still hand
            // the run to the CPU path (which then goes on from its checkpoint).
            if self.settle(on)? {
                return Ok(Outcome::Reached);
            }
        }
    }

    /// For a run that has ended on a GPU it may leave (`BackendChoice::Auto`):
    /// reads its mask back for `finish`. False when the GPU failed reading it
    /// and the run went on to the CPU path, from its checkpoint, to run again
    /// (not under a time budget, which keeps none and is spent: an error).
    fn settle(&mut self, on: &mut dyn FnMut(Event)) -> Result<bool> {
        if !self.finished() || self.ended.is_some() || !self.on_a_gpu_it_may_leave() {
            return Ok(true);
        }
        match self.backend.mask() {
            Ok(mask) => {
                self.ended = Some(mask);
                Ok(true)
            }
            // A budgeted run keeps no checkpoint: on the CPU it would start
            // again with its budget spent, so its failure is the run's.
            Err(e) if self.can_fall_back(&e) && !matches!(self.settings.until, Until::Seconds(_)) => {
                self.fall_back(&e, on)?;
                self.stopped = false;
                Ok(false)
            }
            Err(e) => Err(e),
        }
    }

    /// One step of the backend towards `to` (a batch on the GPU, stopping at the
    /// next checkpoint), then the checkpoint when one is due.
    fn step_once(&mut self, to: u32, on: &mut dyn FnMut(Event)) -> Result<()> {
        let count = self.next_step(to);
        let start = Stamp::now();
        let costs = self.backend.step_up_to(count)?;
        let seconds = start.seconds();
        self.busy += seconds;
        self.paced(seconds, costs.len());
        self.stepped(&costs, on)
    }

    /// Wall time since the budget's origin (`RunOptions::budget_from`, else
    /// when `Run::start` began: its set-up and an animated start included), in
    /// seconds: what a time budget counts. 0 on a platform without a clock
    /// (wasm32-unknown-unknown), as are `set_up` and `seconds`.
    pub fn elapsed(&self) -> f64 {
        self.begun.seconds()
    }

    /// Where `Run::start` spent its time: making the start and starting the
    /// backend.
    pub fn set_up(&self) -> SetUp {
        self.set_up
    }

    /// Seconds spent stepping this run (a step shared with other runs, in
    /// `run_together`, counts in full for each).
    pub fn seconds(&self) -> f64 {
        self.busy
    }

    /// When a time budget ends (`Until::Seconds`).
    fn deadline(&self) -> Option<Instant> {
        match self.settings.until {
            // Run::start refuses a budget where there is no clock.
            Until::Seconds(s) => self.begun.instant().map(|b| b + Duration::from_secs_f64(s)),
            _ => None,
        }
    }

    /// Under a time budget: whether the next iteration, at the pace so far, would
    /// end past the budget (before the first: whether the budget is spent).
    fn out_of_time(&self) -> bool {
        match self.deadline() {
            Some(deadline) => Instant::now() + Duration::from_secs_f64(self.pace.unwrap_or(0.0)) > deadline,
            None => false,
        }
    }

    /// Under a time budget: sets the step scale the cosine schedule gives at the
    /// progress reached (from `FROM_MASK_START` for a run that starts from a
    /// mask), the further of the clock's through the budget and the iterations'
    /// through their cap, so that a run its cap ends first still ends at the
    /// schedule's last step; caps `count` at the iterations that fit in the
    /// budget, at a `BUDGET_STEPS`th of it and at a `BUDGET_STEPS`th of the cap,
    /// so the scale follows both.
    fn budget_step(&mut self, count: u32) -> u32 {
        let Some(deadline) = self.deadline() else { return count };
        let now = Instant::now();
        let since = *self.iterating_since.get_or_insert(now);
        let span = deadline.saturating_duration_since(since).as_secs_f64();
        let by_clock = if span > 0.0 { now.duration_since(since).as_secs_f64() / span } else { 1.0 };
        let cap = self.settings.iterations;
        let by_count = progress(self.iteration(), cap);
        let start = if self.init.is_some() { FROM_MASK_START } else { 1.0 };
        self.backend.set_scale(Some(schedule_between(start, (by_clock as f32).max(by_count))));
        let count = count.min((f64::from(cap) / BUDGET_STEPS).floor().max(1.0) as u32);
        match self.pace {
            Some(pace) if pace > 0.0 => {
                let left = deadline.saturating_duration_since(now).as_secs_f64();
                let fit = (left / pace).floor().max(1.0);
                let slice = (span / BUDGET_STEPS / pace).floor().max(1.0);
                count.min(fit.min(slice) as u32)
            }
            _ => count,
        }
    }

    /// Notes the pace of a step of `iterations` that took `seconds` (without a
    /// clock, none: every step then takes one iteration, with its event and a
    /// look at the cancel flag).
    fn paced(&mut self, seconds: f64, iterations: usize) {
        if iterations > 0 && clock::HAS_CLOCK {
            self.pace = Some(seconds / iterations as f64);
        }
    }

    /// The iterations the next step may take towards `to`: up to the next
    /// checkpoint, under a stopping rule to the end of its window (where the
    /// rule decides), and as many as last about `STEP_SECONDS` at the last
    /// step's pace; sets the step scale the rule's schedule gives.
    fn next_step(&mut self, to: u32) -> u32 {
        let mut stop = match &self.options.checkpoint {
            Some(_) => to.min(self.next_checkpoint),
            None => to,
        };
        match &self.plateau {
            // The backend decides where it stands and ends the run itself.
            Some(_) if self.rule_on_backend => {}
            Some((rule, state)) => {
                // Batches end at windows' ends, where the schedule decides.
                stop = stop.min(self.iteration() + rule.window.max(1) - state.count);
                self.backend.set_scale(Some(state.scale));
            }
            None => {}
        }
        let count = stop.saturating_sub(self.iteration()).max(1).min(paced_iterations(self.pace));
        self.budget_step(count)
    }

    /// After a step that gave `costs`: the stopping rule, progress, and the
    /// checkpoint when one is due.
    fn stepped(&mut self, costs: &[f64], on: &mut dyn FnMut(Event)) -> Result<()> {
        if let (true, Some((_, state))) = (self.rule_on_backend, &mut self.plateau) {
            if let Some((device, stop)) = self.backend.plateau() {
                *state = device;
                self.stopped |= stop;
            }
        } else if let Some((rule, state)) = &mut self.plateau {
            for &c in costs {
                let window_end = state.count + 1 == rule.window.max(1);
                self.stopped |= state.observe(rule, c);
                if let (true, Until::Objective(target)) = (window_end, self.settings.until) {
                    self.stopped |= state.previous <= target;
                }
            }
        }
        let iteration = self.iteration();
        on(Event::Progress {
            iteration,
            iterations: self.settings.iterations,
            objective: costs.last().copied(),
        });
        if iteration >= self.next_checkpoint && !self.finished() {
            if let Some(path) = self.save()? {
                on(Event::Checkpoint { iteration, path: &path });
            }
        }
        Ok(())
    }

    /// Runs several runs to their ends side by side (a scene plan's masks):
    /// those whose backends share a group (Vulkan: one device) step together,
    /// a batch of each in one submission (`Backend::step_together`); any other
    /// steps on its own.
    /// `on(r, event)` hears run r; `done(r, run)` is called once as run r ends
    /// (to write its mask while the others go on). Stops between steps when
    /// `cancel` is set, saving every unfinished run (each to its own
    /// checkpoint; the `Outcome::Cancelled` names the last run's checkpoint and
    /// the first unfinished run's iteration: read each run's own with
    /// `Run::iteration`); a GPU that fails hands each of its runs over to the
    /// CPU path as `advance` does.
    pub fn run_together(
        runs: &mut [Run],
        cancel: &CancelFlag,
        on: &mut dyn FnMut(usize, Event),
        done: &mut dyn FnMut(usize, &Run) -> Result<()>,
    ) -> Result<Outcome> {
        let mut reported = vec![false; runs.len()];
        loop {
            for run in runs.iter_mut() {
                run.stopped |= run.out_of_time();
            }
            for (r, run) in runs.iter_mut().enumerate() {
                if run.finished() && !reported[r] && run.settle(&mut |e| on(r, e))? {
                    reported[r] = true;
                    done(r, run)?;
                }
            }
            let open: Vec<usize> = (0..runs.len()).filter(|&r| !runs[r].finished()).collect();
            if open.is_empty() {
                return Ok(Outcome::Reached);
            }
            if cancel.is_cancelled() {
                let mut saved = None;
                for &r in &open {
                    saved = runs[r].save()?.or(saved);
                }
                let iteration = runs[open[0]].iteration();
                return Ok(Outcome::Cancelled { iteration, saved });
            }
            let group = shared_device_group(runs, &open);
            if group.len() < 2 {
                // Alone: the run's own step, with its fall-back.
                let r = open[0];
                let to = runs[r].settings.iterations;
                let stepped = runs[r].step_once(to, &mut |e| on(r, e));
                runs[r].or_fall_back(stepped, &mut |e| on(r, e))?;
                continue;
            }
            step_shared(runs, &group, on)?;
        }
    }

    /// The mask as it is now, with its provenance. When the run is complete its
    /// checkpoint is removed.
    pub fn finish(self) -> Result<Mask> {
        self.finish_with(|_| Ok(()))
    }

    /// As `finish`, handing the mask to `keep` (writing it out) before the
    /// checkpoint is removed: when `keep` fails, its error is returned and the
    /// checkpoint stays to resume from.
    pub fn finish_with(mut self, keep: impl FnOnce(&Mask) -> Result<()>) -> Result<Mask> {
        let ended = self.ended.take();
        self.finish_mask(ended, keep)
    }

    /// As `finish_with`, leaving the run in place (for runs held in a slice).
    pub fn finish_in_place_with(&self, keep: impl FnOnce(&Mask) -> Result<()>) -> Result<Mask> {
        self.finish_mask(self.ended.clone(), keep)
    }

    /// The mask (`ended`, the ended run's, or else the backend's now), handed
    /// to `keep`, then the finished run's checkpoint removed.
    fn finish_mask(&self, ended: Option<Mask>, keep: impl FnOnce(&Mask) -> Result<()>) -> Result<Mask> {
        let mut mask = match ended {
            Some(mask) => mask,
            None => self.backend.mask()?,
        };
        // The settings' start did not run: the caller's mask did.
        if self.given_start {
            mask.set_meta("start", "a given mask");
        }
        keep(&mask)?;
        if let (Some(c), true) = (&self.options.checkpoint, self.finished()) {
            if c.path.exists() {
                std::fs::remove_file(&c.path).map_err(|e| {
                    Error::io(format!("the run is complete, but removing {} failed", c.path.display()), e)
                })?;
            }
        }
        Ok(mask)
    }

    internal! {
        /// Where the run stands (the backend's state and the schedule's).
        fn state(&self) -> Result<RunState> {
            let mut state = self.backend.state()?;
            state.plateau = self.plateau.map(|(_, s)| s);
            Ok(state)
        }
    }

    /// Writes a checkpoint when checkpointing; where it went.
    fn save(&mut self) -> Result<Option<PathBuf>> {
        let Some(c) = &self.options.checkpoint else { return Ok(None) };
        checkpoint::write(&c.path, &self.fingerprint, &self.state()?)?;
        self.next_checkpoint = self.iteration().saturating_add(c.every);
        Ok(Some(c.path.clone()))
    }

    /// On the GPU under `BackendChoice::Auto`: the CPU path can take over.
    fn on_a_gpu_it_may_leave(&self) -> bool {
        self.options.backend == BackendChoice::Auto
            && self.backend.kind() == crate::optimize::backend::BackendKind::Vulkan
    }

    fn can_fall_back(&self, e: &Error) -> bool {
        self.on_a_gpu_it_may_leave() && e.is_device_failure()
    }

    /// `result`, or, where the GPU failed and the CPU path can take over, the
    /// run handed over to it.
    fn or_fall_back(&mut self, result: Result<()>, on: &mut dyn FnMut(Event)) -> Result<()> {
        match result {
            Err(e) if self.can_fall_back(&e) => self.fall_back(&e, on),
            other => other,
        }
    }

    /// Continues on the CPU path, from the checkpoint when there is one.
    fn fall_back(&mut self, e: &Error, on: &mut dyn FnMut(Event)) -> Result<()> {
        let at = self.iteration();
        let mut cpu = CpuRun::new(self.tile, self.settings, self.init.as_ref())?;
        let checkpoint = self.options.checkpoint.as_ref().map(|c| c.path.clone()).filter(|p| p.exists());
        let saved = checkpoint
            .as_ref()
            .map(|p| read_saved(p, &self.fingerprint, &self.tile, &self.settings))
            .transpose()?;
        if let Some(state) = &saved {
            cpu.restore(state)?;
        }
        self.plateau = schedule(&self.settings, saved.as_ref());
        self.backend = Box::new(cpu);
        self.pace = None;
        self.hand_over_rule()?;
        self.note = self.backend.describe();
        let from = self.iteration();
        let every = self.options.checkpoint.as_ref().map(|c| c.every).unwrap_or(u32::MAX);
        self.next_checkpoint = from.saturating_add(every);
        on(Event::FellBack { error: e, at, backend: &self.note, from, checkpoint: checkpoint.as_deref() });
        Ok(())
    }
}

/// Of the open runs, those whose backends share the first grouped open run's
/// group (`Backend::group`), so can step in one submission (empty where none
/// is grouped).
fn shared_device_group(runs: &[Run], open: &[usize]) -> Vec<usize> {
    let Some(group) = open.iter().find_map(|&r| runs[r].backend.group()) else { return Vec::new() };
    open.iter().copied().filter(|&r| runs[r].backend.group() == Some(group)).collect()
}

/// One step of every run in `group` (runs on one device), in one submission;
/// a GPU that fails hands each over to the CPU path.
fn step_shared(runs: &mut [Run], group: &[usize], on: &mut dyn FnMut(usize, Event)) -> Result<()> {
    let counts: Vec<u32> = group
        .iter()
        .map(|&r| {
            let to = runs[r].settings.iterations;
            runs[r].next_step(to)
        })
        .collect();
    let start = Stamp::now();
    let result = {
        let mut members: Vec<&mut dyn Backend> = runs
            .iter_mut()
            .enumerate()
            .filter(|(r, _)| group.contains(r))
            .map(|(_, run)| &mut *run.backend as &mut dyn Backend)
            .collect();
        match members.split_first_mut() {
            Some((first, others)) => first.step_together(others, &counts),
            None => Ok(Vec::new()),
        }
    };
    let seconds = start.seconds();
    let most = result.as_ref().map_or(0, |costs| costs.iter().map(Vec::len).max().unwrap_or(0));
    for &r in group {
        runs[r].busy += seconds;
        runs[r].paced(seconds, most);
    }
    match result {
        Ok(costs) => {
            for (&r, c) in group.iter().zip(&costs) {
                // The GPU may fail reading a run's state back for its
                // checkpoint: that run goes on on the CPU, as `advance` does.
                let stepped = runs[r].stepped(c, &mut |e| on(r, e));
                runs[r].or_fall_back(stepped, &mut |e| on(r, e))?;
            }
        }
        Err(e) if group.iter().all(|&r| runs[r].can_fall_back(&e)) => {
            for &r in group {
                runs[r].fall_back(&e, &mut |ev| on(r, ev))?;
            }
        }
        Err(e) => return Err(e),
    }
    Ok(())
}

/// The iterations a step may take at `pace` seconds per iteration (the last
/// step's) to last about `STEP_SECONDS`: at least one; one before the pace is
/// known.
fn paced_iterations(pace: Option<f64>) -> u32 {
    match pace {
        Some(pace) if pace > 0.0 => (STEP_SECONDS / pace).clamp(1.0, u32::MAX as f64) as u32,
        Some(_) => u32::MAX,
        None => 1,
    }
}

/// `Error::Interrupted` when the start's flag was set while it was made.
fn interrupted(options: &RunOptions) -> Result<()> {
    match options.cancel_start.as_ref().is_some_and(CancelFlag::is_cancelled) {
        true => Err(Error::Interrupted),
        false => Ok(()),
    }
}

/// The samples of `Start::Animated`: one frame of the tile optimized under the
/// kernel's spatial filter, set in motion over the frames. On the CPU whatever
/// the run's backend: one frame is small, and a device that fails later hands
/// the run over from the same start. Under a time budget with `left` seconds
/// of it left, the frame's run takes `SPATIAL_BUDGET_SHARE` of them.
fn animated_start(tile: Tile, settings: &Settings, left: Option<f64>, options: &RunOptions) -> Result<Mask> {
    let flat = Tile::new(tile.width, tile.height, 1, tile.spp, tile.dims)?;
    let until = match left {
        // At least MIN_SPATIAL_SECONDS, however little is left: a frame run
        // whose set-up takes that long stops before its first iteration (the
        // frame stays white noise, set in motion).
        Some(left) => Until::Seconds((left * SPATIAL_BUDGET_SHARE).max(MIN_SPATIAL_SECONDS)),
        None => Until::Iterations,
    };
    let spatial = Settings::new(KernelSpec { temporal: Temporal::Spatial, ..settings.kernel }, settings.seed)
        .iterations(SPATIAL_ITERATIONS.min(settings.iterations))
        .rule(settings.rule)
        .until(until)
        .start(Start::White)
        .axis_share(settings.axis_share);
    let mut run = Run::start(flat, spatial, None, RunOptions::default().backend(BackendChoice::Cpu))?;
    run.run(&options.cancel_start.clone().unwrap_or_default(), &mut |_| {})?;
    animate(&run.finish()?, tile.frames)
}

/// The samples of `Start::Coarse`: a quarter of the tile made by a run of the
/// same settings and backend in `COARSE_BUDGET_SHARE` of the `left` seconds,
/// laid out 2x2 (`lay_out`), and what was done, in words.
fn coarse_start(tile: Tile, settings: &Settings, left: f64, options: &RunOptions) -> Result<(Mask, String)> {
    let min = 2 * COARSE_MIN_QUARTER;
    if tile.width % 2 != 0 || tile.height % 2 != 0 || tile.width < min || tile.height < min {
        return Err(Error::invalid(format!(
            "a coarse start makes a quarter of the tile first: its width and height must be even and at least \
             {min}, not {}",
            tile.describe()
        )));
    }
    let quarter = Tile::new(tile.width / 2, tile.height / 2, tile.frames, tile.spp, tile.dims)?;
    let until = Until::Seconds((left * COARSE_BUDGET_SHARE).max(MIN_SPATIAL_SECONDS));
    let first = Settings { until, start: Start::Auto, ..*settings };
    let options = RunOptions { checkpoint: None, budget_from: None, ..options.clone() };
    let began = Stamp::now();
    let cancel = options.cancel_start.clone().unwrap_or_default();
    let mut run = Run::start(quarter, first, None, options)?;
    run.run(&cancel, &mut |_| {})?;
    let note = format!(
        "a quarter, {}, of {} iterations in {:.2} s, laid out 2x2",
        quarter.describe(),
        run.iteration(),
        began.seconds()
    );
    Ok((lay_out(&run.finish()?, tile)?, note))
}

/// The end-agnostic schedule of a run that stops by a rule: where a saved state
/// left it, or from the start.
fn schedule(settings: &Settings, saved: Option<&RunState>) -> Option<(Plateau, PlateauState)> {
    let rule = settings.until.plateau()?;
    Some((rule, saved.and_then(|s| s.plateau).unwrap_or_default()))
}

/// The checkpoint rules: with `resume`, the file must hold a checkpoint of this
/// very run; without, an existing file is left alone (an error); and the path
/// must be writable before the work starts.
fn saved_state(
    c: Option<&Checkpointing>,
    fingerprint: &str,
    tile: &Tile,
    settings: &Settings,
) -> Result<Option<RunState>> {
    let Some(c) = c else { return Ok(None) };
    if c.every == 0 {
        return Err(Error::invalid("checkpoints must be at least 1 iteration apart"));
    }
    if c.path.exists() && !c.path.is_file() {
        return Err(Error::invalid(format!(
            "checkpoint {} is not a regular file (a folder, a device or a pipe)",
            c.path.display()
        )));
    }
    let saved = match c.resume {
        true => Some(read_saved(&c.path, fingerprint, tile, settings)?),
        false if c.path.exists() => return Err(Error::CheckpointExists(c.path.clone())),
        false => None,
    };
    AtomicFile::create(&c.path)?; // a checkpoint that cannot be written fails now
    Ok(saved)
}

/// The backend for `options.backend`, and the note that says which and why.
fn start_backend(
    tile: Tile,
    settings: Settings,
    init: Option<&Mask>,
    options: &RunOptions,
) -> Result<(Box<dyn Backend>, String)> {
    let gpu = |require_gpu_type: bool| gpu_backend(tile, settings, init, options, require_gpu_type);
    let cpu = || -> Result<Box<dyn Backend>> { Ok(Box::new(CpuRun::new(tile, settings, init)?)) };
    let backend = match options.backend {
        BackendChoice::Cpu => cpu()?,
        BackendChoice::Vulkan => gpu(false)?,
        // Any reason the GPU path cannot take the run (no device, d > 2, a tile
        // too large for a binding) falls back to the CPU path, which reports input
        // that is wrong everywhere itself. A device the caller named or handed in
        // is taken whatever its type; otherwise only a GPU.
        BackendChoice::Auto => match gpu(options.device.is_none() && !has_context(options)) {
            Ok(b) => b,
            Err(e) => {
                let b = cpu()?;
                let note = format!("{} (no Vulkan GPU used: {e})", b.describe());
                return Ok((b, note));
            }
        },
    };
    let note = backend.describe();
    Ok((backend, note))
}

/// A Vulkan backend for the run on the context `options` give.
#[cfg(feature = "vulkan")]
fn gpu_backend(
    tile: Tile,
    settings: Settings,
    init: Option<&Mask>,
    options: &RunOptions,
    require_gpu_type: bool,
) -> Result<Box<dyn Backend>> {
    let ctx = context_for(options, require_gpu_type)?;
    Ok(Box::new(VulkanRun::new(&ctx, tile, settings, init, options.vulkan)?))
}
#[cfg(not(feature = "vulkan"))]
fn gpu_backend(_: Tile, _: Settings, _: Option<&Mask>, _: &RunOptions, _: bool) -> Result<Box<dyn Backend>> {
    Err(without_vulkan())
}

/// The error of a Vulkan call in a build without the `vulkan` feature.
#[cfg(not(feature = "vulkan"))]
pub(crate) fn without_vulkan() -> Error {
    Error::VulkanUnavailable("fsot was built without its `vulkan` feature".into())
}

/// Whether the caller handed in a Vulkan context.
pub(crate) fn has_context(options: &RunOptions) -> bool {
    #[cfg(feature = "vulkan")]
    return options.context.is_some();
    #[cfg(not(feature = "vulkan"))]
    {
        let _ = options;
        false
    }
}

/// The Vulkan context of a run: the caller's, or one made on the named device
/// (or the first); with `require_gpu_type`, a CPU implementation is refused.
#[cfg(feature = "vulkan")]
pub(crate) fn context_for(options: &RunOptions, require_gpu_type: bool) -> Result<Context> {
    let ctx = match &options.context {
        Some(c) => c.clone(),
        None => {
            Context::new(&ContextOptions { validation: options.validation, device: options.device.clone() })?
        }
    };
    if require_gpu_type && ctx.info().is_cpu() {
        return Err(Error::VulkanUnavailable(format!(
            "the only Vulkan device is {}, a CPU implementation",
            ctx.info().name
        )));
    }
    Ok(ctx)
}

/// Options for several runs that should share one Vulkan device (a scene
/// plan's masks, stepped together): the context `options` would open, made once,
/// under the same rule (`auto`: a GPU, or a device named or handed in). Where
/// `auto` finds none, or the choice is the CPU, `options` as they are.
#[cfg(not(feature = "vulkan"))]
pub fn shared_context(options: &RunOptions) -> Result<RunOptions> {
    match options.backend {
        BackendChoice::Vulkan => Err(without_vulkan()),
        _ => Ok(options.clone()),
    }
}

/// Options for several runs that share one Vulkan device (see above).
#[cfg(feature = "vulkan")]
pub fn shared_context(options: &RunOptions) -> Result<RunOptions> {
    if options.context.is_some() || options.backend == BackendChoice::Cpu {
        return Ok(options.clone());
    }
    let context = match options.backend {
        BackendChoice::Auto => match context_for(options, options.device.is_none()) {
            Ok(ctx) => ctx,
            Err(_) => return Ok(options.clone()),
        },
        _ => context_for(options, false)?,
    };
    Ok(RunOptions { context: Some(context), ..options.clone() })
}

/// Whether runs started with `options` (from `shared_context`) share one Vulkan
/// device, so that `Run::run_together` steps them in one submission.
#[cfg(feature = "vulkan")]
pub fn shares_device(options: &RunOptions) -> bool {
    options.context.is_some()
}

/// Without Vulkan no runs share a device.
#[cfg(not(feature = "vulkan"))]
pub fn shares_device(_options: &RunOptions) -> bool {
    false
}

/// Runs the optimizer to the end on the CPU path, with no observer.
pub fn optimize(tile: Tile, settings: Settings, init: Option<&Mask>) -> Result<Mask> {
    let options = RunOptions { backend: BackendChoice::Cpu, ..RunOptions::default() };
    let mut run = Run::start(tile, settings, init, options)?;
    run.run(&CancelFlag::new(), &mut |_| {})?;
    run.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_checkpoint_no_run_reaches_is_refused_naming_its_file() {
        let dir = std::env::temp_dir().join(format!("fsot-resumable-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("past.ckpt");
        let tile = Tile::new(4, 4, 2, 1, 1).unwrap();
        let settings = Settings::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), 1).iterations(10);
        let n = tile.values();
        // A file whose checksum and fingerprint hold, at an iteration past the run's end.
        let state = RunState {
            iteration: u32::MAX,
            samples: vec![0.5; n],
            first: vec![0.0; n],
            second: Vec::new(),
            plateau: None,
        };
        checkpoint::write(&path, &checkpoint::fingerprint(&tile, &settings), &state).unwrap();
        let options = RunOptions {
            backend: BackendChoice::Cpu,
            checkpoint: Some(Checkpointing { path: path.clone(), every: 1, resume: true }),
            ..Default::default()
        };
        let e = Run::start(tile, settings, None, options).err().expect("refused").to_string();
        assert!(e.contains("past.ckpt") && e.contains("iteration 4294967295 of a run of 10"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_step_takes_one_iteration_until_the_pace_is_known_then_about_step_seconds_worth() {
        assert_eq!(paced_iterations(None), 1);
        assert_eq!(paced_iterations(Some(STEP_SECONDS / 32.0)), 32);
        assert_eq!(paced_iterations(Some(0.001)), (STEP_SECONDS / 0.001) as u32);
        // Slower than a step's worth: still one iteration at a time.
        assert_eq!(paced_iterations(Some(3.0 * STEP_SECONDS)), 1);
        // A step too quick to time does not limit the next.
        assert_eq!(paced_iterations(Some(0.0)), u32::MAX);
    }
}
