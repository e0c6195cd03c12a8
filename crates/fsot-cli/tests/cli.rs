//! The command line: a working run, and clear errors (non-zero exit, a message, no
//! panic) for bad flags and bad files, without touching existing outputs.

#[path = "../../../tests/common/mod.rs"]
mod common;

use std::path::Path;
use std::process::{Command, Output};

fn fsot(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fsot")).args(args).current_dir(dir).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_ktx2_mask_is_read_wherever_a_mask_file_is_taken() {
    // A float KTX2 holds the values exactly: it scores as its EXR twin does, and
    // a run started from it is the run started from the EXR, bit for bit.
    let dir = tempfile::tempdir().unwrap();
    let make = ["optimize", "--backend", "cpu", "--size", "8x8x4", "--iterations", "10", "--seed", "3"];
    let o = fsot(
        &[&make[..], &["--out", "m.ktx2", "--ktx2-format", "r32g32_sfloat", "--also", "m.exr"]].concat(),
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let score = |file: &str| {
        let s = fsot(&["score", file], dir.path());
        assert!(s.status.success(), "{}", stderr(&s));
        String::from_utf8_lossy(&s.stdout).split(": objective").nth(1).unwrap().to_string()
    };
    assert_eq!(score("m.ktx2"), score("m.exr"));
    for init in ["m.ktx2", "m.exr"] {
        let out = format!("from-{init}.exr");
        let o = fsot(&[&make[..], &["--init", init, "--out", &out]].concat(), dir.path());
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let read = |f: &str| std::fs::read(dir.path().join(f)).unwrap();
    assert_eq!(
        fsot::Mask::open(dir.path().join("from-m.ktx2.exr")).unwrap(),
        fsot::Mask::open(dir.path().join("from-m.exr.exr")).unwrap()
    );
    // An 8-bit one reads as its levels; a truncated one is refused by name.
    let o = fsot(&[&make[..], &["--out", "m8.ktx2", "--ktx2-format", "r8g8_unorm"]].concat(), dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let s = fsot(&["score", "m8.ktx2"], dir.path());
    assert!(s.status.success(), "{}", stderr(&s));
    let bytes = read("m8.ktx2");
    std::fs::write(dir.path().join("cut.ktx2"), &bytes[..bytes.len() / 2]).unwrap();
    let s = fsot(&["score", "cut.ktx2"], dir.path());
    assert!(
        !s.status.success() && stderr(&s).contains("cut.ktx2") && stderr(&s).contains("KTX2"),
        "{}",
        stderr(&s)
    );
}

#[test]
fn the_version_names_the_commit_built_for_a_bug_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = fsot(&["--version"], dir.path());
    assert!(out.status.success(), "{}", stderr(&out));
    let said = String::from_utf8_lossy(&out.stdout);
    let commit = env!("FSOT_COMMIT");
    assert_eq!(said.trim_end(), format!("fsot {} ({commit})", env!("CARGO_PKG_VERSION")));
    assert!(commit == "unknown" || commit.trim_end_matches("-dirty").len() >= 7, "{commit}");
}

#[test]
fn optimize_writes_exr_and_png_and_score_reads_it() {
    let dir = tempfile::tempdir().unwrap();
    let o = fsot(
        &[
            "optimize",
            "--backend",
            "cpu",
            "--size",
            "8x8x4",
            "--iterations",
            "20",
            "--kernel",
            "taa",
            "--seed",
            "3",
            "--out",
            "m.exr",
            "--png",
            "slices",
        ],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("wrote m.exr") && out.contains("objective"), "{out}");
    assert!(dir.path().join("m.exr").is_file());
    assert_eq!(std::fs::read_dir(dir.path().join("slices")).unwrap().count(), 4);
    let s = fsot(&["score", "m.exr", "--kernel", "taa"], dir.path());
    assert!(s.status.success(), "{}", stderr(&s));
    let asked = String::from_utf8_lossy(&s.stdout).into_owned();
    assert!(asked.contains("ratio") && asked.contains("(as asked)"), "{asked}");
    // Without a kernel flag: the kernel recorded in the mask, the same figures here.
    let s = fsot(&["score", "m.exr"], dir.path());
    assert!(s.status.success(), "{}", stderr(&s));
    let recorded = String::from_utf8_lossy(&s.stdout).into_owned();
    assert!(recorded.contains("kernel taa (ppd = 37.84, alpha = 0.1) (recorded in the mask)"), "{recorded}");
    assert_eq!(recorded.split(": objective").nth(1), asked.split(": objective").nth(1));
    // A kernel flag the kernel has no use for is refused, as by optimize.
    for (flags, says) in [
        (&["--kernel", "taa", "--fps", "30"][..], "--kernel taa has none"),
        (&["--kernel", "perceptual", "--sigma-t", "3"][..], "--kernel perceptual has none"),
        (&["--alpha", "0.2", "--sigma-t", "3"][..], "--kernel perceptual-taa has none"),
    ] {
        let s = fsot(&[&["score", "m.exr"][..], flags].concat(), dir.path());
        assert!(!s.status.success() && stderr(&s).contains(says), "{flags:?}: {}", stderr(&s));
    }
    // --init continues from the file, taking its shape.
    let c = fsot(
        &[
            "optimize",
            "--backend",
            "cpu",
            "--init",
            "m.exr",
            "--iterations",
            "5",
            "--kernel",
            "taa",
            "--out",
            "m2.exr",
        ],
        dir.path(),
    );
    assert!(c.status.success(), "{}", stderr(&c));
    let continued = String::from_utf8_lossy(&c.stdout).into_owned();
    assert!(continued.contains("8x8x4"), "{continued}");
    // The report's objectives are the start's and the result's on `fsot score`'s
    // slices: here the start is m.exr, scored above.
    let scored =
        |text: &str| text.split(": objective ").nth(1).unwrap().split(' ').next().unwrap().to_string();
    assert_eq!(report(&continued).0, scored(&asked), "{continued}");
    assert_eq!(report(&out).1, scored(&asked), "{out}");
}

/// The objectives `fsot optimize` reports: (start, result, result x white noise).
fn report(stdout: &str) -> (String, String, f64) {
    let line = stdout.lines().find(|l| l.contains("x white noise")).expect(stdout);
    let figures = line.split("; objective ").nth(1).unwrap();
    let (start, rest) = figures.split_once(" -> ").unwrap();
    let (result, rest) = rest.split_once(" (").unwrap();
    let ratio = rest.split(' ').next().unwrap().parse().unwrap();
    (start.to_string(), result.to_string(), ratio)
}

#[test]
fn a_budgeted_run_reports_the_objective_of_its_animated_start_not_of_white_noise() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["optimize", "--backend", "cpu", "--size", "16x16x8", "--kernel", "taa", "--budget", "0.3s"];
    let o = fsot(&[&args[..], &["--out", "m.exr"]].concat(), dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    let (start, result, ratio) = report(&out);
    let (start, result): (f64, f64) = (start.parse().unwrap(), result.parse().unwrap());
    // White noise's objective is the result's divided by its ratio; one frame
    // optimized and set in motion starts well below it.
    let white = result / ratio;
    assert!(start < 0.7 * white, "start {start}, white noise {white}: {out}");
}

#[test]
fn a_budgeted_run_that_its_iteration_cap_ends_first_says_so() {
    // A minute that 20 iterations of a small tile cannot fill.
    let dir = tempfile::tempdir().unwrap();
    let args = ["optimize", "--backend", "cpu", "--size", "8x8x4", "--budget", "60s", "--iterations", "20"];
    let o = fsot(&[&args[..], &["--out", "m.exr"]].concat(), dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(out.contains("the run ended at its cap of 20 iterations (--iterations)"), "{out}");
}

#[cfg(unix)]
#[test]
fn an_output_that_links_to_the_checkpoint_is_refused_and_the_checkpoint_kept() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("st.ckpt"), b"a run's state").unwrap();
    std::os::unix::fs::symlink("st.ckpt", dir.path().join("lk.exr")).unwrap();
    let o = fsot(
        &["optimize", "--size", "4x4x2", "--iterations", "3", "--checkpoint", "st.ckpt", "--out", "lk.exr"],
        dir.path(),
    );
    assert!(!o.status.success() && stderr(&o).contains("is also an output"), "{}", stderr(&o));
    assert_eq!(std::fs::read(dir.path().join("st.ckpt")).unwrap(), b"a run's state");
}

#[test]
fn bad_input_gets_a_clear_error_and_leaves_existing_files_alone() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("existing.exr"), b"keep me").unwrap();
    std::fs::write(dir.path().join("garbage.exr"), b"not an exr at all").unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--size", "0x8x8"], "width must be at least 1"),
        (&["--size", "8x8"], ""), // valid: one frame (checked below to succeed)
        (&["--size", "99999999x99999999x9999"], "more than"),
        (&["--size", "4096x4096x16", "--dims", "8"], "more than 268435456 values"),
        (&["--size", "axb"], "size must look like"),
        (&["--dims", "0"], "dimensions per sample"),
        (&["--dims", "9"], "dimensions per sample"),
        (&["--spp", "0"], "samples per pixel"),
        (&["--kernel", "box"], "invalid value 'box'"),
        (&["--kernel", "taa", "--alpha", "1.5"], "alpha"),
        (&["--kernel", "taa", "--alpha", "NaN"], "alpha"),
        (&["--alpha", "5e-324"], "alpha (TAA blend weight) must be in [0.0001, 1]"),
        (&["--sigma", "-2"], "sigma"),
        (&["--sigma", "1e-200"], "sigma must be in [0.01, 64]"),
        (&["--kernel", "gaussian", "--sigma-t", "1e-200"], "temporal sigma must be in [0.01, 64]"),
        (&["--kernel", "taa", "--sigma-t", "2"], "--sigma-t sets the gaussian kernel's temporal width"),
        (&["--kernel", "spatial", "--alpha", "0.2"], "--kernel spatial has none"),
        (&["--kernel", "taa", "--fps", "30"], "--kernel taa has none"),
        (&["--png-bits", "8"], "--png"),
        (&["--kernel", "gaussian", "--sigma-t", "NaN"], "temporal sigma"),
        (&["--fps", "0"], "fps"),
        (&["--iterations", "0"], "iterations"),
        (&["--iterations", "-3"], "invalid value"),
        (&["--slices", "0"], "slices"),
        (&["--slices", "4294967295"], "slices per iteration must be 1 to 16777216"),
        (&["--axis-share", "1.5"], "--axis-share must be between 0 and 1"),
        (&["--axis-share", "NaN"], "--axis-share must be between 0 and 1"),
        (&["--axis-share", "0.5", "--method", "stbn"], "are for --method fsot"),
        (&["--threads", "0"], "threads"),
        (&["--threads", "100000"], "--threads must be 1 to 1024"),
        (&["--init", "existing.exr", "--start", "white"], "give one"),
        (&["--out", "m.png"], "cannot tell the format of m.png"),
        (&["--ktx2-format", "r8_unorm", "--also", "m.h"], "neither --out nor --also names a .ktx2 file"),
        (&["--out", "m"], "cannot tell the format of m"),
        (&["--out", "."], ". is a folder: name a mask file in it"),
        (&["--init", "missing.exr"], "cannot read"),
        (&["--init", "garbage.exr"], "not a readable EXR"),
        (&["--out", "no/such/folder/m.exr"], "does not exist"),
        (&["--backend", "vulkan", "--device", "no-such-gpu"], "no device matches"),
        (&["--until", "sometimes"], "--until must be"),
        (&["--until", "objective:-1"], "--until must be"),
        (&["--budget", "soon"], "--budget must be a time"),
        (&["--budget", "0s"], "--budget must be a time"),
        (&["--budget", "1e-300s"], "--budget must be at least 0.001 s"),
        (&["--budget", "-1"], "--budget must be a time"),
        (&["--budget", "1e9"], "at most 86400 seconds"),
        (&["--budget", "1s", "--until", "plateau"], "cannot be used with"),
        (&["--budget", "1s", "--checkpoint", "c.ckpt"], "takes no checkpoints"),
        (&["--start", "coarse"], "a coarse start divides a time budget"),
        (&["--start", "coarse", "--budget", "1s"], "even and at least 32"),
        (&["--png", "existing.exr"], "--png existing.exr is also the output existing.exr"),
        (&["--also", "m.ktx2", "--png", "./m.ktx2"], "is also the output m.ktx2"),
    ];
    for (extra, expect) in cases {
        // Small defaults, each replaced when the case gives that flag itself.
        let mut args = vec!["optimize"];
        for (flag, value) in [("--size", "4x4x2"), ("--iterations", "3"), ("--out", "existing.exr")] {
            if !extra.contains(&flag) {
                args.extend_from_slice(&[flag, value]);
            }
        }
        args.extend_from_slice(extra);
        let o = fsot(&args, dir.path());
        let err = stderr(&o);
        assert!(!err.contains("panicked"), "{extra:?} panicked: {err}");
        if expect.is_empty() {
            assert!(o.status.success(), "{extra:?}: {err}");
            std::fs::write(dir.path().join("existing.exr"), b"keep me").unwrap();
            continue;
        }
        assert!(!o.status.success(), "{extra:?} should fail");
        assert!(err.contains(expect), "{extra:?}: expected {expect:?} in {err:?}");
        assert_eq!(std::fs::read(dir.path().join("existing.exr")).unwrap(), b"keep me", "{extra:?}");
    }
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    let s = fsot(&["score", "garbage.exr"], dir.path());
    assert!(!s.status.success() && stderr(&s).contains("not a readable EXR"));
}

