//! `fsot bench`: the benchmark suites and the single-kernel measurements.

use serde::Serialize;
use serde_json::json;

use crate::*;
use fsot::vk::{Context, SortPath};
use fsot_cli::bench::convergence::Point;

/// The most pairs (or contributions) a kernel benchmark takes: 2^28, 2 GiB of
/// pairs of 32-bit keys and payloads, eight times the most the benchmarks measure
/// (2^25).
const MAX_BENCH_N: u32 = 1 << 28;
/// The most timed runs of a kernel benchmark (their timestamps fill one query
/// pool).
const MAX_REPEATS: u32 = 10_000;

pub(crate) fn bench_command(args: BenchArgs) -> Result<()> {
    if args.suite.is_some() && (args.quick || args.json.is_some() || args.out.is_some()) {
        return Err(Error::invalid(
            "--quick, --json and --out are for the whole suite (fsot bench without a suite named)",
        ));
    }
    match args.suite {
        None => bench_suites(&args),
        Some(BenchSuite::ScalingOne { size, dims, spp, iterations }) => {
            use fsot_cli::bench::scaling::{format_line, measure, peak_resident_bytes};
            let (w, h, t) = Tile::parse_size(&size)?;
            let (slices, seconds) = measure(Tile::new(w, h, t, spp, dims)?, iterations)?;
            outln!("{}", format_line(slices, seconds, peak_resident_bytes().unwrap_or(0)))?;
            Ok(())
        }
        Some(
            BenchSuite::Sort(KernelBench { n, repeats, .. })
            | BenchSuite::Scatter(KernelBench { n, repeats, .. }),
        ) if !(1..=MAX_BENCH_N).contains(&n) || !(1..=MAX_REPEATS).contains(&repeats) => Err(Error::invalid(
            format!("--n must be 1 to {MAX_BENCH_N} and --repeats 1 to {MAX_REPEATS}, got {n} and {repeats}"),
        )),
        Some(BenchSuite::Sort(KernelBench { n, repeats, device })) => {
            let ctx = super::env::context(device)?;
            let b = fsot_cli::bench::bench_sort(&ctx, n, repeats, SortPath::Auto)?;
            outln!(
                "sort {} pairs (32-bit keys + 32-bit payloads): vulkan {:.3} ms = {:.3} G pairs/s on {}; cpu {:.3} ms = {:.3} G pairs/s ({} threads, rayon stable sort)",
                b.n,
                b.gpu_seconds * 1e3,
                b.gpu_pairs_per_second() * 1e-9,
                b.device,
                b.cpu_seconds * 1e3,
                b.cpu_pairs_per_second() * 1e-9,
                b.cpu_threads
            )?;
            outln!("  {}", bandwidth_line(&b))?;
            outln!("  passes: {} ({} dispatches)", b.passes, b.dispatches)?;
            // The other paths on the same pairs, for comparison: on a CPU
            // implementation (the lanes path by default) the workgroups' blocks;
            // elsewhere the other small-sort path.
            let tail_max = fsot::vk::sort::TAIL_MAX_BLOCKS * b.block;
            let other = match b.dispatches {
                _ if b.lanes && n <= tail_max => Some(SortPath::Tail),
                _ if b.lanes => Some(SortPath::Blocks),
                16 if n <= tail_max => Some(SortPath::Tail),
                16 => None,
                _ => Some(SortPath::Blocks),
            };
            // The decoupled look-back path, only on GPUs known to let a
            // workgroup run while another waits on it.
            let look_back = ctx.info().keeps_workgroups_running().then_some(SortPath::LookBack);
            for path in other.into_iter().chain(look_back) {
                let o = fsot_cli::bench::bench_sort(&ctx, n, repeats, path)?;
                outln!(
                    "  {} on the same pairs ({} dispatches): {:.3} ms = {:.3} G pairs/s",
                    o.passes,
                    o.dispatches,
                    o.gpu_seconds * 1e3,
                    o.gpu_pairs_per_second() * 1e-9
                )?;
            }
            let unit = match b.lanes {
                true => format!("{}-pair runs", fsot::vk::sort::LANE_RUN),
                false => format!("{}-pair blocks", b.block),
            };
            outln!(
                "  one profiled sort ({unit}), 4 passes: histogram {:.3} ms, scan {:.3} ms, scatter {:.3} ms",
                b.stages_ms[0],
                b.stages_ms[1],
                b.stages_ms[2]
            )?;
            Ok(())
        }
        Some(BenchSuite::Scatter(KernelBench { n, repeats, device })) => {
            let ctx = super::env::context(device)?;
            let b = fsot_cli::bench::bench_scatter(&ctx, n, repeats)?;
            outln!("{}", scatter_line(&b))?;
            Ok(())
        }
    }
}

