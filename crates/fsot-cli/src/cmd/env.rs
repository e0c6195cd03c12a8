//! The environment variables the command line reads and hands to the library as
//! options (the library reads none but the documented `FSOT_FAULT` test switch).

use fsot::gpu::shape::{ClassSort, TransportShape, LOCAL_MAX};
use fsot::vk::{Context, ContextOptions, SortPath};

use crate::{Error, Result};

/// The Vulkan device: the flag, else `FSOT_DEVICE`.
pub(crate) fn device(flag: Option<String>) -> Option<String> {
    flag.or_else(|| std::env::var("FSOT_DEVICE").ok()).filter(|d| !d.is_empty())
}

/// `FSOT_VALIDATION=1`: the Vulkan validation layer on.
pub(crate) fn validation() -> bool {
    std::env::var("FSOT_VALIDATION").map(|v| v == "1").unwrap_or(false)
}

/// `FSOT_FLOAT_PAIRS=1`: for d >= 3, the box spline's targets in pairs of
/// float32s even on a device with shaderFloat64 (to compare the two).
pub(crate) fn float_pair_targets() -> bool {
    std::env::var("FSOT_FLOAT_PAIRS").map(|v| v == "1").unwrap_or(false)
}

/// `FSOT_HOST_RULE=1`: a stopping rule evaluated by the host once per window
/// even where the device could evaluate it (to compare the two).
pub(crate) fn host_stopping_rule() -> bool {
    std::env::var("FSOT_HOST_RULE").map(|v| v == "1").unwrap_or(false)
}

/// `FSOT_TRANSPORT=WG,SPG`: the workgroup transport forced to that shape (tuning).
pub(crate) fn transport_shape() -> Option<(u32, u32)> {
    let v = std::env::var("FSOT_TRANSPORT").ok()?;
    let f: Vec<u32> = v.split(',').filter_map(|x| x.trim().parse().ok()).collect();
    match f[..] {
        [wg, spg] if wg > 0 && spg > 0 => Some((wg, spg)),
        _ => None,
    }
}

/// `FSOT_SORT=blocks`: the large-class stage sorts by the block passes even
/// where the look-back path was timed faster, or where a CPU implementation
/// would take the lanes path (to compare); unset: the path is chosen at run
/// time. `SortPath::Tail` is what `Auto` does on a GPU for a count only on the
/// device (the tail scan up to its limit, the four block passes past it), and
/// never the lanes path. The look-back path cannot be forced from here: on a
/// CPU implementation with several threads it could wait forever.
pub(crate) fn large_sort() -> Result<Option<SortPath>> {
    match std::env::var("FSOT_SORT").ok().as_deref() {
        None | Some("") => Ok(None),
        Some("blocks") => Ok(Some(SortPath::Tail)),
        Some(other) => Err(Error::invalid(format!(
            "FSOT_SORT={other}: it takes `blocks` (the block passes), or is unset (the path chosen at run time)"
        ))),
    }
}

/// `FSOT_CLASS_SORT`: how the workgroup transport (GPUs; lavapipe for d >= 3)
/// sorts a class: `subgroup` (the default: by buckets, and at d <= 2 a class
/// that fits a subgroup by the subgroup alone), `buckets` (every class by
/// buckets) or `bitonic` (every class by the bitonic network), to compare.
pub(crate) fn class_sort() -> Result<ClassSort> {
    match std::env::var("FSOT_CLASS_SORT").ok().as_deref() {
        None | Some("") | Some("subgroup") => Ok(ClassSort::Subgroup),
        Some("buckets") => Ok(ClassSort::Buckets),
        Some("bitonic") => Ok(ClassSort::Bitonic),
        Some(other) => Err(Error::invalid(format!(
            "FSOT_CLASS_SORT={other}: it takes `subgroup` (the default), `buckets` or `bitonic`"
        ))),
    }
}

/// `FSOT_DEFER=0`: no second pass of the workgroup transport (GPUs); the classes
/// past its limit go to the large-class stage's global sorts, to compare; unset:
/// the second pass where the device's shared memory holds those classes.
pub(crate) fn defer() -> Result<Option<u32>> {
    match std::env::var("FSOT_DEFER").ok().as_deref() {
        None | Some("") => Ok(None),
        Some("0") => Ok(Some(0)),
        Some(other) => Err(Error::invalid(format!(
            "FSOT_DEFER={other}: it takes 0 (no second pass), or is unset (the second pass where it fits)"
        ))),
    }
}

/// `FSOT_LOCAL_MAX=N`: the workgroup transport's first pass sorts classes up to N
/// (a power of two from 64 to 2048) instead of 2048, handing the larger ones to
/// its second pass (GPUs) or to the large-class stage: less shared memory and
/// fewer registers a workgroup, for tuning; unset: 2048.
pub(crate) fn local_max() -> Result<Option<u32>> {
    let takes = format!("a power of two from 64 to {LOCAL_MAX}, or is unset ({LOCAL_MAX})");
    u32_variable("FSOT_LOCAL_MAX", TransportShape::local_max_allowed, &takes)
}

/// `FSOT_LANE_ROUNDS=N`: each invocation of the per-lane transport takes at most
/// N slices (a positive integer; the loop budget still bounds it): to compare
/// (1: one slice an invocation, a workgroup per eight slices); unset: as many
/// as the loop budget allows.
pub(crate) fn lane_rounds() -> Result<Option<u32>> {
    u32_variable("FSOT_LANE_ROUNDS", |n| n >= 1, "a positive integer, or is unset")
}

/// `FSOT_LANE_CHUNKS=N`: the per-lane transport aims at N chunks of slices an
/// iteration (a positive integer; the loop budget, and a chunk for each tier,
/// may make more): to compare; unset: four for each of the host's threads.
pub(crate) fn lane_chunks() -> Result<Option<u32>> {
    u32_variable("FSOT_LANE_CHUNKS", |n| n >= 1, "a positive integer, or is unset")
}

/// The variable `name` as a number that `allowed` accepts; None when unset or
/// empty; otherwise a clear error saying what it `takes`.
fn u32_variable(name: &str, allowed: impl Fn(u32) -> bool, takes: &str) -> Result<Option<u32>> {
    match std::env::var(name).ok().as_deref() {
        None | Some("") => Ok(None),
        Some(v) => match v.parse::<u32>() {
            Ok(n) if allowed(n) => Ok(Some(n)),
            _ => Err(Error::invalid(format!("{name}={v}: it takes {takes}"))),
        },
    }
}

/// A Vulkan context on the device the flag or the environment names.
pub(crate) fn context(flag: Option<String>) -> Result<Context> {
    Context::new(&ContextOptions { validation: validation(), device: device(flag) })
}

/// A cancel flag that Ctrl-C (SIGINT) and SIGTERM set. Once per process.
pub fn interrupt_flag() -> Result<fsot::run::CancelFlag> {
    let flag = fsot::run::CancelFlag::new();
    let set = flag.clone();
    ctrlc::set_handler(move || set.cancel())
        .map_err(|e| Error::invalid(format!("cannot catch interrupts: {e}")))?;
    Ok(flag)
}