#[test]
fn every_flag_has_help() {
    let dir = tempfile::tempdir().unwrap();
    let o = fsot(&["optimize", "--help"], dir.path());
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = help.lines().collect();
    for flag in [
        "--size",
        "--dims",
        "--spp",
        "--kernel",
        "--sigma",
        "--sigma-t",
        "--alpha",
        "--fps",
        "--iterations",
        "--slices",
        "--axis-share",
        "--seed",
        "--backend",
        "--threads",
        "--init",
        "--out",
        "--png",
    ] {
        let i = lines
            .iter()
            .position(|l| l.trim_start().starts_with(&format!("{flag} <")))
            .unwrap_or_else(|| panic!("{flag} missing from --help"));
        assert!(!lines[i + 1].trim().is_empty(), "{flag} has no description");
    }
    // A default the help states in words is the library's.
    let flat = help.split_whitespace().collect::<Vec<_>>().join(" ");
    let share = format!("[default: {}]", fsot::core::slice::DEFAULT_AXIS_SHARE);
    let from = flat.find("--axis-share <").expect("--axis-share in --help");
    let to = flat[from..].find("--seed <").expect("--seed after --axis-share") + from;
    assert!(flat[from..to].contains(&share), "--axis-share's help does not say {share}");
}

#[test]
fn every_method_writes_valid_masks_for_one_to_four_dimensions() {
    let dir = tempfile::tempdir().unwrap();
    for method in ["fsot", "white", "stbn", "fast"] {
        for dims in ["1", "2", "3", "4"] {
            let out = format!("{method}{dims}.exr");
            let o = fsot(
                &[
                    "optimize",
                    "--method",
                    method,
                    "--size",
                    "8x8x4",
                    "--dims",
                    dims,
                    "--iterations",
                    "5",
                    "--passes",
                    "2",
                    "--backend",
                    "cpu",
                    "--out",
                    &out,
                ],
                dir.path(),
            );
            assert!(o.status.success(), "{method} d = {dims}: {}", stderr(&o));
            let m = fsot::io::exr::read(&dir.path().join(&out)).unwrap();
            assert_eq!((m.tile.width, m.tile.height, m.tile.frames), (8, 8, 4));
            assert_eq!(m.tile.dims.to_string(), dims);
            assert_eq!(m.meta("method"), Some(method));
            assert!(
                m.samples.iter().all(|v| (0.0..1.0).contains(v)),
                "{method} d = {dims}: a value outside [0, 1)"
            );
            if method == "stbn" || method == "fast" {
                // Ranks (d = 1) or swaps of stratified values (d >= 2): every
                // dimension holds each of the 256 strata exactly once.
                let d = m.tile.dims;
                for k in 0..d {
                    let mut values: Vec<f32> = m.samples.iter().skip(k).step_by(d).copied().collect();
                    values.sort_by(|a, b| a.total_cmp(b));
                    for (r, v) in values.iter().enumerate() {
                        assert_eq!(
                            *v,
                            ((r as f64 + 0.5) / 256.0) as f32,
                            "{method} d = {dims}, dimension {k}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn swap_methods_refuse_bad_settings() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--method", "fast", "--passes", "0"], "--passes"),
        (&["--method", "stbn", "--dims", "2", "--passes", "0"], "--passes"),
        (&["--method", "fast", "--fast-spatial", "sinc:2"], "unknown filter"),
        (&["--method", "fast", "--fast-spatial", "ema:0.1:0.1"], "unknown filter"),
        (&["--method", "fast", "--fast-temporal", "ema:1.5:0.1"], "out of range"),
        (&["--method", "fast", "--fast-temporal", "gaussian:-1"], "out of range"),
        (&["--method", "fast", "--fast-combine", "sum:2"], "--fast-combine"),
        (&["--method", "fast", "--spp", "2"], "1 spp"),
        (&["--method", "stbn", "--spp", "2"], "1 spp"),
        (
            &["--method", "fast", "--fast-spatial", "none", "--fast-temporal", "none"],
            "weighs no pair of pixels",
        ),
    ];
    refused(dir.path(), &["optimize", "--size", "4x4x2", "--out", "m.exr"], cases);
}

#[test]
fn eval_refuses_counts_it_cannot_judge_keeps_the_results_already_there_and_makes_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("results.md"), b"keep me").unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--seeds", "1"], "--seeds must be in 2..=10000 (an interval needs two), got 1"),
        (&["--seeds", "10001"], "--seeds must be in 2..=10000 (an interval needs two), got 10001"),
        (&["--seeds", "-2"], "invalid value"),
        (&["--seeds", "3", "--planned-masks", "4"], "--planned-masks must be 1 (one mask judged at every placement) or the seeds, 3 (a mask per seed), got 4"),
        (&["--seeds", "4", "--planned-masks", "2"], "--planned-masks must be 1 (one mask judged at every placement) or the seeds, 4 (a mask per seed), got 2"),
        (&["--sigma", "9"], "--sigma must be in [0.01, 8], got 9"),
        (&["--sigma", "1e-200"], "--sigma must be in [0.01, 8]"),
        (&["--iterations", "0"], "--iterations must be in 1..=1000000, got 0"),
    ];
    refused(
        dir.path(),
        &["eval", "--quick", "--scenes", "light-pick", "--methods", "white", "--out", "out"],
        cases,
    );
    assert_eq!(std::fs::read(out.join("results.md")).unwrap(), b"keep me");
    // Nor does a bad flag make an output folder.
    refused(dir.path(), &["eval", "--quick", "--out", "fresh"], cases);
    refused(
        dir.path(),
        &["eval", "--quick", "--out", "fresh"],
        &[(&["--methods", "nothing"], "unknown method")],
    );
    assert!(!dir.path().join("fresh").exists(), "a refused eval made its output folder");
}