/// A sort's bytes moved against the copy bandwidth measured in the same run.
pub(crate) fn bandwidth_line(b: &fsot_cli::bench::SortBench) -> String {
    format!(
        "bytes moved: {:.1} MB (4 passes x 16 bytes per pair) at {:.1} GB/s; a copy of the pairs in the same run: {:.1} GB/s; the sort at {:.0}% of the copy's bandwidth",
        b.bytes_moved() * 1e-6,
        b.sort_bandwidth() * 1e-9,
        b.copy_bandwidth() * 1e-9,
        100.0 * b.sort_bandwidth() / b.copy_bandwidth()
    )
}

/// One scatter measurement in words.
pub(crate) fn scatter_line(b: &fsot_cli::bench::ScatterBench) -> String {
    let rate = |s: f64| b.n as f64 / s * 1e-9;
    let float = match (b.float_seconds, b.float_error) {
        (Some(s), Some(e)) => {
            format!("float atomics {:.3} ms = {:.3} G adds/s (max error {e:.1e}); ", s * 1e3, rate(s))
        }
        _ => "no float atomics; ".to_string(),
    };
    format!(
        "scatter {} contributions into {} accumulators on {}: fixed point {:.3} ms = {:.3} G adds/s (max error {:.1e}); {float}cpu {:.3} ms = {:.3} G adds/s ({} threads)",
        b.n,
        b.targets,
        b.device,
        b.fixed_seconds * 1e3,
        rate(b.fixed_seconds),
        b.fixed_error,
        b.cpu_seconds * 1e3,
        rate(b.cpu_seconds),
        b.cpu_threads
    )
}

/// The convergence and time-to-quality suites, CPU path against Vulkan, then the
/// scaling, sort and scatter suites; Markdown, CSV, a plot and JSON records.
pub(crate) fn bench_suites(args: &BenchArgs) -> Result<()> {
    let out = args.out_dir();
    fsot::io::atomic::make_folder(out)?;
    let md = AtomicFile::create(&out.join("convergence.md"))?;
    let csv = AtomicFile::create(&out.join("convergence.csv"))?;
    let plot = AtomicFile::create(&out.join("convergence.png"))?;
    let json = args.json.as_ref().map(|p| AtomicFile::create(p)).transpose()?;
    let mut records: Vec<serde_json::Value> = Vec::new();
    let (points, mut table) = convergence_suite(args)?;
    let mut rows = format!("{}\n", Point::CSV_HEADER);
    for p in &points {
        rows += &format!("{}\n", p.csv_row());
        let mut record = serde_json::to_value(p).map_err(json_error)?;
        record["suite"] = json!("convergence");
        records.push(record);
    }
    table += &scaling_suite(args.quick, &mut records)?;
    match super::env::context(None) {
        Ok(ctx) => table += &kernel_suites(&ctx, args.quick, &mut records)?,
        Err(e) => table += &format!("\nSort and scatter suites not run: no Vulkan device ({e}).\n"),
    }
    plot.commit(&fsot_cli::bench::plot::line_plot(&plot_series(&points), 640, 400)?)?;
    md.commit(table.as_bytes())?;
    csv.commit(rows.as_bytes())?;
    if let Some(j) = json {
        let mut text = serde_json::to_string_pretty(&records).map_err(json_error)?;
        text.push('\n');
        j.commit(text.as_bytes())?;
    }
    outln!("{table}")?;
    Ok(())
}

fn json_error(e: serde_json::Error) -> Error {
    Error::invalid(format!("cannot write the JSON records: {e}"))
}

