//! The fsot optimizer's Vulkan backend, built on the generic layer in `vk/`:
//! the binding layout and its Rust mirror (`layout`), the transport's launch shape
//! (`shape`), the buffer plan (`buffers`), the pipelines (`pipelines`) and the run
//! (`run`, `VulkanRun`, one implementation of `backend::Backend`) and the
//! stopping rule on the device (`rule`).

pub(crate) mod buffers;
pub mod layout;
pub(crate) mod pipelines;
pub mod rule;
pub(crate) mod run;
pub mod shape;

pub use run::{LaneOrder, LaneTier, VulkanRun};
pub use shape::{TransportKind, TransportShape};

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
///
/// ```
/// let options = fsot::VulkanOptions::default().deterministic(true);
/// assert!(options.deterministic && !options.profile);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct VulkanOptions {
    /// Fixed-point int64 atomics: bit-identical run to run. Otherwise float
    /// atomic add where the device has it, GPUs and CPU implementations
    /// (lavapipe) alike: faster (BENCHMARKS.md), not reproducible bit for bit.
    pub deterministic: bool,
    /// Time each pass with timestamp queries (`Report::profile`).
    pub profile: bool,
    /// Paths forced for tests, in place of the device's choice.
    #[cfg(feature = "internals")]
    #[doc(hidden)]
    pub hooks: VulkanHooks,
    #[cfg(not(feature = "internals"))]
    pub(crate) hooks: VulkanHooks,
}

impl VulkanOptions {
    /// With fixed-point atomics (`deterministic`) on or off.
    pub fn deterministic(mut self, on: bool) -> Self {
        self.deterministic = on;
        self
    }

    /// With the passes timed (`profile`) or not.
    pub fn profile(mut self, on: bool) -> Self {
        self.profile = on;
        self
    }

    /// With paths forced for tests.
    #[cfg(feature = "internals")]
    #[doc(hidden)]
    pub fn hooks(mut self, hooks: VulkanHooks) -> Self {
        self.hooks = hooks;
        self
    }
}

/// What tests force to cover each path a device class may take, where the
/// device at hand would choose otherwise. None and false: the device's choice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VulkanHooks {
    /// The transport pass: per lane (CPU implementations) or by workgroups
    /// (GPUs).
    pub transport: Option<TransportKind>,
    /// The workgroup transport in (invocations, slices per workgroup), as a
    /// GPU runs it.
    pub workgroup_shape: Option<(u32, u32)>,
    /// For d >= 3: the box spline's targets in pairs of float32s even where the
    /// device has shaderFloat64 (devices without it always take them).
    pub float_pair_targets: bool,
    /// The stopping rule left to the host (read back and decided once per
    /// window), as on a device without shaderFloat64.
    pub host_stopping_rule: bool,
    /// The per-lane transport's class limit, unchecked against the loop
    /// budget: a class a CPU implementation's loop cap cuts short must fail
    /// the run instead of moving samples the wrong way.
    pub unchecked_lane_limit: Option<u32>,
    /// Order the per-lane transport's slices this many iterations at a time
    /// (at most a batch), as where one binding cannot hold a batch's orders.
    pub slice_order_slots: Option<u32>,
    /// The large-class stage's sort path, untimed. None: chosen at run time
    /// (`vk::choose_sort_path`: on NVIDIA's and AMD's GPUs the faster of the
    /// look-back path and the block passes, timed on the device at the
    /// stage's expected size; the block passes elsewhere). The look-back path
    /// must not be set on a device that may not keep a waiting workgroup's
    /// peers running (`DeviceInfo::keeps_workgroups_running`), such as a CPU
    /// implementation that runs several threads.
    pub large_sort: Option<SortPath>,
    /// The workgroup transport's second pass, for classes past its limit that
    /// shared memory can still hold: None, on GPUs up to the smallest power of
    /// two holding the kernel's largest class, as the device's shared memory
    /// allows (none on CPU implementations); Some(0) none (those classes go to
    /// the large-class stage's global sorts); Some(m) up to m, a power of two.
    pub defer: Option<u32>,
    /// The workgroup transport's class limit (a power of two from 64 to 2048)
    /// in place of 2048, so that lavapipe's shared memory gives the second
    /// pass classes to take. The per-lane transport ignores it.
    pub local_max: Option<u32>,
    /// Workgroups of the second pass at most, in place of 65535
    /// (`DEFER_GROUPS`), so that each workgroup takes several listed slices.
    pub defer_groups: Option<u32>,
    /// The large-class buffers' capacity in elements, at most the planned one:
    /// a small one makes classes overflow, as a device's largest buffer can.
    pub large_capacity: Option<u32>,
}