#[test]
fn kernel_benchmarks_refuse_sizes_no_machine_holds_before_they_allocate() {
    let dir = tempfile::tempdir().unwrap();
    for suite in ["sort", "scatter"] {
        let cases: &[(&[&str], &str)] = &[
            (&["--n", "0"], "--n must be 1 to 268435456"),
            (&["--n", "4294967295"], "--n must be 1 to 268435456"),
            (&["--repeats", "0"], "--repeats 1 to 10000"),
            (&["--repeats", "4294967295"], "--repeats 1 to 10000"),
        ];
        refused(dir.path(), &["bench", suite], cases);
        // The whole suite's flags are refused with one suite, not ignored.
        for flags in [&["--json", "b.json"][..], &["--out", "b"], &["--quick"]] {
            let o = fsot(&[&["bench"][..], flags, &[suite, "--n", "16"]].concat(), dir.path());
            let err = stderr(&o);
            assert!(!o.status.success() && err.contains("are for the whole suite"), "{flags:?}: {err}");
            assert!(!dir.path().join("b.json").exists() && !dir.path().join("b").exists());
        }
    }
}

#[test]
fn an_output_folder_that_cannot_be_made_an_output_named_twice_or_a_checkpoint_named_as_an_output_leaves_the_existing_file(
) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.exr"), b"what the user had").unwrap();
    std::fs::write(dir.path().join("file"), b"a file, not a folder").unwrap();
    let run = ["optimize", "--size", "8x8x2", "--iterations", "5", "--backend", "cpu", "--out", "m.exr"];
    let cases: &[(&[&str], &str)] = &[
        (&["--png", "file/slices"], "is not a folder to make it in"),
        (&["--checkpoint", "m.exr"], "is also an output"),
        (&["--checkpoint", "./m.exr"], "is also an output"),
        (&["--also", "m.ktx2", "--checkpoint", "m.ktx2"], "is also an output"),
        (&["--checkpoint", "/dev/null"], "is not a regular file"),
        (&["--also", "m.exr"], "are one file"),
        (&["--also", "./m.exr"], "are one file"),
        (&["--also", "m.h", "--also", "./m.h"], "are one file"),
    ];
    for (extra, expect) in cases {
        let mut args = run.to_vec();
        args.extend_from_slice(extra);
        let o = fsot(&args, dir.path());
        let err = stderr(&o);
        assert!(!o.status.success() && !err.contains("panicked"), "{extra:?}: {err}");
        assert!(err.contains(expect), "{extra:?}: expected {expect:?} in {err:?}");
        assert_eq!(std::fs::read(dir.path().join("m.exr")).unwrap(), b"what the user had", "{extra:?}");
    }
}