/// Convergence of each backend on the same problem, and time to quality.
fn convergence_suite(args: &BenchArgs) -> Result<(Vec<Point>, String)> {
    use fsot_cli::bench::convergence::{convergence, SceneJudge, WARM_UP_ITERATIONS};
    let (tile, kernel, checkpoints): (Tile, &str, Vec<u32>) = if args.quick {
        (Tile::new(32, 32, 16, 1, 2)?, "taa", vec![2, 4, 8, 16, 32, 64, 128, 192])
    } else {
        (Tile::new(64, 64, 16, 1, 2)?, "perceptual-taa", vec![2, 5, 10, 20, 50, 100, 200, 500, 1000])
    };
    let spec = KernelSpec::from_name(kernel, DEFAULT_SIGMA, None, DEFAULT_ALPHA, DEFAULT_FPS)?;
    let seed = 7;
    eprintln!(
        "scene judge: soft shadow, 64 x 64, 80 frames, TAA (reference cached in {})",
        args.out_dir().display()
    );
    let judge = SceneJudge::new(tile, Some(&args.out_dir().join("cache")))?;
    let base = RunOptions::default().device(super::env::device(None)).validation(super::env::validation());
    let mut points = Vec::new();
    let mut notes = Vec::new();
    for choice in [BackendChoice::Cpu, BackendChoice::Vulkan] {
        match convergence(choice, &base, tile, spec, seed, &checkpoints, &judge) {
            Ok(p) => {
                eprintln!("{} on {}: {} checkpoints", p[0].backend, p[0].machine, p.len());
                points.extend(p);
            }
            Err(e) if choice == BackendChoice::Vulkan => notes.push(format!("vulkan not measured: {e}")),
            Err(e) => return Err(e),
        }
    }
    let mut table = format!(
        "# fsot bench{}\n\nfsot {} (commit {}) on {}.\n\nProblem: {}, kernel {}, seed {seed}; checkpoints of one run per backend (schedule \
         planned for the last). Objective: `fsot score` / white noise. pRelMSE: soft-shadow scene, 64 x 64, TAA, \
         eye sigma 2.1, / white noise. Seconds: optimisation only, host wall time, after an untimed \
         warm-up run of {WARM_UP_ITERATIONS} iterations per backend (one-time costs such as llvmpipe's shader \
         compilation); GPU s: the GPU's own time from timestamp queries (Vulkan).\n\n\
         | backend | machine | iteration | seconds | GPU s | objective | pRelMSE | perceived |\n\
         | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n",
        if args.quick { " --quick" } else { "" },
        env!("CARGO_PKG_VERSION"),
        env!("FSOT_COMMIT"),
        fsot_cli::bench::machine::cpu_description(),
        tile.describe(),
        spec.describe()
    );
    for p in &points {
        table += &format!("{}\n", p.markdown_row());
    }
    table += &time_to_quality(&points);
    for n in &notes {
        table += &format!("\n{n}\n");
    }
    table +=
        "\nPlot (convergence.png): x seconds (log), y ratio to white noise; blue CPU objective, orange CPU \
              pRelMSE, green Vulkan objective, red Vulkan pRelMSE.\n";
    Ok((points, table))
}

/// The backends that have points, in order.
fn backends(points: &[Point]) -> Vec<String> {
    let mut b: Vec<String> = points.iter().map(|p| p.backend.clone()).collect();
    b.dedup();
    b
}

