//! The fsot optimizer's Vulkan backend, built on the generic layer in `vk/`:
//! the binding layout and its Rust mirror (`layout`), the transport's launch shape
//! (`shape`), the buffer plan (`buffers`), the pipelines (`pipelines`) and the run
//! (`run`, `VulkanRun`, one implementation of `backend::Backend`), the stopping
//! rule on the device (`rule`); and the peers' swap search on Vulkan (`swap`).

pub mod buffers;
pub mod layout;
pub mod pipelines;
pub mod rule;
pub mod run;
pub mod shape;
pub mod swap;

pub use run::{LaneOrder, LaneTier, VulkanRun};
pub use shape::{ClassSort, TransportKind, TransportShape};

use crate::vk::SortPath;

pub mod shaders {
    //! SPIR-V of `glsl/fsot/*.comp` and their variants, embedded from `spirv/fsot/`.
    spirv_module!("fsot");
}

/// Largest dimension whose exact targets the GPU path takes in float32 closed
/// form; beyond it, the box spline (`glsl/fsot/targets.glsl`), in f64 where the
/// device has shaderFloat64, else in pairs of float32s.
pub const CLOSED_FORM_DIMS: usize = 2;
/// Iterations recorded per submission.
pub const BATCH: u32 = 32;

/// How a Vulkan run works.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VulkanOptions {
    /// Fixed-point int64 atomics: bit-identical run to run. Otherwise float
    /// atomic add where the device has it, GPUs and CPU implementations
    /// (lavapipe) alike: faster (on lavapipe about 14% less time a run since the
    /// texel views: `bench/results/issue16-float-default.txt`), not reproducible
    /// bit for bit.
    pub deterministic: bool,
    /// Time each pass with timestamp queries.
    pub profile: bool,
    /// Which transport pass to use: None picks by device (per lane on CPU
    /// implementations, workgroups on GPUs); tests force each.
    pub transport: Option<TransportKind>,
    /// For d >= 3: the box spline's targets in pairs of float32s even where the
    /// device has shaderFloat64 (devices without it always take them): for
    /// tests and comparisons.
    pub float_pair_targets: bool,
    /// Force the workgroup transport with (invocations, slices per workgroup):
    /// for tuning (the command line reads it from `FSOT_TRANSPORT=WG,SPG`).
    pub transport_shape: Option<(u32, u32)>,
    /// Leave a stopping rule to the host (read back and decided once per
    /// window) even where the device could evaluate it: to compare.
    pub host_stopping_rule: bool,
    /// The per-lane transport's class limit, unchecked against the loop
    /// budget: for tests that a class a CPU implementation's loop cap cuts
    /// short fails the run instead of moving samples the wrong way.
    pub unchecked_lane_limit: Option<u32>,
    /// Order the per-lane transport's slices this many iterations at a time
    /// (at most a batch), as where one binding cannot hold a batch's orders:
    /// for tests.
    pub slice_order_slots: Option<u32>,
    /// The large-class stage's sort path. None: chosen at run time
    /// (`vk::choose_sort_path`: on GPUs the faster of the look-back path and
    /// the block passes, timed on the device at the stage's expected size;
    /// the block passes on CPU implementations). Set: that path, untimed (for
    /// tests and comparisons; the command line reads `FSOT_SORT`). The look-back
    /// path must not be set on a CPU implementation that runs several threads.
    pub large_sort: Option<SortPath>,
    /// How the workgroup transport sorts a class: by default by buckets, and
    /// those that fit a subgroup by the subgroup alone; `Buckets` or `Bitonic`
    /// (what it did before the bucket sort, which keeps it as its fallback) for
    /// every class, to compare on a device (the command line reads
    /// `FSOT_CLASS_SORT`). The masks are the same whichever.
    pub class_sort: ClassSort,
    /// The workgroup transport's second pass, for classes past its limit (2048)
    /// that shared memory can still hold: None, on GPUs up to the smallest
    /// power of two holding the kernel's largest class, as the device's shared
    /// memory allows (none on CPU implementations); Some(0) none (those
    /// classes go to the large-class stage's global sorts, as before; the
    /// command line reads `FSOT_DEFER=0`, to compare); Some(m) up to m, a power
    /// of two (for tests).
    pub defer: Option<u32>,
    /// The workgroup transport's class limit (a power of two from 64 to 2048)
    /// in place of 2048: for tests, which give lavapipe's shared memory a
    /// second pass to run, and for tuning (the command line reads
    /// `FSOT_LOCAL_MAX`). The per-lane transport ignores it.
    pub local_max: Option<u32>,
    /// Workgroups of the second pass at most, in place of 65535 (`DEFER_GROUPS`):
    /// for tests, which then see each workgroup take several listed slices.
    pub defer_groups: Option<u32>,
    /// The per-lane transport's slices per invocation at most, in place of as
    /// many as the loop budget allows at each chunk's classes
    /// (`TransportShape::lane_table`): for
    /// tests and comparisons (the command line reads `FSOT_LANE_ROUNDS`).
    pub lane_rounds: Option<u32>,
    /// The chunks the per-lane transport aims to share each iteration's slices
    /// out in, in place of LANE_CHUNKS_PER_THREAD for each of the host's
    /// threads (`TransportShape::lane_table`): for tests and comparisons (the
    /// command line reads `FSOT_LANE_CHUNKS`).
    pub lane_chunks: Option<u32>,
}