#[test]
fn png_slices_that_cannot_all_be_written_are_refused_before_the_work_and_nothing_is_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let slices = dir.path().join("slices");
    std::fs::create_dir_all(slices.join("frame0002.png")).unwrap();
    std::fs::write(slices.join("frame0000.png"), b"the user's slice").unwrap();
    std::fs::write(dir.path().join("m.exr"), b"what the user had").unwrap();
    let args = ["optimize", "--size", "8x8x4", "--iterations", "3", "--backend", "cpu", "--out", "m.exr"];
    let o = fsot(&[&args[..], &["--png", "slices"]].concat(), dir.path());
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("frame0002.png is a directory"), "{err}");
    assert!(!err.contains("optimizing"), "refused before the work: {err}");
    assert_eq!(std::fs::read(slices.join("frame0000.png")).unwrap(), b"the user's slice");
    assert!(!slices.join("frame0001.png").exists());
    assert_eq!(std::fs::read(dir.path().join("m.exr")).unwrap(), b"what the user had");
}

#[test]
fn the_stress_suite_refuses_a_named_device_it_cannot_find_rather_than_run_the_cpu_checks_alone() {
    let dir = tempfile::tempdir().unwrap();
    let o = fsot(&["stress", "--quick", "--device", "no-such-gpu"], dir.path());
    let err = stderr(&o);
    assert!(!o.status.success() && err.contains("no device matches"), "{err}");
    assert!(!err.contains("checks held") && !dir.path().join("stress.md").exists(), "{err}");
}

#[test]
fn a_flag_the_method_has_no_use_for_is_noted_and_the_run_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let base = ["optimize", "--size", "8x8x4", "--backend", "cpu", "--out", "m.exr"];
    let fsot_run =
        ["--iterations", "3", "--passes", "4", "--fast-combine", "sum:0.5", "--checkpoint-every", "2"];
    let o = fsot(&[&base[..], &fsot_run].concat(), dir.path());
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    for flag in ["--passes", "--fast-combine", "--checkpoint-every"] {
        assert!(err.contains(&format!("note: {flag} does nothing here")), "{flag}: {err}");
    }
    assert!(!err.contains("note: --iterations"), "{err}");
    let o = fsot(
        &[&base[..], &["--method", "white", "--iterations", "3", "--until", "plateau"]].concat(),
        dir.path(),
    );
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("note: --iterations does nothing here: it is for --method fsot"), "{err}");
    assert!(err.contains("note: --until does nothing here"), "{err}");
    // A scalar STBN mask is void and cluster, not a swap search.
    let o = fsot(&[&base[..], &["--method", "stbn", "--dims", "1", "--passes", "3"]].concat(), dir.path());
    let err = stderr(&o);
    assert!(o.status.success() && err.contains("note: --passes does nothing here"), "{err}");
    // Defaults are no flags given: nothing to note.
    let o = fsot(&[&base[..], &["--method", "fast", "--passes", "1"]].concat(), dir.path());
    assert!(o.status.success() && !stderr(&o).contains("note:"), "{}", stderr(&o));
}

/// Each case, `base` then its flags, fails with its message, no panic, and
/// leaves no `m.exr` in `dir`.
fn refused(dir: &Path, base: &[&str], cases: &[(&[&str], &str)]) {
    for (extra, expect) in cases {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        let o = fsot(&args, dir);
        let err = stderr(&o);
        assert!(!o.status.success() && !err.contains("panicked"), "{extra:?}: {err}");
        assert!(err.contains(expect), "{extra:?}: expected {expect:?} in {err:?}");
        assert!(!dir.join("m.exr").exists(), "{extra:?} left a file");
    }
}