/// Seconds to quality levels per backend (Vulkan twice: host wall time, then the
/// GPU's own time from timestamps).
fn time_to_quality(points: &[Point]) -> String {
    use fsot_cli::bench::convergence::time_to;
    let mut table = String::from(
        "\n## Time to quality (seconds; - where not reached)\n\n\
                  | backend | objective 0.8 | 0.6 | 0.5 | pRelMSE 0.6 | 0.4 | 0.3 | perceived 0.65 | 0.55 |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    let backends = backends(points);
    let mut rows_by: Vec<(String, Vec<Point>)> = Vec::new();
    for b in &backends {
        let mine: Vec<_> = points.iter().filter(|p| &p.backend == b).cloned().collect();
        if mine.iter().all(|p| p.gpu_seconds.is_some()) {
            let gpu_time = mine
                .iter()
                .map(|p| Point { seconds: p.gpu_seconds.unwrap_or(p.seconds), ..p.clone() })
                .collect();
            rows_by.push((b.clone(), mine));
            rows_by.push((format!("{b}, GPU time"), gpu_time));
        } else {
            rows_by.push((b.clone(), mine));
        }
    }
    let cell = |v: Option<f64>| v.map(|s| format!("{s:.4}")).unwrap_or_else(|| "-".into());
    for (b, mine) in &rows_by {
        let obj: Vec<String> =
            [0.8, 0.6, 0.5].iter().map(|&l| cell(time_to(mine, l, |p| p.objective_ratio))).collect();
        let pr: Vec<String> =
            [0.6, 0.4, 0.3].iter().map(|&l| cell(time_to(mine, l, |p| p.prelmse_ratio))).collect();
        let pe: Vec<String> =
            [0.65, 0.55].iter().map(|&l| cell(time_to(mine, l, |p| p.perceived_ratio))).collect();
        table += &format!("| {b} | {} | {} | {} |\n", obj.join(" | "), pr.join(" | "), pe.join(" | "));
    }
    let total = |b: &str| points.iter().filter(|p| p.backend == b).map(|p| p.seconds).fold(0.0, f64::max);
    if backends.len() == 2 {
        table += &format!(
            "\nVulkan / CPU, seconds to the last checkpoint, this run: {:.2}\n",
            total("vulkan") / total("cpu").max(1e-9)
        );
    }
    table
}

/// The plot's lines: per backend, objective and pRelMSE against seconds.
fn plot_series(points: &[Point]) -> Vec<Vec<(f64, f64)>> {
    let mut series = Vec::new();
    for b in backends(points) {
        let mine: Vec<_> = points.iter().filter(|p| p.backend == b && p.seconds > 0.0).collect();
        series.push(mine.iter().map(|p| (p.seconds, p.objective_ratio)).collect());
        series.push(mine.iter().map(|p| (p.seconds, p.prelmse_ratio)).collect());
    }
    series
}

/// A scaling record.
#[derive(Serialize)]
struct ScalingRecord {
    suite: &'static str,
    tile: String,
    slices: u32,
    seconds_per_iteration: f64,
    peak_bytes: u64,
}

/// Scaling: each configuration in a child process (its peak memory its own).
fn scaling_suite(quick: bool, records: &mut Vec<serde_json::Value>) -> Result<String> {
    let configs: Vec<(usize, usize, usize, usize, usize)> = if quick {
        vec![(32, 32, 8, 2, 1), (64, 64, 16, 2, 1), (32, 32, 8, 1, 1), (32, 32, 8, 8, 1), (32, 32, 8, 2, 4)]
    } else {
        let mut c = vec![(32, 32, 8, 2, 1), (64, 64, 16, 2, 1), (128, 128, 32, 2, 1), (256, 256, 64, 2, 1)];
        c.extend((1..=8).filter(|&d| d != 2).map(|d| (64, 64, 16, d, 1)));
        c.extend([2, 4, 8, 16].iter().map(|&spp| (32, 32, 8, 2, spp)));
        c
    };
    let exe =
        std::env::current_exe().map_err(|e| Error::invalid(format!("cannot find this program: {e}")))?;
    let mut table = format!(
        "\n## Scaling (CPU path, {}; perceptual-taa, time per iteration and the child process's peak memory)\n\n\
         | tile | slices per iteration | ms per iteration | peak memory (MiB) |\n| --- | ---: | ---: | ---: |\n",
        fsot_cli::bench::machine::cpu_description()
    );
    for (w, h, t, d, spp) in configs {
        let tile = Tile::new(w, h, t, spp, d)?;
        let iterations = if tile.values() > 1 << 22 { "3" } else { "10" };
        let out = std::process::Command::new(&exe)
            .args(["bench", "scaling-one", "--size", &format!("{w}x{h}x{t}"), "--dims", &d.to_string()])
            .args(["--spp", &spp.to_string(), "--iterations", iterations])
            .output()
            .map_err(|e| Error::invalid(format!("cannot run the scaling child: {e}")))?;
        if !out.status.success() {
            return Err(Error::invalid(format!(
                "scaling child failed: {}",
                String::from_utf8_lossy(&out.stderr)
            )));
        }
        let scale = fsot_cli::bench::scaling::parse_line(tile, &String::from_utf8_lossy(&out.stdout))?;
        eprintln!("scaling {}: {:.2} ms per iteration", tile.describe(), scale.seconds_per_iteration * 1e3);
        table += &format!(
            "| {} | {} | {:.2} | {:.1} |\n",
            tile.describe(),
            scale.slices,
            scale.seconds_per_iteration * 1e3,
            scale.peak_bytes as f64 / 1048576.0
        );
        let record = ScalingRecord {
            suite: "scaling",
            tile: tile.describe(),
            slices: scale.slices,
            seconds_per_iteration: scale.seconds_per_iteration,
            peak_bytes: scale.peak_bytes,
        };
        records.push(serde_json::to_value(record).map_err(json_error)?);
    }
    Ok(table)
}

/// The GPU radix sort against the CPU sort, and the gradient scatter, against size.
fn kernel_suites(ctx: &Context, quick: bool, records: &mut Vec<serde_json::Value>) -> Result<String> {
    let sizes: Vec<u32> = if quick {
        vec![1 << 16, 1 << 18, 1 << 20]
    } else {
        (16..=24).step_by(2).map(|k| 1u32 << k).collect()
    };
    let repeats = if quick { 3 } else { 5 };
    let ceiling = if ctx.info().is_cpu() {
        let b = fsot_cli::bench::machine::host_copy_bandwidth();
        format!("host memory, measured by a parallel copy: {:.1} GB/s", b * 1e-9)
    } else {
        "the device's memory bandwidth (its specification)".to_string()
    };
    let cpu = fsot_cli::bench::machine::cpu_description();
    let mut table = format!(
        "\n## Sort throughput against size ({}; ceiling: {ceiling})\n\n\
         Effective bandwidth: 4 passes, each reading and writing 8 bytes per pair.\n\n\
         | pairs | vulkan ms | vulkan G pairs/s | effective GB/s | cpu ms ({cpu}) | cpu G pairs/s |\n\
         | ---: | ---: | ---: | ---: | ---: | ---: |\n",
        ctx.info().name
    );
    for &n in &sizes {
        let b = fsot_cli::bench::bench_sort(ctx, n, repeats, SortPath::Auto)?;
        let gbs = 4.0 * 16.0 * n as f64 / b.gpu_seconds * 1e-9;
        eprintln!("sort {n}: {:.3} G pairs/s", b.gpu_pairs_per_second() * 1e-9);
        table += &format!(
            "| {n} | {:.3} | {:.3} | {gbs:.1} | {:.3} | {:.3} |\n",
            b.gpu_seconds * 1e3,
            b.gpu_pairs_per_second() * 1e-9,
            b.cpu_seconds * 1e3,
            b.cpu_pairs_per_second() * 1e-9
        );
        records.push(json!({"suite": "sort", "device": b.device, "pairs": n, "gpu_seconds": b.gpu_seconds, "cpu_seconds": b.cpu_seconds}));
    }
    table += &format!(
        "\n## Scatter throughput against size ({}; ceiling as above)\n\n\
         N contributions at random into N/16 accumulators, as the optimizer's gradient scatter. \
         Effective bandwidth: the least bytes a scatter moves (index and value read, \
         each 8-byte accumulator read and written once) over the time.\n\n\
         | contributions | fixed point ms | G adds/s | effective GB/s | float atomics ms | G adds/s | cpu ms ({cpu}) | cpu G adds/s |\n\
         | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
        ctx.info().name
    );
    for &n in &sizes {
        let b = fsot_cli::bench::bench_scatter(ctx, n, repeats)?;
        eprintln!("{}", scatter_line(&b));
        let rate = |s: f64| n as f64 / s * 1e-9;
        let (float_ms, float_rate) = match b.float_seconds {
            Some(s) => (format!("{:.3}", s * 1e3), format!("{:.3}", rate(s))),
            None => ("-".to_string(), "-".to_string()),
        };
        table += &format!(
            "| {n} | {:.3} | {:.3} | {:.1} | {float_ms} | {float_rate} | {:.3} | {:.3} |\n",
            b.fixed_seconds * 1e3,
            rate(b.fixed_seconds),
            b.bytes() / b.fixed_seconds * 1e-9,
            b.cpu_seconds * 1e3,
            rate(b.cpu_seconds)
        );
        records.push(json!({"suite": "scatter", "device": b.device, "contributions": n, "fixed_seconds": b.fixed_seconds, "float_seconds": b.float_seconds, "cpu_seconds": b.cpu_seconds}));
    }
    Ok(table)
}
