//! A run of the optimizer: its settings (`settings`), the run the library owns
//! (`run`: backend choice, fall-back, checkpoints, cancellation), checkpoint
//! files (`checkpoint`), the one interface over the backends (`backend`), the
//! wall clock budgets read (`clock`), and the backends: the CPU path (`cpu`) and
//! Vulkan (`vulkan`).
pub mod backend;
pub mod checkpoint;
pub(crate) mod clock;
pub mod cpu;
pub mod run;
pub mod settings;
#[cfg(feature = "vulkan")]
pub mod vulkan;