#[test]
fn fast_starts_from_an_initial_mask_and_methods_that_start_from_nothing_refuse_one() {
    let dir = tempfile::tempdir().unwrap();
    let made = fsot(
        &["optimize", "--method", "white", "--size", "8x8x4", "--dims", "1", "--out", "w.exr"],
        dir.path(),
    );
    assert!(made.status.success(), "{}", stderr(&made));
    let o = fsot(
        &["optimize", "--method", "fast", "--init", "w.exr", "--passes", "2", "--out", "f.exr"],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (mut start, mut swapped) =
        (read_samples(&dir.path().join("w.exr")), read_samples(&dir.path().join("f.exr")));
    assert_ne!(start, swapped, "no swap taken");
    start.sort_unstable();
    swapped.sort_unstable();
    assert_eq!(start, swapped, "FAST from a mask keeps its values");
    let cases: &[(&[&str], &str)] = &[
        (&["--method", "white"], "initial mask"),
        (&["--method", "stbn"], "initial mask"),
        (&["--method", "fast", "--size", "16x16x4"], "initial mask is 8x8x4"),
    ];
    refused(dir.path(), &["optimize", "--init", "w.exr", "--out", "m.exr"], cases);
}

#[test]
fn a_run_killed_mid_way_leaves_the_existing_output_untouched_and_nothing_else() {
    // A long run over an existing file, killed (SIGKILL: no chance to clean up)
    // after a second and a half of its work.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("existing.exr"), b"the user's mask").unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_fsot"))
        .args(["optimize", "--backend", "cpu", "--size", "64x64x16", "--iterations", "100000"])
        .args(["--out", "existing.exr"])
        .current_dir(dir.path())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    assert!(child.try_wait().unwrap().is_none(), "the run ended before it was killed");
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(std::fs::read(dir.path().join("existing.exr")).unwrap(), b"the user's mask");
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["existing.exr".to_string()], "files left behind");
}

fn read_samples(path: &Path) -> Vec<u32> {
    fsot::io::exr::read(path).unwrap().samples.iter().map(|v| v.to_bits()).collect()
}

/// `fsot args` in `dir`, sent SIGINT (as a user's Ctrl-C) once its checkpoint
/// `run.ckpt` is on disk; what it printed and how it ended.
fn interrupted_once_checkpointed(args: &[&str], dir: &Path) -> Output {
    let child = Command::new(env!("CARGO_BIN_EXE_fsot"))
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let (ckpt, started) = (dir.join("run.ckpt"), std::time::Instant::now());
    while !ckpt.exists() {
        assert!(started.elapsed().as_secs() < 120, "no checkpoint appeared");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // Twice, as `timeout` and some shells send it (to the process, then its
    // group): one request to stop, not a second to quit at once.
    for _ in 0..2 {
        assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    }
    child.wait_with_output().unwrap()
}

#[test]
fn ctrl_c_saves_a_checkpoint_and_resuming_gives_the_uninterrupted_mask_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let run: Vec<&str> = vec![
        "optimize",
        "--backend",
        "cpu",
        "--size",
        "16x16x8",
        "--kernel",
        "taa",
        "--seed",
        "5",
        "--iterations",
        "4000",
    ];
    let straight = fsot(&[&run[..], &["--out", "straight.exr"]].concat(), dir.path());
    assert!(straight.status.success(), "{}", stderr(&straight));

    std::fs::write(dir.path().join("existing.exr"), b"the user's mask").unwrap();
    let with_checkpoint = [&run[..], &["--checkpoint", "run.ckpt", "--checkpoint-every", "50"]].concat();
    let out = interrupted_once_checkpointed(
        &[&with_checkpoint[..], &["--out", "existing.exr"]].concat(),
        dir.path(),
    );
    let ckpt = dir.path().join("run.ckpt");
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(130), "{message}");
    assert!(message.contains("interrupted at iteration") && message.contains("--resume"), "{message}");
    assert!(!message.contains("panicked"), "{message}");
    assert_eq!(std::fs::read(dir.path().join("existing.exr")).unwrap(), b"the user's mask");
    assert!(ckpt.exists());

    // The same command again without --resume refuses to overwrite the checkpoint.
    let again = fsot(&[&with_checkpoint[..], &["--out", "existing.exr"]].concat(), dir.path());
    assert!(!again.status.success() && stderr(&again).contains("--resume"), "{}", stderr(&again));
    // A different run cannot resume it.
    let mut other = with_checkpoint.clone();
    other[8] = "6"; // the seed
    let wrong = fsot(&[&other[..], &["--out", "existing.exr", "--resume"]].concat(), dir.path());
    assert!(!wrong.status.success() && stderr(&wrong).contains("different run"), "{}", stderr(&wrong));
    assert_eq!(std::fs::read(dir.path().join("existing.exr")).unwrap(), b"the user's mask");

    let resumed = fsot(&[&with_checkpoint[..], &["--out", "existing.exr", "--resume"]].concat(), dir.path());
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    assert!(stderr(&resumed).contains("resumed from"), "{}", stderr(&resumed));
    // A white start is made from the seed again: its objective is reported.
    let report = String::from_utf8_lossy(&resumed.stdout);
    assert!(report.contains("objective ") && report.contains(" -> "), "{report}");
    assert!(!ckpt.exists(), "the checkpoint of a completed run is removed");
    assert_eq!(
        read_samples(&dir.path().join("existing.exr")),
        read_samples(&dir.path().join("straight.exr")),
        "resumed and uninterrupted runs differ"
    );
}

