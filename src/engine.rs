//! One interface over the backends, for the command line and benchmarks: pick a
//! backend, step in batches, take the mask.

use crate::error::{Error, Result};
use crate::gpu::context::{Context, ContextOptions};
use crate::gpu::optimizer::{GpuOptions, GpuRun};
use crate::mask::Mask;
use crate::optimize::{Run, RunState, Settings};
use crate::problem::Tile;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackendChoice {
    /// A Vulkan GPU when there is one (not a CPU implementation such as
    /// lavapipe, which is slower than the CPU path, unless the user names that
    /// device), else the CPU path; a GPU that fails mid-run hands over to the CPU.
    Auto,
    Cpu,
    Vulkan,
}

pub enum Engine {
    Cpu(Box<Run>),
    Gpu(Box<GpuRun>),
}

/// What `Engine::start` decided, for the user.
pub struct Started {
    pub engine: Engine,
    pub note: String,
}

impl Engine {
    pub fn start(
        choice: BackendChoice,
        tile: Tile,
        settings: Settings,
        init: Option<&Mask>,
        device: Option<String>,
        gpu: GpuOptions,
    ) -> Result<Started> {
        let try_gpu = |require_gpu_type: bool| -> Result<Started> {
            let ctx = Context::new(&ContextOptions::from_env(device.clone()))?;
            let info = ctx.info().clone();
            if require_gpu_type && info.device_type == ash::vk::PhysicalDeviceType::CPU {
                return Err(Error::VulkanUnavailable(format!(
                    "the only Vulkan device is {}, a CPU implementation",
                    info.name
                )));
            }
            let run = GpuRun::new(&ctx, tile, settings, init, gpu)?;
            let scatter =
                if run.uses_float_atomics() { "float atomics" } else { "fixed point, deterministic" };
            Ok(Started {
                note: format!("backend: vulkan on {} ({}; scatter: {scatter})", info.name, info.driver),
                engine: Engine::Gpu(Box::new(run)),
            })
        };
        let cpu = |why: String| -> Result<Started> {
            Ok(Started {
                engine: Engine::Cpu(Box::new(Run::new(tile, settings, init)?)),
                note: format!("backend: cpu, {} threads{why}", rayon::current_num_threads()),
            })
        };
        match choice {
            BackendChoice::Cpu => cpu(String::new()),
            BackendChoice::Vulkan => try_gpu(false),
            // Any reason the GPU path cannot take the run (no device, d > 2, a tile
            // too large for a binding) falls back to the CPU path, which reports
            // input that is wrong everywhere itself.
            // A device the user named (--device, FSOT_DEVICE) is taken whatever its
            // type; otherwise only a GPU.
            BackendChoice::Auto => {
                match try_gpu(device.is_none() && std::env::var_os("FSOT_DEVICE").is_none()) {
                    Ok(s) => Ok(s),
                    Err(e) => cpu(format!(" (no Vulkan GPU used: {e})")),
                }
            }
        }
    }

    pub fn finished(&self) -> bool {
        match self {
            Engine::Cpu(r) => r.finished(),
            Engine::Gpu(r) => r.finished(),
        }
    }

    pub fn iteration(&self) -> u32 {
        match self {
            Engine::Cpu(r) => r.iteration(),
            Engine::Gpu(r) => r.iteration(),
        }
    }

    pub fn slices_per_iteration(&self) -> u32 {
        match self {
            Engine::Cpu(r) => r.slices_per_iteration(),
            Engine::Gpu(r) => r.slices_per_iteration(),
        }
    }

    /// Runs a few iterations (one on the CPU, a batch on the GPU); returns their
    /// objective estimates.
    pub fn step(&mut self) -> Result<Vec<f64>> {
        match self {
            Engine::Cpu(r) => Ok(vec![r.step()]),
            Engine::Gpu(r) => r.step_batch(u32::MAX),
        }
    }

    /// Runs at most `max` iterations (at least one): one on the CPU, a batch of
    /// up to `max` on the GPU; returns their objective estimates.
    pub fn step_up_to(&mut self, max: u32) -> Result<Vec<f64>> {
        match self {
            Engine::Cpu(r) => Ok(vec![r.step()]),
            Engine::Gpu(r) => r.step_batch(max.max(1)),
        }
    }

    /// Where the run stands, for a checkpoint.
    pub fn state(&self) -> Result<RunState> {
        match self {
            Engine::Cpu(r) => Ok(r.state()),
            Engine::Gpu(r) => r.state(),
        }
    }

    /// Continues from a checkpoint's state (made by either backend).
    pub fn restore(&mut self, saved: &RunState) -> Result<()> {
        match self {
            Engine::Cpu(r) => r.restore(saved),
            Engine::Gpu(r) => r.restore(saved),
        }
    }

    pub fn mask(&self) -> Result<Mask> {
        match self {
            Engine::Cpu(r) => Ok(r.mask()),
            Engine::Gpu(r) => r.mask(),
        }
    }

    /// What the Vulkan validation layer reported (empty on the CPU path or with
    /// the layer off).
    pub fn validation_messages(&self) -> Vec<String> {
        match self {
            Engine::Cpu(_) => Vec::new(),
            Engine::Gpu(r) => r.validation_messages(),
        }
    }

    pub fn is_gpu(&self) -> bool {
        matches!(self, Engine::Gpu(_))
    }
}
