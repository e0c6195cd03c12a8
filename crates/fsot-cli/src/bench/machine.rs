//! The machine a figure was measured on, in words: every benchmark names it.

/// CPU model (from /proc/cpuinfo where there is one) and the threads used.
pub fn cpu_description() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| {
            text.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    format!("{model}, {cores} cores, {} threads", rayon::current_num_threads())
}

/// Host memory bandwidth, bytes per second: the best of a few copies of a
/// 128 MiB buffer (read + write counted), all threads. The ceiling for a CPU
/// implementation of Vulkan such as lavapipe.
pub fn host_copy_bandwidth() -> f64 {
    use rayon::prelude::*;
    let n = 1 << 25; // 32 Mi u32 = 128 MiB
    let src: Vec<u32> = (0..n as u32).collect();
    let mut dst = vec![0u32; n];
    let mut best = f64::MAX;
    for _ in 0..4 {
        let start = std::time::Instant::now();
        dst.par_chunks_mut(1 << 16).zip(src.par_chunks(1 << 16)).for_each(|(d, s)| d.copy_from_slice(s));
        best = best.min(start.elapsed().as_secs_f64());
    }
    std::hint::black_box(&dst);
    2.0 * (n * 4) as f64 / best
}