#[test]
fn scene_runs_plan_write_a_folder_and_refuse_bad_scenes_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n\
                 [[group]]\nname = \"pick\"\ndims = 1\n[[group]]\nname = \"deep\"\ndims = 2\nvisible = false\n";
    std::fs::write(dir.path().join("s.toml"), scene).unwrap();
    let plan = fsot(&["plan", "s.toml", "--backend", "cpu"], dir.path());
    assert!(plan.status.success(), "{}", stderr(&plan));
    let text = String::from_utf8_lossy(&plan.stdout);
    assert!(text.contains("pick (d = 1") && text.contains("skipped: not visible"), "{text}");
    let json = fsot(&["plan", "s.toml", "--backend", "cpu", "--json"], dir.path());
    let doc: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(doc["tile"], serde_json::json!([8, 8, 4]));

    let o = fsot(&["optimize", "--scene", "s.toml", "--out", "masks", "--backend", "cpu"], dir.path());
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["pick.exr", "deep.exr", "plan.json"] {
        assert!(dir.path().join("masks").join(f).exists(), "{f}");
    }
    // Under a budget: the plan says it, the run reports how it kept it.
    let plan = fsot(&["plan", "s.toml", "--backend", "cpu", "--budget", "1s"], dir.path());
    let text = String::from_utf8_lossy(&plan.stdout);
    assert!(text.contains("budget: 1 s") && text.contains("total: about 1.0 s"), "{text}");
    assert!(!text.contains("too short"), "an 8x8x4 mask takes hundreds of iterations a second: {text}");
    // A budget too short for one iteration of a mask is said, with the mask.
    let big =
        "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"128x128x64\"\n[[group]]\nname = \"lens\"\ndims = 2\n";
    std::fs::write(dir.path().join("big.toml"), big).unwrap();
    let plan = fsot(&["plan", "big.toml", "--backend", "cpu", "--budget", "1ms"], dir.path());
    let text = String::from_utf8_lossy(&plan.stdout);
    assert!(text.contains("too short here for one iteration of lens.exr"), "{text}");
    let o = fsot(
        &["optimize", "--scene", "s.toml", "--out", "b", "--backend", "cpu", "--budget", "1s"],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("budget 1 s: the masks were made"), "{out}");
    let mask = fsot::io::exr::read(&dir.path().join("b").join("pick.exr")).unwrap();
    assert!(mask.meta("budget_seconds").is_some(), "{:?}", mask.meta);
    // KTX2 beside each mask, in the format asked for.
    let o = fsot(
        &["optimize", "--scene", "s.toml", "--out", "k", "--backend", "cpu", "--ktx2-format", "r8g8_unorm"],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["pick.ktx2", "deep.ktx2"] {
        let bytes = std::fs::read(dir.path().join("k").join(f)).unwrap();
        let r = ktx2::Reader::new(&bytes[..]).unwrap();
        assert_eq!(r.header().format, Some(ktx2::Format::R8G8_UNORM), "{f}");
    }
    // A KTX2 output that cannot be written is refused before the work.
    std::fs::create_dir_all(dir.path().join("kd/pick.ktx2")).unwrap();
    let o = fsot(
        &["optimize", "--scene", "s.toml", "--out", "kd", "--backend", "cpu", "--ktx2-format", "auto"],
        dir.path(),
    );
    assert!(!o.status.success() && stderr(&o).contains("kd/pick.ktx2 is a directory"), "{}", stderr(&o));
    assert!(!dir.path().join("kd/pick.exr").exists() && !dir.path().join("kd/plan.json").exists());

    std::fs::write(dir.path().join("bad.toml"), "[[group]]\nname = \"a\"\ndims = 2\nsppp = 1\n").unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["optimize", "--scene", "bad.toml", "--out", "bad"], "line 4"),
        (&["optimize", "--scene", "missing.toml", "--out", "bad"], "cannot read the scene"),
        (&["optimize", "--scene", "s.toml", "--out", "bad.exr"], "names a folder"),
        (&["optimize", "--scene", "s.toml", "--out", "bad.ktx2"], "names a folder"),
        (&["optimize", "--scene", "s.toml", "--out", "/dev/null"], "names a folder"),
        (&["optimize", "--scene", "s.toml", "--out", "bad", "--dims", "3"], "--scene does not take"),
        (&["optimize", "--scene", "s.toml", "--out", "bad", "--until", "plateau"], "--scene does not take"),
        (
            &["optimize", "--scene", "s.toml", "--out", "bad", "--start", "white"],
            "--scene does not take --start",
        ),
        (&["optimize", "--scene", "s.toml", "--out", "bad", "--budget", "soon"], "--budget must be a time"),
        (
            &["optimize", "--scene", "s.toml", "--out", "bad", "--alpha", "5"],
            "--scene does not take --kernel",
        ),
        (
            &["optimize", "--scene", "s.toml", "--out", "bad", "--display", "standard_4k"],
            "--scene does not take --kernel",
        ),
        (&["optimize", "--scene", "s.toml", "--out", "bad", "--png", "p"], "--scene does not take --png"),
        (&["optimize", "--scene", "s.toml", "--out", "bad", "--seed", "3"], "--scene does not take --seed"),
        (
            &["optimize", "--scene", "s.toml", "--out", "bad", "--slices", "9"],
            "--scene does not take --slices",
        ),
        (&["optimize", "--scene", "s.toml", "--out", "bad", "--ktx2-format", "r8_unorm"], "d = 2"),
        (&["plan", "bad.toml"], "line 4"),
    ];
    for (args, expect) in cases {
        let o = fsot(args, dir.path());
        let err = stderr(&o);
        assert!(!o.status.success() && !err.contains("panicked"), "{args:?}: {err}");
        assert!(err.contains(expect), "{args:?}: expected {expect:?} in {err:?}");
        assert!(!dir.path().join("bad").exists() && !dir.path().join("bad.exr").exists(), "{args:?} wrote");
    }
}

#[test]
fn a_ktx2_from_optimize_decodes_to_the_exr_of_the_same_command_within_one_level() {
    let dir = tempfile::tempdir().unwrap();
    let run = |out: &str, extra: &[&str]| {
        let mut args =
            vec!["optimize", "--backend", "cpu", "--size", "32x32x16", "--dims", "2", "--kernel", "taa"];
        args.extend(["--seed", "7", "--iterations", "20", "--out", out]);
        args.extend(extra);
        let o = fsot(&args, dir.path());
        assert!(o.status.success(), "{}", stderr(&o));
    };
    // The format applies to a .ktx2 given by --also as by --out.
    run("m.exr", &["--also", "also.ktx2", "--ktx2-format", "r16g16_unorm"]);
    run("m.ktx2", &["--ktx2-format", "r16g16_unorm"]);
    let exr = fsot::io::exr::read(&dir.path().join("m.exr")).unwrap();
    let bytes = std::fs::read(dir.path().join("m.ktx2")).unwrap();
    assert_eq!(std::fs::read(dir.path().join("also.ktx2")).unwrap(), bytes);
    let r = ktx2::Reader::new(&bytes[..]).unwrap();
    assert_eq!(r.header().format, Some(ktx2::Format::R16G16_UNORM));
    assert_eq!(r.header().layer_count, 16);
    let data = r.levels().next().unwrap().data;
    let mut worst = 0.0f64;
    for (i, pair) in data.chunks_exact(4).enumerate() {
        let (x, y, t) = (i % 32, (i / 32) % 32, i / 1024);
        for c in 0..2 {
            let q = u16::from_le_bytes([pair[2 * c], pair[2 * c + 1]]) as f64 / 65535.0;
            worst = worst.max((q - exr.sample(x, y, t, 0)[c] as f64).abs());
        }
    }
    assert!(worst <= 1.0 / 65535.0, "worst {worst}");
}

