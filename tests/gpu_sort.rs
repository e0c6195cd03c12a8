//! The GPU radix sort against the CPU's stable sort: random keys, duplicates,
//! signed zeros, extremes, and awkward sizes. Equal keys keep their input order.
#![cfg(feature = "vulkan")]

mod common;

use fsot::core::rng::{derive, Stream};
use fsot::vk::sort::{float_key, SortShape};
use fsot::vk::{Buffer, Location, RadixSort, SortCount, SortPath};

fn cpu_sort(keys: &[u32], vals: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut pairs: Vec<(u32, u32)> = keys.iter().copied().zip(vals.iter().copied()).collect();
    pairs.sort_by_key(|p| p.0); // stable
    pairs.into_iter().unzip()
}

fn check(sort: &mut RadixSort, keys: Vec<u32>, what: &str) {
    let vals: Vec<u32> = (0..keys.len() as u32).collect();
    let (gk, gv) = sort.sort_pairs(&keys, &vals).unwrap();
    let (ck, cv) = cpu_sort(&keys, &vals);
    assert_eq!(gk.len(), ck.len(), "{what}");
    if let Some(i) = (0..ck.len()).find(|&i| gk[i] != ck[i] || gv[i] != cv[i]) {
        panic!(
            "{what} (n = {}): first difference at {i}: gpu ({}, {}) cpu ({}, {})",
            keys.len(),
            gk[i],
            gv[i],
            ck[i],
            cv[i]
        );
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn sorts_like_the_cpu_at_awkward_sizes() {
    let ctx = common::gpu_context();
    // Up to 4M + 1 pairs, or the device's most.
    let most = RadixSort::max_capacity(&ctx).min((1 << 22) + 1);
    let mut sort = RadixSort::new(&ctx, most, SortCount::Host).unwrap();
    let mut rng = Stream::new(derive(5, 5));
    let mut sizes = vec![0usize, 1, 2, 3, 7, 255, 256, 257, 2047, 2048, 2049, 4095, 65537];
    for k in [12u32, 16, 20, 22] {
        sizes.push((1 << k) - 1);
        sizes.push((1 << k) + 1);
    }
    sizes.retain(|&n| n <= most as usize);
    for n in sizes {
        let keys: Vec<u32> = (0..n).map(|_| rng.next_u32()).collect();
        check(&mut sort, keys, "random keys");
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn keeps_equal_keys_in_input_order_and_orders_float_keys() {
    let ctx = common::gpu_context();
    let mut sort = RadixSort::new(&ctx, 100_000, SortCount::Host).unwrap();
    let mut rng = Stream::new(derive(6, 6));
    // Heavy duplicates: 5 distinct keys.
    let dup: Vec<u32> =
        (0..100_000).map(|_| [0, 7, 0x8000_0000, u32::MAX, 12345][rng.below(5) as usize]).collect();
    check(&mut sort, dup, "duplicates");
    // All equal.
    check(&mut sort, vec![42; 5000], "all equal");
    // Already sorted and reversed.
    check(&mut sort, (0..70_000).collect(), "sorted");
    check(&mut sort, (0..70_000).rev().collect(), "reversed");
    // Float keys: signed zeros, extremes, infinities, subnormals.
    let floats = [
        0.0f32,
        -0.0,
        1.0,
        -1.0,
        f32::MAX,
        f32::MIN,
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE,
        f32::INFINITY,
        f32::NEG_INFINITY,
        1e-45,
        -1e-45,
        0.5,
        -0.5,
    ];
    let mut keys = Vec::new();
    for i in 0..3000 {
        keys.push(float_key(floats[i % floats.len()]));
    }
    check(&mut sort, keys.clone(), "float keys");
    let vals: Vec<u32> = (0..keys.len() as u32).collect();
    let (sorted, _) = sort.sort_pairs(&keys, &vals).unwrap();
    // Decoded, the keys come out in float order, -0.0 before +0.0.
    let decoded: Vec<f32> = sorted
        .iter()
        .map(|&k| f32::from_bits(if k & 0x8000_0000 != 0 { k & 0x7fff_ffff } else { !k }))
        .collect();
    assert!(decoded.windows(2).all(|w| w[0] <= w[1]));
    let first_pos_zero = decoded.iter().position(|v| *v == 0.0 && v.is_sign_positive()).unwrap();
    assert!(decoded[first_pos_zero - 1].is_sign_negative());
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn refuses_more_pairs_than_it_can_hold() {
    let ctx = common::gpu_context();
    let mut sort = RadixSort::new(&ctx, 1000, SortCount::Host).unwrap();
    assert!(sort.set_count(1001).is_err());
    assert!(RadixSort::new(&ctx, u32::MAX, SortCount::Host).is_err());
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn every_path_sorts_stably_by_any_number_of_low_bits() {
    // The single-workgroup pass (one block by default on GPUs, forced here far
    // past it), the histogram's tail scan (up to TAIL_MAX_BLOCKS blocks), the
    // four block passes (forced at small counts) and the lanes path (a run an
    // invocation: by default on CPU implementations), by 8, 20 and 32 bits
    // (one, three and four passes: an odd count ends in the second buffers), on
    // keys with many duplicates in their low bits.
    let ctx = common::gpu_context();
    let mut sort = RadixSort::new(&ctx, 300_000, SortCount::Host).unwrap();
    let block = sort.shape().block;
    let tail_max = fsot::vk::sort::TAIL_MAX_BLOCKS * block;
    if ctx.info().is_cpu() {
        assert!(sort.lanes_path(), "a CPU implementation takes the lanes path by default");
        assert!(!sort.single_pass(Some(1)) && !sort.tail_scan(Some(1)));
    } else {
        assert!(!sort.lanes_path());
        assert!(sort.single_pass(Some(block)) && !sort.single_pass(Some(block + 1)));
        assert!(sort.tail_scan(Some(tail_max)) && !sort.tail_scan(Some(tail_max + 1)));
    }
    sort.path = SortPath::Tail;
    assert!(sort.tail_scan(Some(tail_max)) && !sort.tail_scan(Some(tail_max + 1)));
    sort.path = SortPath::Auto;
    assert!(!sort.single_pass(None), "a count only on the GPU never takes the single pass");
    let mut rng = Stream::new(derive(9, 9));
    let sizes = [
        0,
        1,
        2,
        7,
        255,
        256,
        257,
        block - 1,
        block,
        block + 1,
        2 * block + 1,
        65536,
        tail_max,
        tail_max + 1,
        fsot::vk::sort::LANE_RUN * 73 + 5,
    ];
    for path in [SortPath::Auto, SortPath::Single, SortPath::Tail, SortPath::Blocks, SortPath::Lanes] {
        sort.path = path;
        for &n in &sizes {
            if path == SortPath::Single && n > 100_000 {
                continue; // one workgroup: slow past a few blocks on lavapipe
            }
            for bits in [8u32, 20, 32] {
                let keys: Vec<u32> = (0..n).map(|_| rng.next_u32() & 0xfff0_0fff).collect();
                let vals: Vec<u32> = (0..n).collect();
                let (gk, gv) = sort.sort_pairs_by(&keys, &vals, bits).unwrap();
                // Whole 8-bit digits: 20 bits sort by the low 24.
                let digits = bits.div_ceil(8) * 8;
                let mask = if digits == 32 { u32::MAX } else { (1 << digits) - 1 };
                let mut pairs: Vec<(u32, u32)> = keys.iter().copied().zip(vals.iter().copied()).collect();
                pairs.sort_by_key(|p| p.0 & mask); // stable
                let (ck, cv): (Vec<u32>, Vec<u32>) = pairs.into_iter().unzip();
                assert!(
                    gk == ck && gv == cv,
                    "{path:?}, n = {n}, {bits} bits: differs from the CPU's stable sort"
                );
            }
        }
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn every_block_shape_the_device_runs_sorts_like_the_cpu() {
    // Every workgroup x items the device fits, not only the one it is given:
    // 8 to 64 items an invocation, blocks of 64 to 4096 pairs (a shape's arrays
    // are sized by its items: a fixed size would break every shape past 32). Each
    // path, at sizes around one block, several, the tail scan's last and the
    // scan's two levels' limit for the smallest blocks (64 x 64 / 256 x 64).
    let ctx = common::gpu_context();
    let info = ctx.info().clone();
    let fits = |wg: u32, items: u32| {
        SortShape::fits(wg, items, info.subgroup_size, info.max_workgroup_invocations, info.max_shared_memory)
    };
    let lanes = info.subgroup_size;
    let shapes: Vec<SortShape> =
        [(lanes, 8), (lanes, 40), (lanes, 64), (2 * lanes, 24), (4 * lanes, 32), (256, 16)]
            .into_iter()
            .filter_map(|(wg, items)| fits(wg, items))
            .collect();
    assert!(shapes.iter().any(|s| s.items > 32), "no shape past 32 items fits {}", info.name);
    let mut rng = Stream::new(derive(11, 11));
    for shape in shapes {
        let block = shape.block;
        let tail_max = fsot::vk::sort::TAIL_MAX_BLOCKS * block;
        let capacity = shape.scan_capacity().min(3 * tail_max as u64 + 7) as u32;
        let mut sort = RadixSort::with_shape(&ctx, capacity, SortCount::Host, shape).unwrap();
        let mut sizes = vec![1, block - 1, block + 1, 3 * block + 5, tail_max, tail_max + 1, capacity];
        sizes.retain(|&n| n <= capacity);
        for path in [SortPath::Single, SortPath::Tail, SortPath::Blocks, SortPath::Lanes] {
            sort.path = path;
            for &n in &sizes {
                if path == SortPath::Single && n > 20 * block {
                    continue; // one workgroup: slow on lavapipe past a few blocks
                }
                let keys: Vec<u32> = (0..n).map(|_| rng.next_u32() & 0xff0f_f0ff).collect();
                let what = format!("{} x {} items, {path:?}", shape.workgroup, shape.items);
                check(&mut sort, keys, &what);
            }
        }
    }
    // A shape the device cannot run is refused, not run.
    let too_big = SortShape { workgroup: 32, items: 4096, subgroups: 32 / lanes, block: 32 * 4096 };
    assert!(RadixSort::with_shape(&ctx, 1000, SortCount::Host, too_big).is_err());
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_count_only_on_the_device_sorts_by_every_path() {
    // The optimizer's large-class stage sorts a count its passes wrote on the
    // device: every dispatch is sized there (indirect), for each path.
    let ctx = common::gpu_context();
    let mut count = Buffer::new(&ctx, 16, Location::Upload, "test-count").unwrap();
    // SAFETY: `count` outlives the sort (declared before it).
    let mut sort = RadixSort::new(&ctx, 200_000, unsafe { SortCount::device(&count) }).unwrap();
    let block = sort.shape().block;
    let mut rng = Stream::new(derive(12, 12));
    for path in [SortPath::Auto, SortPath::Tail, SortPath::Blocks, SortPath::Lanes] {
        sort.path = path;
        for n in [1u32, block + 1, 3 * fsot::vk::sort::LANE_RUN + 1, 99_999, 200_000] {
            let keys: Vec<u32> = (0..n).map(|_| rng.next_u32() & 0xff0f_f0ff).collect();
            let vals: Vec<u32> = (0..n).map(|i| i ^ 0x5555).collect();
            let (gk, gv) = common::sort_with_device_count(&ctx, &mut sort, &mut count, &keys, &vals);
            let (ck, cv) = cpu_sort(&keys, &vals);
            assert!(gk == ck && gv == cv, "{path:?}, device count {n}: differs from the CPU's stable sort");
        }
    }
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn the_lanes_path_reads_its_input_as_storage_where_texel_views_cannot_hold_it() {
    // The lanes path reads through texel views; a sort larger than the device's
    // maxTexelBufferElements reads the same pairs as storage instead.
    let ctx = common::gpu_context();
    let mut rng = Stream::new(derive(13, 13));
    let mut sort = RadixSort::with_storage_reads(&ctx, 100_000, SortCount::Host).unwrap();
    sort.path = SortPath::Lanes;
    for n in [1usize, 4097, 100_000] {
        let keys: Vec<u32> = (0..n).map(|_| rng.next_u32() & 0xff0f_f0ff).collect();
        check(&mut sort, keys, "lanes path, storage reads");
    }
    let mut count = Buffer::new(&ctx, 16, Location::Upload, "test-count").unwrap();
    // SAFETY: `count` outlives the sort (declared before it).
    let mut sort =
        RadixSort::with_storage_reads(&ctx, 100_000, unsafe { SortCount::device(&count) }).unwrap();
    sort.path = SortPath::Lanes;
    let keys: Vec<u32> = (0..99_999).map(|_| rng.next_u32()).collect();
    let vals: Vec<u32> = (0..99_999).collect();
    let (gk, gv) = common::sort_with_device_count(&ctx, &mut sort, &mut count, &keys, &vals);
    assert!((gk, gv) == cpu_sort(&keys, &vals), "lanes path, storage reads, device count");
    common::assert_no_validation_messages(&ctx);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_known_count_past_the_capacity_sorts_the_capacity_and_a_sort_never_counted_sorts_nothing() {
    let ctx = common::gpu_context();
    let n = 5000u32;
    let mut rng = Stream::new(derive(77, 1));
    let keys: Vec<u32> = (0..n).map(|_| rng.next_u32()).collect();
    let vals: Vec<u32> = (0..n).collect();
    // The look-back path takes the same checks in its own binary, where
    // lavapipe runs one thread (crates/fsot-cli/tests/gpu_sort_look_back.rs).
    for path in [SortPath::Auto, SortPath::Blocks] {
        // Never given a count: the host's count starts at 0, so nothing moves.
        let mut sort = RadixSort::new(&ctx, n, SortCount::Host).unwrap();
        sort.path = path;
        sort.upload_pairs(&keys, &vals).unwrap();
        // SAFETY: the sort outlives this submission, which is waited for.
        ctx.submit(|cmd| unsafe { sort.record(cmd, 32, None) }).unwrap();
        assert_eq!(sort.keys().download::<u32>(n as usize).unwrap(), keys, "{path:?}: a sort of 0 pairs");
        // A known count past the capacity sorts the capacity (the passes are
        // sized by the buffers, not past them).
        sort.set_count(n).unwrap();
        // SAFETY: as above.
        ctx.submit(|cmd| unsafe { sort.record(cmd, 32, Some(u32::MAX)) }).unwrap();
        let (ck, cv) = cpu_sort(&keys, &vals);
        assert_eq!(sort.keys().download::<u32>(n as usize).unwrap(), ck, "{path:?}");
        assert_eq!(sort.vals().download::<u32>(n as usize).unwrap(), cv, "{path:?}");
    }
    common::assert_no_validation_messages(&ctx);
}
