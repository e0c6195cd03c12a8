//! The peers' swap search (`peers::swap`, whose child this is) on Vulkan: FAST's greedy swaps and
//! vector STBN's annealing as two compute passes per batch (`glsl/swap/`).
//!
//! A pass proposes as many swaps as pixels, the very proposals of the CPU path
//! (the same counter-based stream), in batches of rounds. In a round, every
//! proposal's energy change is computed in parallel on the values as they stand
//! at the round's start and decided, and a taken swap claims its two pixels;
//! then a taken swap is applied unless an earlier taken swap of the round claims
//! a pixel it reads or moves. The swaps applied are pairwise apart, so each
//! change is exact and the tracked energy is the energy. A swap so held back is
//! evaluated again in the batch's next round (`SwapReport::recomputed`), as the
//! CPU path evaluates a stale proposal again at its turn, except after the last
//! round (`SwapReport::dropped`). A proposal rejected on a stale change stays
//! rejected, and a retried one comes after later proposals of its batch: a
//! search of the same kind, not the same bits. Batches are sized from the last
//! pass's acceptance as the CPU path sizes its own. One submission and one
//! read-back per pass.

use ash::vk;
use bytemuck::{Pod, Zeroable};

use crate::core::rng::derive;
use crate::error::{Error, Result};
use crate::peers::swap::{mean_abs_delta, start, PairEnergy, Schedule, SwapReport, ValueTerm};
use crate::vk::buffer::Location;
use crate::vk::commands::{barrier, copy, zero};
use crate::vk::{Buffer, ComputeDesc, ComputePipeline, Context};

pub mod shaders {
    //! SPIR-V of `glsl/swap/*.comp`, embedded from `spirv/swap/`.
    spirv_module!("swap");
}

/// The Rust mirror of `glsl/swap/bindings.glsl`; `tests/spirv_layout.rs` checks
/// it against the compiled SPIR-V.
pub mod layout {
    use super::{Pod, Zeroable};

    /// Binding indices (`SWAP_BINDING_*`).
    pub mod binding {
        pub const VALUES: u32 = 0;
        pub const OFFSETS: u32 = 1;
        pub const PROPOSALS: u32 = 2;
        pub const CLAIMS: u32 = 3;
        pub const STATS: u32 = 4;
        /// Bindings in the layout (`SWAP_BINDINGS`).
        pub const BINDINGS: u32 = 5;
        /// Every binding with the name of its block in GLSL.
        pub const BLOCKS: [(&str, u32); 5] = [
            ("Values", VALUES),
            ("Offsets", OFFSETS),
            ("Proposals", PROPOSALS),
            ("Claims", CLAIMS),
            ("Stats", STATS),
        ];
    }

    /// Largest sample dimension (`SWAP_MAX_DIMS`).
    pub const MAX_DIMS: usize = 8;
    /// Fixed-point scale of `SwapStats::energy` (`SWAP_ENERGY_SCALE`).
    pub const ENERGY_SCALE: f64 = 4_294_967_296.0;
    /// `SWAP_TERM_GAUSSIAN`, `SWAP_TERM_NEG_DISTANCE`.
    pub const TERM_GAUSSIAN: u32 = 0;
    pub const TERM_NEG_DISTANCE: u32 = 1;

    /// `SwapPush`: one batch.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SwapPush {
        pub width: u32,
        pub height: u32,
        pub frames: u32,
        pub offsets: u32,
        pub term: u32,
        pub inv_sigma2: f32,
        pub temperature: f32,
        pub pass_key: u32,
        pub first: u32,
        pub count: u32,
        pub batch: u32,
        pub retry: u32,
        pub last: u32,
    }

    /// `SwapOffset`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SwapOffset {
        pub dx: u32,
        pub dy: u32,
        pub dt: u32,
        pub weight: f32,
    }

    /// `SwapProposal`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SwapProposal {
        pub p: u32,
        pub q: u32,
        pub delta: f32,
        pub state: u32,
    }

    /// `SwapStats`.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
    pub struct SwapStats {
        pub energy: i64,
        pub accepted: u32,
        pub dropped: u32,
        pub uphill: u32,
        pub retried: u32,
    }
}

use layout::{binding, SwapOffset, SwapProposal, SwapPush, SwapStats};

