//! The pipelines of a Vulkan run, each bound to the run's buffers through the one
//! fsot layout.

use super::buffers::RunBuffers;
use super::layout::{binding, TransportPush, UpdatePush};
use super::shaders;
use super::shape::{TransportShape, LARGE_WORKGROUP};
use crate::error::Result;
use crate::vk::{Buffer, ComputeDesc, ComputePipeline, Context, RadixSort, TexelView};

/// Descriptor sets of the gather: keyed by segment, or by projection.
pub const GATHER_BY_SEGMENT: usize = 0;
pub const GATHER_BY_PROJECTION: usize = 1;

/// How the transport passes compute the exact targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Targets {
    /// d <= 2: float32 closed form.
    ClosedForm,
    /// d >= 3: the box spline in f64 (shaderFloat64).
    F64,
    /// d >= 3: the box spline in pairs of float32s (`glsl/fsot/real.glsl`), for
    /// devices without shaderFloat64.
    FloatPairs,
}

pub struct RunPipelines {
    pub transport: ComputePipeline,
    /// The workgroup transport's second pass over the slices it deferred
    /// (`TransportShape::defer_max`), where there is one.
    pub deferred: Option<ComputePipeline>,
    pub update: ComputePipeline,
    /// The large-class stage, when the kernel makes large classes.
    pub large: Option<LargePipelines>,
    /// The stopping rule's pass, on devices with shaderFloat64.
    pub plateau: Option<ComputePipeline>,
    /// The slice order's two passes (count, place), for the per-lane transport.
    pub order: Option<[ComputePipeline; 2]>,
    /// The texel views the per-lane transport and the update pass read on CPU
    /// implementations (bindings `TEXELS`), kept while the sets point at them;
    /// there the update pass leaves the accumulators' reset to the host.
    pub texels: Option<Vec<(u32, TexelView)>>,
}

pub struct LargePipelines {
    pub args: ComputePipeline,
    pub gather: ComputePipeline,
    pub transport: ComputePipeline,
}

/// A pass of the run's family; `full_subgroups` for a pass that relies on
/// full subgroups (`ComputeDesc::full_subgroups`).
fn pipeline(
    ctx: &Context,
    spirv: &[u8],
    push_bytes: usize,
    spec: &[u32],
    sets: u32,
    full_subgroups: bool,
) -> Result<ComputePipeline> {
    let desc = ComputeDesc {
        spirv,
        bindings: binding::BINDINGS,
        push_bytes: push_bytes as u32,
        spec,
        sets,
        images: &[],
        uniforms: &[],
        texels: &binding::TEXELS,
        full_subgroups,
    };
    Ok(ComputePipeline::new(ctx, &desc)?)
}

