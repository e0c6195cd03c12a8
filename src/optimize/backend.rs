//! One interface over the optimizer's backends: the CPU path (`cpu`) and
//! Vulkan (`vulkan`). `run::Run` drives a backend through it; nothing else needs to
//! know which one it has.

use crate::core::mask::Mask;
use crate::core::step_rule::{Plateau, PlateauState};
use crate::error::Result;
use crate::optimize::settings::RunState;

/// Where a run may go.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum BackendChoice {
    /// A Vulkan GPU when there is one (not a CPU implementation such as
    /// lavapipe, which is slower than the CPU path, unless a device is named),
    /// else the CPU path; a GPU that fails mid-run hands over to the CPU.
    #[default]
    Auto,
    /// The CPU path.
    Cpu,
    /// A Vulkan device of any type (a CPU implementation included); an error
    /// where there is none, and no hand-over to the CPU when it fails.
    Vulkan,
}

/// Which backend a run is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackendKind {
    /// The CPU path.
    Cpu,
    /// A Vulkan device.
    Vulkan,
}

impl BackendKind {
    /// The backend's name: "cpu" or "vulkan".
    pub fn name(&self) -> &'static str {
        match self {
            BackendKind::Cpu => "cpu",
            BackendKind::Vulkan => "vulkan",
        }
    }
}

/// GPU time per pass, from timestamp queries (nanoseconds, summed).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Profile {
    /// The first transport pass (with the slice order's passes).
    pub transport_ns: f64,
    /// The classes too large for the first transport pass: its second pass and
    /// the large-class stage.
    pub large_ns: f64,
    /// The update pass, which moves the samples.
    pub update_ns: f64,
    /// Iterations profiled (the times sum over them).
    pub iterations: u32,
    /// The least bytes each pass must move per iteration (a model: see
    /// `vulkan::run::VulkanRun::pass_bytes`), so a pass's distance to the memory
    /// bandwidth's floor can be read off its time.
    pub transport_bytes: f64,
    /// The large-class stage's least bytes per iteration, by the same model.
    pub large_bytes: f64,
    /// The update pass's least bytes per iteration, by the same model.
    pub update_bytes: f64,
}

impl Profile {
    /// The GPU's own time over every profiled iteration.
    pub fn seconds(&self) -> f64 {
        (self.transport_ns + self.large_ns + self.update_ns) * 1e-9
    }
}

/// What a backend has to say after (or during) a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// Time per pass, when profiling (Vulkan).
    pub profile: Option<Profile>,
    /// Large classes skipped because their buffer was full (Vulkan; should be 0).
    pub skipped_large_classes: u64,
    /// What the Vulkan validation layer reported (empty with the layer off).
    pub validation_messages: Vec<String>,
    /// The large-class stage's sort path and how it was chosen, in words
    /// (Vulkan, where the run has that stage and the path was timed or set).
    pub large_sort: Option<String>,
    /// The transport pass, its shape and its class sort, in words (Vulkan).
    pub transport: Option<String>,
}

/// A run of the optimizer on one backend: step, save, restore, read.
pub trait Backend: Send {
    fn kind(&self) -> BackendKind;
    /// The backend and its device, in words.
    fn describe(&self) -> String;
    /// Iterations done.
    fn iteration(&self) -> u32;
    fn slices_per_iteration(&self) -> u32;
    /// Runs at least one and at most `max` iterations (one on the CPU, a batch
    /// on the GPU); returns their objective estimates. None past the end.
    fn step_up_to(&mut self, max: u32) -> Result<Vec<f64>>;
    /// Where the run stands, for a checkpoint.
    fn state(&self) -> Result<RunState>;
    /// Continues from a saved state (made by either backend).
    fn restore(&mut self, saved: &RunState) -> Result<()>;
    /// The samples as they are now.
    fn samples(&self) -> Result<Vec<f32>>;
    /// The samples with their provenance.
    fn mask(&self) -> Result<Mask>;
    /// Diagnostics: the summed displacement of every coordinate from the slices
    /// of iteration `iteration`, without moving anything.
    fn displacements(&mut self, iteration: u32) -> Result<Vec<f64>>;
    /// The step scale of the following iterations, set by an end-agnostic
    /// schedule (`step_rule::Plateau`); None: the cosine schedule over the run's
    /// iterations.
    fn set_scale(&mut self, scale: Option<f32>);
    /// Takes over an end-agnostic schedule's stopping rule, standing at `state`
    /// (with `target`, the objective that ends the run, if any): the backend then
    /// sets its own step scale and ends the run itself (Vulkan: on the device).
    /// False where it cannot; the caller then evaluates the rule (`set_scale`).
    fn adopt_plateau(
        &mut self,
        _rule: &Plateau,
        _state: &PlateauState,
        _target: Option<f64>,
    ) -> Result<bool> {
        Ok(false)
    }
    /// The adopted rule's state after the last step, and whether it ended the
    /// run. None unless adopted.
    fn plateau(&self) -> Option<(PlateauState, bool)> {
        None
    }
    fn report(&self) -> Report;
    /// Runs whose backends give the same group can step together in one
    /// submission (`step_together`): on Vulkan, runs on one device. None: this
    /// run steps alone.
    fn group(&self) -> Option<usize> {
        None
    }
    /// Steps this run and `others` (runs of its group) together: up to `max[0]`
    /// iterations of this run and `max[i + 1]` of `others[i]`; each run's
    /// objective estimates, this run's first. Backends without groups refuse.
    fn step_together(&mut self, others: &mut [&mut dyn Backend], max: &[u32]) -> Result<Vec<Vec<f64>>> {
        let _ = (others, max);
        Err(crate::error::Error::invalid("this backend steps its runs one at a time"))
    }
    /// The run as `Any`, for a backend's own `step_together` to find its kind
    /// among `others`.
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any;
}
