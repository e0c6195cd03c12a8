//! The radix sort's decoupled look-back path (`SortPath::LookBack`) against the
//! CPU's stable sort. A workgroup of that path waits on blocks that started
//! before it; on lavapipe with several threads such a wait can run past
//! lavapipe's 65535 loop iterations per invocation, which cuts it short
//! silently and misplaces the block (`SortPath::LookBack`), so on lavapipe this
//! binary runs it with one thread (LP_NUM_THREADS=1, set before the device is
//! made: blocks then run one after another, in ticket order, and none waits);
//! on a GPU the variable is ignored and the workgroups really wait on each
//! other.

#[path = "../../../tests/common/mod.rs"]
mod common;

use fsot::core::rng::{derive, Stream};
use fsot::vk::buffer::{Buffer, Location};
use fsot::vk::{RadixSort, SortCount, SortPath};

/// The CPU's stable sort by the low `bits` bits, in whole 8-bit digits.
fn cpu_sort_by(keys: &[u32], vals: &[u32], bits: u32) -> (Vec<u32>, Vec<u32>) {
    let digits = bits.div_ceil(8) * 8;
    let mask = if digits == 32 { u32::MAX } else { (1 << digits) - 1 };
    let mut pairs: Vec<(u32, u32)> = keys.iter().copied().zip(vals.iter().copied()).collect();
    pairs.sort_by_key(|p| p.0 & mask); // stable
    pairs.into_iter().unzip()
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_look_back_path_sorts_stably_by_any_number_of_low_bits_with_either_count() {
    // One test in this binary: the variable is read when llvmpipe starts.
    std::env::set_var("LP_NUM_THREADS", "1");
    let ctx = common::gpu_context();
    let mut rng = Stream::new(derive(11, 3));
    // The count set by the host.
    let mut sort = RadixSort::new(&ctx, 300_000, SortCount::Host).unwrap();
    sort.path = SortPath::LookBack;
    let block = sort.shape().block;
    assert!(!sort.single_pass(Some(block + 1)));
    for n in [0, 1, 2, 255, block - 1, block, block + 1, 3 * block + 7, 65536, 131_073, 300_000] {
        for bits in [8u32, 20, 32] {
            // Many duplicates in the low bits: stability shows.
            let keys: Vec<u32> = (0..n).map(|_| rng.next_u32() & 0xfff0_0fff).collect();
            let vals: Vec<u32> = (0..n).collect();
            let (gk, gv) = sort.sort_pairs_by(&keys, &vals, bits).unwrap();
            let (ck, cv) = cpu_sort_by(&keys, &vals, bits);
            assert!(
                gk == ck && gv == cv,
                "host count, n = {n}, {bits} bits: differs from the CPU's stable sort"
            );
        }
    }
    drop(sort);
    // The count only on the GPU (the first word of a buffer): indirect dispatches.
    let mut count = Buffer::new(&ctx, 16, Location::Upload, "test-count").unwrap();
    // SAFETY: `count` outlives the sort (declared before it).
    let mut sort = RadixSort::new(&ctx, 200_000, unsafe { SortCount::device(&count) }).unwrap();
    sort.path = SortPath::LookBack;
    for n in [1u32, block + 1, 99_999, 200_000] {
        let keys: Vec<u32> = (0..n).map(|_| rng.next_u32()).collect();
        let vals: Vec<u32> = (0..n).map(|i| i ^ 0x5555).collect();
        let (gk, gv) = common::sort_with_device_count(&ctx, &mut sort, &mut count, &keys, &vals);
        let (ck, cv) = cpu_sort_by(&keys, &vals, 32);
        assert!(gk == ck && gv == cv, "device count, n = {n}: differs from the CPU's stable sort");
    }
    drop(sort);
    // Never given a count: the host's count starts at 0, so nothing moves; then
    // a known count past the capacity sorts the capacity.
    let n = 5000u32;
    let keys: Vec<u32> = (0..n).map(|_| rng.next_u32()).collect();
    let vals: Vec<u32> = (0..n).collect();
    let mut sort = RadixSort::new(&ctx, n, SortCount::Host).unwrap();
    sort.path = SortPath::LookBack;
    sort.upload_pairs(&keys, &vals).unwrap();
    // SAFETY: the sort outlives this submission, which is waited for.
    ctx.submit(|cmd| unsafe { sort.record(cmd, 32, None) }).unwrap();
    assert_eq!(sort.keys().download::<u32>(n as usize).unwrap(), keys, "a sort of 0 pairs");
    sort.set_count(n).unwrap();
    // SAFETY: as above.
    ctx.submit(|cmd| unsafe { sort.record(cmd, 32, Some(u32::MAX)) }).unwrap();
    let (ck, cv) = cpu_sort_by(&keys, &vals, 32);
    assert_eq!(sort.keys().download::<u32>(n as usize).unwrap(), ck, "a count past the capacity");
    assert_eq!(sort.vals().download::<u32>(n as usize).unwrap(), cv, "a count past the capacity");
    drop(sort);
    // The sort benchmark times this path on GPUs; its run checks the result
    // against the CPU's (an error otherwise) in five dispatches.
    let b = fsot_cli::bench::bench_sort(&ctx, 70_000, 1, SortPath::LookBack).unwrap();
    assert_eq!(b.dispatches, 5);
    common::assert_no_validation_messages(&ctx);
}