impl RunPipelines {
    /// The passes for this shape, sample dimension and accumulator, bound to
    /// `buffers` (and the large-class sort's buffers).
    pub fn new(
        ctx: &Context,
        shape: &TransportShape,
        targets: Targets,
        float_acc: bool,
        buffers: &RunBuffers,
        sort: Option<&RadixSort>,
    ) -> Result<Self> {
        let all = buffers.bindings(sort)?;
        // The per-lane shape is for CPU implementations; its passes read through
        // texel views: R32_SFLOAT values, RGBA32UI taps, the int64 accumulators
        // as two words.
        let texels = match shape.per_lane {
            true => {
                use ash::vk::Format;
                let acc = if float_acc { (Format::R32_SFLOAT, 4) } else { (Format::R32G32_UINT, 8) };
                let views = [
                    (binding::SAMPLE_TEXELS, &buffers.samples, (Format::R32_SFLOAT, 4)),
                    (binding::TAP_TEXELS, &buffers.taps, (Format::R32G32B32A32_UINT, 16)),
                    (binding::ACC_TEXELS, &buffers.acc, acc),
                    (binding::FIRST_TEXELS, &buffers.first, (Format::R32_SFLOAT, 4)),
                    (binding::SECOND_TEXELS, &buffers.second, (Format::R32_SFLOAT, 4)),
                ];
                let made: Result<Vec<(u32, TexelView)>> = views
                    .into_iter()
                    .map(|(b, buffer, (format, bytes))| Ok((b, TexelView::new(ctx, buffer, format, bytes)?)))
                    .collect();
                Some(made?)
            }
            false => None,
        };
        let views: Vec<(u32, &TexelView)> = texels.iter().flatten().map(|(b, v)| (*b, v)).collect();
        let bound = |p: ComputePipeline, set: usize, table: Option<&Buffer>| -> Result<ComputePipeline> {
            // SAFETY: the run holds the buffers, views and tables as long as its
            // pipelines, and dispatches them only through itself.
            unsafe {
                p.bind(set, &all)?;
                if !views.is_empty() {
                    p.bind_texels(set, &views)?;
                }
                if let Some(t) = table {
                    p.bind(set, &[(binding::GATHER_TABLE, t)])?;
                }
            }
            Ok(p)
        };
        let tpush = std::mem::size_of::<TransportPush>();
        // d <= 2: the float32 closed-form targets; otherwise the box spline, in
        // f64 or in float32 pairs.
        let transport_spv = match (shape.per_lane, targets, float_acc) {
            (true, Targets::ClosedForm, true) => shaders::TRANSPORT_LANE_FLOAT,
            (true, Targets::ClosedForm, false) => shaders::TRANSPORT_LANE,
            (true, Targets::F64, true) => shaders::TRANSPORT_LANE_DIMS_FLOAT,
            (true, Targets::F64, false) => shaders::TRANSPORT_LANE_DIMS,
            (true, Targets::FloatPairs, true) => shaders::TRANSPORT_LANE_DIMS_DF_FLOAT,
            (true, Targets::FloatPairs, false) => shaders::TRANSPORT_LANE_DIMS_DF,
            (false, Targets::ClosedForm, true) => shaders::TRANSPORT_FLOAT,
            (false, Targets::ClosedForm, false) => shaders::TRANSPORT,
            (false, Targets::F64, true) => shaders::TRANSPORT_DIMS_FLOAT,
            (false, Targets::F64, false) => shaders::TRANSPORT_DIMS,
            (false, Targets::FloatPairs, true) => shaders::TRANSPORT_DIMS_DF_FLOAT,
            (false, Targets::FloatPairs, false) => shaders::TRANSPORT_DIMS_DF,
        };
        // The same constants whatever the tile: llvmpipe compiles a pipeline at
        // its first dispatch (seconds for this pass) and keeps it by its
        // constants, so a constant that changed with the tile would cost every
        // run that compilation (what changes goes in TransportPush).
        let spec = [
            shape.workgroup,
            shape.slices_per_group,
            shape.one_subgroup as u32,
            shape.local_max,
            shape.defer_max,
            0,
            shape.defer_groups,
            shape.subgroup_classes as u32,
        ];
        // The workgroup transport sums and ranks a class subgroup by subgroup.
        let grouped = !shape.per_lane;
        let transport = bound(pipeline(ctx, transport_spv, tpush, &spec, 1, grouped)?, 0, None)?;
        let deferred = match shape.defer_max {
            0 => None,
            max => {
                // (No class of the second pass fits a subgroup.)
                let spec = [shape.defer_workgroup, 1, 0, max, 0, 1, shape.defer_groups, 0];
                Some(bound(pipeline(ctx, transport_spv, tpush, &spec, 1, grouped)?, 0, None)?)
            }
        };
        let update_spv = match (texels.is_some(), float_acc) {
            (false, false) => shaders::UPDATE,
            (false, true) => shaders::UPDATE_FLOAT,
            (true, false) => shaders::UPDATE_TEXELS,
            (true, true) => shaders::UPDATE_TEXELS_FLOAT,
        };
        let update =
            bound(pipeline(ctx, update_spv, std::mem::size_of::<UpdatePush>(), &[256], 1, false)?, 0, None)?;
        let large = match sort {
            Some(_) => {
                let gather = pipeline(ctx, shaders::LARGE_GATHER, 0, &[256], 2, false)?;
                let gather = bound(gather, GATHER_BY_SEGMENT, Some(&buffers.large_seg))?;
                let gather = bound(gather, GATHER_BY_PROJECTION, Some(&buffers.large_pkey))?;
                let spv = match (targets, float_acc) {
                    (Targets::ClosedForm, true) => shaders::TRANSPORT_LARGE_FLOAT,
                    (Targets::ClosedForm, false) => shaders::TRANSPORT_LARGE,
                    (Targets::F64, true) => shaders::TRANSPORT_LARGE_DIMS_FLOAT,
                    (Targets::F64, false) => shaders::TRANSPORT_LARGE_DIMS,
                    (Targets::FloatPairs, true) => shaders::TRANSPORT_LARGE_DIMS_DF_FLOAT,
                    (Targets::FloatPairs, false) => shaders::TRANSPORT_LARGE_DIMS_DF,
                };
                // The same invocations whatever the device: a class may hold
                // taps x spp samples, and each invocation loops over n / WG.
                let transport = bound(pipeline(ctx, spv, tpush, &[LARGE_WORKGROUP], 1, false)?, 0, None)?;
                let args = bound(pipeline(ctx, shaders::LARGE_ARGS, 0, &[], 1, false)?, 0, None)?;
                Some(LargePipelines { args, gather, transport })
            }
            None => None,
        };
        let plateau = super::rule::pipeline(ctx)?.map(|p| bound(p, 0, None)).transpose()?;
        let order = match shape.per_lane {
            true => Some([
                bound(pipeline(ctx, shaders::SLICE_ORDER_COUNT, tpush, &[], 1, false)?, 0, None)?,
                bound(pipeline(ctx, shaders::SLICE_ORDER_PLACE, tpush, &[], 1, false)?, 0, None)?,
            ]),
            false => None,
        };
        Ok(Self { transport, deferred, update, large, plateau, order, texels })
    }
}