#[test]
fn a_c_header_compiles_and_holds_the_masks_levels() {
    let dir = tempfile::tempdir().unwrap();
    let o = fsot(
        &["optimize", "--backend", "cpu", "--size", "4x4x2", "--spp", "2", "--iterations", "5"]
            .into_iter()
            .chain(["--out", "blue-4.h"])
            .collect::<Vec<_>>(),
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let header = std::fs::read_to_string(dir.path().join("blue-4.h")).unwrap();
    assert!(header.contains("static const uint16_t blue_4[128]"), "{header}");
    assert!(header.contains("BLUE_4_SPP = 2"));
    let c = "#include <stdio.h>\n#include \"blue-4.h\"\nint main(void) { for (int i = 0; i < 128; i++) \
             printf(\"%u\\n\", blue_4[i]); return BLUE_4_WIDTH * BLUE_4_HEIGHT * BLUE_4_FRAMES * BLUE_4_SPP * \
             BLUE_4_DIMS == 128 ? 0 : 1; }\n";
    std::fs::write(dir.path().join("main.c"), c).unwrap();
    let cc = Command::new("cc")
        .args(["-std=c99", "-Wall", "-Werror", "main.c", "-o", "main"])
        .current_dir(dir.path())
        .output();
    let Ok(cc) = cc else {
        let _ = common::skip("the compile half: no C compiler (cc) on this machine");
        return;
    };
    assert!(cc.status.success(), "{}", String::from_utf8_lossy(&cc.stderr));
    let run = Command::new(dir.path().join("main")).output().unwrap();
    assert!(run.status.success());
    let levels: Vec<u32> = String::from_utf8_lossy(&run.stdout).lines().map(|l| l.parse().unwrap()).collect();
    // The same mask again as EXR: every level the nearest to v * 65535, in the
    // documented order (((t * spp + s) * H + y) * W + x) * D + k.
    let o = fsot(
        &[
            "optimize",
            "--backend",
            "cpu",
            "--size",
            "4x4x2",
            "--spp",
            "2",
            "--iterations",
            "5",
            "--out",
            "m.exr",
        ],
        dir.path(),
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let m = fsot::io::exr::read(&dir.path().join("m.exr")).unwrap();
    let mut i = 0;
    for t in 0..2 {
        for s in 0..2 {
            for y in 0..4 {
                for x in 0..4 {
                    for &v in m.sample(x, y, t, s) {
                        assert!(
                            (levels[i] as f64 - v as f64 * 65535.0).abs() <= 0.5,
                            "{} against {v}",
                            levels[i]
                        );
                        i += 1;
                    }
                }
            }
        }
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn vulkan_takes_three_four_and_eight_dimensions_with_the_validation_layer_on() {
    // FSOT_VALIDATION=1: the command fails if the layer says anything.
    let dir = tempfile::tempdir().unwrap();
    for dims in ["3", "4", "8"] {
        let o = Command::new(env!("CARGO_BIN_EXE_fsot"))
            .args([
                "optimize",
                "--backend",
                "vulkan",
                "--dims",
                dims,
                "--size",
                "8x8x4",
                "--iterations",
                "20",
            ])
            .args(["--out", "m.exr"])
            .env("FSOT_VALIDATION", "1")
            .current_dir(dir.path())
            .output()
            .unwrap();
        let err = format!("{}{}", stderr(&o), String::from_utf8_lossy(&o.stdout));
        assert!(o.status.success(), "d = {dims}: {err}");
        assert!(err.contains("backend: vulkan") && err.contains("(vulkan)"), "d = {dims}: {err}");
        assert!(err.contains(&format!("d = {dims}")), "{err}");
        let mask = fsot::io::exr::read(&dir.path().join("m.exr")).unwrap();
        assert_eq!(mask.tile.dims, dims.parse::<usize>().unwrap());
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn fast_and_vector_stbn_search_on_vulkan_with_the_validation_layer_on() {
    // FSOT_VALIDATION=1: the command fails, writing nothing, if the layer says anything.
    let dir = tempfile::tempdir().unwrap();
    for method in [&["--method", "fast"][..], &["--method", "stbn", "--dims", "2"]] {
        let o = Command::new(env!("CARGO_BIN_EXE_fsot"))
            .args(["optimize", "--backend", "vulkan", "--size", "8x8x4", "--passes", "4", "--out", "m.exr"])
            .args(method)
            .env("FSOT_VALIDATION", "1")
            .current_dir(dir.path())
            .output()
            .unwrap();
        let err = format!("{}{}", stderr(&o), String::from_utf8_lossy(&o.stdout));
        assert!(o.status.success(), "{method:?}: {err}");
        assert!(err.contains("backend: vulkan"), "{method:?}: {err}");
        let mask = fsot::io::exr::read(&dir.path().join("m.exr")).unwrap();
        assert_eq!(mask.tile.pixels(), 8 * 8 * 4);
        assert!(err.contains("on vulkan") && err.contains("proposed swaps taken"), "{err}");
        if method[1] == "fast" {
            assert_eq!(
                mask.meta.iter().find(|(k, _)| k == "backend").map(|(_, v)| v.as_str()),
                Some("vulkan")
            );
        } else {
            assert!(mask.meta.iter().any(|(_, v)| v.contains("passes on vulkan")), "{:?}", mask.meta);
        }
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_scene_plan_runs_on_vulkan_its_masks_side_by_side_with_the_validation_layer_on() {
    let dir = tempfile::tempdir().unwrap();
    let scene = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n\
                 [[group]]\nname = \"pick\"\ndims = 1\n[[group]]\nname = \"lens\"\ndims = 2\n\
                 [[group]]\nname = \"deep\"\ndims = 2\nvisible = false\n";
    std::fs::write(dir.path().join("s.toml"), scene).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_fsot"))
        .args(["optimize", "--scene", "s.toml", "--out", "masks", "--backend", "vulkan"])
        .env("FSOT_VALIDATION", "1")
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["pick.exr", "lens.exr"] {
        let mask = fsot::io::exr::read(&dir.path().join("masks").join(f)).unwrap();
        let backend = mask.meta.iter().find(|(k, _)| k == "backend").map(|(_, v)| v.clone());
        assert!(backend.as_deref().is_some_and(|b| b.starts_with("vulkan")), "{f}: {backend:?}");
    }
    let plan: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("masks/plan.json")).unwrap()).unwrap();
    assert_eq!(plan["groups"].as_array().unwrap().len(), 3);
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn profile_prints_each_pass_s_time_and_the_bytes_it_must_move() {
    let dir = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_fsot"))
        .args(["optimize", "--backend", "vulkan", "--size", "8x8x4", "--spp", "16", "--iterations", "4"])
        .args(["--kernel", "perceptual-taa", "--profile", "--out", "m.exr"])
        .env("FSOT_VALIDATION", "1")
        .current_dir(dir.path())
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}{out}", stderr(&o));
    assert!(out.contains("profile (4 iterations, per iteration): transport"), "{out}");
    // 8x8x4 x 16 spp x 2 coordinates, each read (4 bytes) and added into (a 4-byte
    // float or 8-byte fixed-point atomic) at least once per iteration.
    let line = out.lines().find(|l| l.contains("least bytes per iteration")).expect("the bytes line");
    let mb: f64 = line.split("transport ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(mb * 1e6 >= 8.0 * (8 * 8 * 4 * 16 * 2) as f64, "{line}");
}

#[test]
fn an_axis_share_at_one_dimension_is_said_to_do_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["optimize", "--backend", "cpu", "--size", "8x8x4", "--iterations", "3", "--out", "m.exr"];
    let one = fsot(&[&args[..], &["--dims", "1", "--axis-share", "0.9"]].concat(), dir.path());
    assert!(one.status.success(), "{}", stderr(&one));
    assert!(stderr(&one).contains("--axis-share does nothing at d = 1"), "{}", stderr(&one));
    let two = fsot(&[&args[..], &["--dims", "2", "--axis-share", "0.9"]].concat(), dir.path());
    assert!(two.status.success() && !stderr(&two).contains("does nothing"), "{}", stderr(&two));
}

#[test]
fn a_resumed_run_whose_animated_start_the_checkpoint_does_not_keep_reports_the_result_alone() {
    let dir = tempfile::tempdir().unwrap();
    let run = [
        "optimize",
        "--backend",
        "cpu",
        "--size",
        "16x16x8",
        "--kernel",
        "taa",
        "--start",
        "animated",
        "--iterations",
        "4000",
        "--checkpoint",
        "run.ckpt",
        "--checkpoint-every",
        "50",
        "--out",
        "m.exr",
    ];
    let out = interrupted_once_checkpointed(&run, dir.path());
    assert_eq!(out.status.code(), Some(130), "{}", stderr(&out));
    let resumed = fsot(&[&run[..], &["--resume"]].concat(), dir.path());
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    let report = String::from_utf8_lossy(&resumed.stdout);
    assert!(report.contains("the start's not kept") && !report.contains(" -> "), "{report}");
}

#[test]
fn output_that_cannot_be_written_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let made = fsot(
        &["optimize", "--backend", "cpu", "--size", "8x8x4", "--iterations", "5", "--out", "m.exr"],
        dir.path(),
    );
    assert!(made.status.success(), "{}", stderr(&made));
    // A full disk behind standard output.
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_fsot"))
        .args(["score", "m.exr"])
        .current_dir(dir.path())
        .stdout(full)
        .output()
        .unwrap();
    let text = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("cannot write to standard output") && !text.contains("panicked"), "{text}");
}

#[test]
fn an_stbn_energy_that_weighs_no_pair_of_pixels_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    for dims in ["1", "2"] {
        let o = fsot(
            &[
                "optimize",
                "--method",
                "stbn",
                "--size",
                "16x16x8",
                "--dims",
                dims,
                "--sigma",
                "0.01",
                "--sigma-t",
                "0.01",
                "--out",
                "b.exr",
            ],
            dir.path(),
        );
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains("weighs no pair of pixels"), "{}", stderr(&o));
        assert!(!dir.path().join("b.exr").exists());
    }
}

#[test]
fn png_slices_of_another_mask_that_would_stay_beside_the_new_ones_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let make = |size: &str| {
        fsot(
            &[
                "optimize",
                "--backend",
                "cpu",
                "--size",
                size,
                "--iterations",
                "5",
                "--out",
                "p.exr",
                "--png",
                "P",
            ],
            dir.path(),
        )
    };
    assert!(make("8x8x8").status.success());
    let shorter = make("8x8x4");
    assert_eq!(shorter.status.code(), Some(1), "{}", stderr(&shorter));
    assert!(stderr(&shorter).contains("frame0004.png and 3 more"), "{}", stderr(&shorter));
    // The same tile again replaces its own slices.
    assert!(make("8x8x8").status.success());
}

#[test]
fn a_scene_run_touches_nothing_before_its_runs_start_and_a_resume_clears_what_it_does_not_need() {
    let dir = tempfile::tempdir().unwrap();
    let scene =
        "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n[[group]]\nname = \"light\"\ndims = 2\n\
                 [[group]]\nname = \"hid\"\ndims = 2\nvisible = false\n";
    std::fs::write(dir.path().join("s.toml"), scene).unwrap();
    let run = |extra: &[&str]| {
        fsot(
            &[&["optimize", "--backend", "cpu", "--scene", "s.toml", "--out", "o"][..], extra].concat(),
            dir.path(),
        )
    };
    assert!(run(&[]).status.success());
    let o = dir.path().join("o");
    let before: Vec<(String, Vec<u8>)> = ["plan.json", "light.exr", "hid.exr"]
        .iter()
        .map(|f| (f.to_string(), std::fs::read(o.join(f)).unwrap()))
        .collect();
    // A checkpoint left there: the fresh run fails before any file changes.
    std::fs::write(o.join(".light.ckpt"), b"x").unwrap();
    let failed = run(&[]);
    assert_eq!(failed.status.code(), Some(1), "{}", stderr(&failed));
    assert!(stderr(&failed).contains("exists"), "{}", stderr(&failed));
    for (f, bytes) in &before {
        assert_eq!(&std::fs::read(o.join(f)).unwrap(), bytes, "{f} changed");
    }
    // A resume keeps the finished mask and removes the checkpoint beside it.
    let resumed = run(&["--resume"]);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    assert!(!o.join(".light.ckpt").exists());
    assert!(run(&[]).status.success(), "a fresh run after it finds no checkpoint in its way");
    // A plan under a budget takes no checkpoints: nothing to resume.
    let budget = run(&["--resume", "--budget", "1s"]);
    assert_eq!(budget.status.code(), Some(1), "{}", stderr(&budget));
    assert!(stderr(&budget).contains("nothing to resume"), "{}", stderr(&budget));
}