/// Invocations per workgroup of both passes: on GPUs, and on CPU
/// implementations (lavapipe), where a workgroup runs on one core and a small
/// batch must still spread over every core.
const WORKGROUP: u32 = 64;
const WORKGROUP_CPU: u32 = 8;
/// Rounds per batch: the first, then rounds over the proposals dropped in the
/// last (each applies at least the earliest of them).
pub const ROUNDS: u32 = 4;
/// Most proposals in one batch.
pub const MAX_BATCH: usize = 65536;
/// Most offsets an energy may have on Vulkan: the commit pass walks 2 x
/// (offsets + 1) pixels per invocation, within lavapipe's 65535 loop iterations.
pub const MAX_OFFSETS: usize = 30_000;

/// Improves `values` (pixels x dims) by swaps on `ctx`, as `swap_search` does
/// on the CPU (see the module's notes for how the two differ).
pub fn swap_search(
    ctx: &Context,
    energy: &PairEnergy,
    values: &mut [f32],
    schedule: Schedule,
    key: u32,
    mut on_pass: impl FnMut(u32, f64),
) -> Result<SwapReport> {
    let tile = *energy.tile();
    let (n, d) = (tile.pixels(), tile.dims);
    let offsets = energy.offsets();
    if d > layout::MAX_DIMS {
        return Err(Error::invalid(format!(
            "the Vulkan swap search takes d <= {}; d = {d} runs on the CPU backend",
            layout::MAX_DIMS
        )));
    }
    if offsets.len() > MAX_OFFSETS {
        // Unavailable, not invalid: the CPU backend takes it (`--backend auto` goes there).
        return Err(Error::VulkanUnavailable(format!(
            "the energy has {} neighbours per pixel; the Vulkan swap search takes at most {MAX_OFFSETS} \
             (the loop budget of a shader invocation); use the CPU backend",
            offsets.len()
        )));
    }
    if !ctx.info().int64_atomics {
        return Err(Error::VulkanUnavailable(format!("{} lacks 64-bit buffer atomics", ctx.info().name)));
    }
    let (mut report, trivial) = start(energy, values, schedule)?;
    if trivial {
        return Ok(report);
    }
    let mut current = report.start_energy;
    let (term, inv_sigma2) = match energy.term() {
        ValueTerm::Gaussian { sigma } => (layout::TERM_GAUSSIAN, (1.0 / (sigma * sigma)) as f32),
        ValueTerm::NegDistance => (layout::TERM_NEG_DISTANCE, 0.0),
    };
    let table: Vec<SwapOffset> = offsets
        .iter()
        .map(|o| SwapOffset { dx: o.dx as u32, dy: o.dy as u32, dt: o.dt as u32, weight: o.weight as f32 })
        .collect();
    let search = Passes::new(ctx, values, n, &table, n.min(MAX_BATCH))?;
    let mut acceptance = 0.5f64;
    let t0 = schedule.start_temperature * mean_abs_delta(energy, values, key);
    for pass in 0..schedule.passes {
        // Claims are cleared at each pass, so rounds are counted within it.
        let mut batch = 1u32;
        // Sized as the CPU path sizes its batches.
        let size = energy.batch_for(acceptance).clamp(8, MAX_BATCH).min(n);
        let base = SwapPush {
            width: tile.width as u32,
            height: tile.height as u32,
            frames: tile.frames as u32,
            offsets: table.len() as u32,
            term,
            inv_sigma2,
            temperature: schedule.temperature(t0, pass) as f32,
            pass_key: derive(key, pass),
            ..SwapPush::default()
        };
        let mut pushes = Vec::with_capacity(n.div_ceil(size) * ROUNDS as usize);
        for first in (0..n).step_by(size) {
            for round in 0..ROUNDS {
                pushes.push(SwapPush {
                    first: first as u32,
                    count: size.min(n - first) as u32,
                    batch,
                    retry: round,
                    last: u32::from(round + 1 == ROUNDS),
                    ..base
                });
                batch = batch
                    .checked_add(1)
                    .ok_or_else(|| Error::invalid("swap search: more than 2^32 rounds"))?;
            }
        }
        let stats = search.pass(&pushes)?;
        report.proposed += n as u64;
        report.accepted += stats.accepted as u64;
        report.uphill += stats.uphill as u64;
        report.dropped += stats.dropped as u64;
        report.recomputed += stats.retried as u64;
        current += stats.energy as f64 / layout::ENERGY_SCALE;
        report.trace.push(current);
        on_pass(pass, current);
        // The pass's rate, smoothed as the CPU path smooths its batches', never zero.
        acceptance = 0.5 * acceptance + 0.5 * (stats.accepted as f64 + 0.5) / (n as f64 + 1.0);
    }
    values.copy_from_slice(&search.values.download::<f32>(values.len())?);
    Ok(report)
}

/// The passes of a search and the buffers they are bound to (pipelines first:
/// dropped before the buffers).
struct Passes {
    propose: ComputePipeline,
    commit: ComputePipeline,
    values: Buffer,
    _offsets: Buffer,
    _proposals: Buffer,
    claims: Buffer,
    stats: Buffer,
    readback: Buffer,
    workgroup: u32,
    ctx: Context,
}

impl Passes {
    fn new(ctx: &Context, values: &[f32], pixels: usize, table: &[SwapOffset], batch: usize) -> Result<Self> {
        let dims = (values.len() / pixels) as u32;
        let values_buf = Buffer::with_data(ctx, values, Location::Device, "swap values")?;
        let offsets = Buffer::with_data(ctx, table, Location::Device, "swap offsets")?;
        let proposals = Buffer::new(
            ctx,
            (batch * std::mem::size_of::<SwapProposal>()) as u64,
            Location::Device,
            "swap proposals",
        )?;
        let claims = Buffer::new(ctx, (pixels * 8) as u64, Location::Device, "swap claims")?;
        let stats_bytes = std::mem::size_of::<SwapStats>() as u64;
        let stats = Buffer::new(ctx, stats_bytes, Location::Device, "swap stats")?;
        let readback = Buffer::new(ctx, stats_bytes, Location::Readback, "swap stats read-back")?;
        let workgroup = if ctx.info().is_cpu() { WORKGROUP_CPU } else { WORKGROUP };
        let pipeline = |spirv: &[u8]| -> Result<ComputePipeline> {
            let p = ComputePipeline::new(
                ctx,
                &ComputeDesc {
                    spirv,
                    bindings: binding::BINDINGS,
                    images: &[],
                    uniforms: &[],
                    texels: &[],
                    full_subgroups: false,
                    push_bytes: std::mem::size_of::<SwapPush>() as u32,
                    spec: &[workgroup, dims],
                    sets: 1,
                },
            )?;
            // SAFETY: `Passes` holds these buffers as long as its pipelines, and
            // dispatches them only through itself.
            unsafe {
                p.bind(
                    0,
                    &[
                        (binding::VALUES, &values_buf),
                        (binding::OFFSETS, &offsets),
                        (binding::PROPOSALS, &proposals),
                        (binding::CLAIMS, &claims),
                        (binding::STATS, &stats),
                    ],
                )?
            };
            Ok(p)
        };
        Ok(Self {
            propose: pipeline(shaders::PROPOSE)?,
            commit: pipeline(shaders::COMMIT)?,
            values: values_buf,
            _offsets: offsets,
            _proposals: proposals,
            claims,
            stats,
            readback,
            workgroup,
            ctx: ctx.clone(),
        })
    }

    /// Records and runs one pass (its batches in order) in one submission;
    /// returns what it did. The claims are cleared before it.
    fn pass(&self, batches: &[SwapPush]) -> Result<SwapStats> {
        let ctx = &self.ctx;
        ctx.submit(|cmd| {
            zero(cmd, &self.stats, 0, vk::WHOLE_SIZE);
            zero(cmd, &self.claims, 0, vk::WHOLE_SIZE);
            barrier(cmd);
            for push in batches {
                let groups = [push.count.div_ceil(self.workgroup), 1, 1];
                self.propose.dispatch(cmd, 0, groups, bytemuck::bytes_of(push));
                barrier(cmd);
                self.commit.dispatch(cmd, 0, groups, bytemuck::bytes_of(push));
                barrier(cmd);
            }
            copy(cmd, &self.stats, &self.readback, std::mem::size_of::<SwapStats>() as u64, 0);
            barrier(cmd);
        })?;
        self.readback
            .read::<SwapStats>(1)?
            .first()
            .copied()
            .ok_or_else(|| Error::invalid("swap search: no statistics read back"))
    }
}
