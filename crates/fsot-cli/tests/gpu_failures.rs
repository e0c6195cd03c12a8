//! What users see when Vulkan fails (failures injected with FSOT_FAULT, see
//! src/optimize/vulkan/fault.rs, or a missing driver): `--backend vulkan` stops with a clear
//! error and writes nothing; `--backend auto` says so and finishes on the CPU path.

use std::path::Path;
use std::process::{Command, Output};

fn fsot(dir: &Path, env: &[(&str, &str)], args: &[&str]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_fsot"));
    c.args(["optimize", "--size", "16x16x8", "--kernel", "taa", "--iterations", "120"]);
    c.args(args).current_dir(dir);
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned() + &String::from_utf8_lossy(&o.stdout)
}

fn setup() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("existing.exr"), b"the user's mask").unwrap();
    dir
}

fn untouched(dir: &Path) -> bool {
    std::fs::read(dir.join("existing.exr")).unwrap() == b"the user's mask"
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_lost_device_stops_a_vulkan_run_with_a_clear_error_and_nothing_written() {
    let dir = setup();
    let o = fsot(
        dir.path(),
        &[("FSOT_FAULT", "device-lost:3")],
        &["--backend", "vulkan", "--out", "existing.exr"],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("the GPU was lost") && !t.contains("panicked"), "{t}");
    assert!(untouched(dir.path()));
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn with_auto_a_lost_device_hands_over_to_the_cpu_from_the_last_checkpoint() {
    let dir = setup();
    // Device 0 named explicitly, so that auto takes it even where it is lavapipe.
    let o = fsot(
        dir.path(),
        &[("FSOT_FAULT", "device-lost:6")],
        &["--backend", "auto", "--device", "0", "--checkpoint", "c.ckpt", "--checkpoint-every", "20"],
    );
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("warning: the GPU failed at iteration"), "{t}");
    assert!(t.contains("continuing from its checkpoint"), "{t}");
    // From the last checkpoint before the failure (one every 20 iterations;
    // a failure while saving one continues from the one before).
    let number_after = |key: &str| -> u32 {
        let rest = &t[t.find(key).unwrap_or_else(|| panic!("{key} in {t}")) + key.len()..];
        rest[..rest.find(|c: char| !c.is_ascii_digit()).unwrap()].parse().unwrap()
    };
    let (at, from) = (number_after("failed at iteration "), number_after("(iteration "));
    assert!(from > 0 && from % 20 == 0 && from <= at && at - from <= 20, "failed at {at}, from {from}: {t}");
    assert!(t.contains("120 iterations") && t.contains("(cpu)"), "{t}");
    let mask = fsot::io::exr::read(&dir.path().join("mask.exr")).unwrap();
    assert!(mask.samples.iter().all(|v| (0.0..1.0).contains(v)));
    assert!(!dir.path().join("c.ckpt").exists());
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn out_of_device_memory_is_an_error_for_vulkan_and_a_fall_back_for_auto() {
    let dir = setup();
    let env = [("FSOT_FAULT", "device-memory:1024")];
    let o = fsot(dir.path(), &env, &["--backend", "vulkan", "--out", "existing.exr"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("GPU memory") && t.contains("--backend cpu"), "{t}");
    assert!(untouched(dir.path()));
    let o = fsot(dir.path(), &env, &["--backend", "auto", "--device", "0"]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("backend: cpu") && t.contains("no Vulkan GPU used: GPU memory"), "{t}");
}

#[test]
fn without_a_vulkan_driver_vulkan_fails_clearly_and_auto_uses_the_cpu() {
    let dir = setup();
    let env = [("VK_ICD_FILENAMES", "/nonexistent/icd.json"), ("VK_DRIVER_FILES", "/nonexistent/icd.json")];
    let o = fsot(dir.path(), &env, &["--backend", "vulkan", "--out", "existing.exr"]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("Vulkan") && !t.contains("panicked"), "{t}");
    assert!(untouched(dir.path()));
    let o = fsot(dir.path(), &env, &["--backend", "auto"]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("backend: cpu") && t.contains("no Vulkan GPU used"), "{t}");
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn a_swap_search_the_gpu_cannot_finish_starts_again_on_the_cpu_with_auto_and_stops_with_vulkan() {
    let dir = setup();
    let run = |backend: &str, out: &str, fault: Option<&str>| {
        let mut c = Command::new(env!("CARGO_BIN_EXE_fsot"));
        c.args(["optimize", "--method", "fast", "--size", "16x16x8", "--passes", "4", "--out", out]);
        c.args(["--backend", backend, "--device", "0"]).current_dir(dir.path());
        if let Some(f) = fault {
            c.env("FSOT_FAULT", f);
        }
        c.output().unwrap()
    };
    let lost = run("vulkan", "existing.exr", Some("device-lost:2"));
    assert_eq!(lost.status.code(), Some(1), "{}", text(&lost));
    assert!(untouched(dir.path()));
    let handed = run("auto", "auto.exr", Some("device-lost:2"));
    let t = text(&handed);
    assert!(handed.status.success(), "{t}");
    assert!(t.contains("the GPU was lost") && t.contains("the search runs on the cpu"), "{t}");
    // Started again from its seed: the CPU's own mask, bit for bit.
    let cpu = run("cpu", "cpu.exr", None);
    assert!(cpu.status.success(), "{}", text(&cpu));
    assert_eq!(
        std::fs::read(dir.path().join("auto.exr")).unwrap(),
        std::fs::read(dir.path().join("cpu.exr")).unwrap()
    );
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn with_auto_a_scene_whose_device_is_lost_at_any_submission_finishes_on_the_cpu() {
    // Two masks stepping together on one device, checkpointing every 5
    // iterations: the device lost at each of the first submissions, whether
    // in a step or in a checkpoint's read-back, hands every run to the CPU,
    // and says so.
    let scene = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n\
                 [[group]]\nname = \"light\"\ndims = 2\n[[group]]\nname = \"pick\"\ndims = 1\n";
    for n in 1..=16 {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("s.toml"), scene).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_fsot"))
            .args(["optimize", "--backend", "auto", "--device", "0", "--scene", "s.toml", "--out", "o"])
            .args(["--checkpoint-every", "5"])
            .current_dir(dir.path())
            .env("FSOT_FAULT", format!("device-lost:{n}"))
            .output()
            .unwrap();
        let t = text(&o);
        assert!(o.status.success(), "device lost at submission {n}: {t}");
        assert!(dir.path().join("o/plan.json").exists() && !t.contains("panicked"), "{n}: {t}");
        // The loss is said, wherever it fell: as a mask's run started (its
        // backend's line) or mid-run (a warning).
        assert!(t.contains("the GPU failed") || t.contains("no Vulkan GPU used"), "{n}: {t}");
    }
}

#[cfg_attr(fsot_skip_gpu, ignore = "FSOT_SKIP_GPU_TESTS=1: no Vulkan device here")]
#[test]
fn with_auto_a_run_whose_device_is_lost_at_any_submission_finishes_on_the_cpu() {
    // Its upload, its steps, its checkpoints' read-backs and the mask's own:
    // wherever the device is lost, auto ends on the CPU with the mask written.
    for n in 1..=20 {
        let dir = setup();
        let o = fsot(
            dir.path(),
            &[("FSOT_FAULT", &format!("device-lost:{n}"))],
            &["--backend", "auto", "--device", "0", "--checkpoint", "c.ckpt", "--checkpoint-every", "20"],
        );
        let t = text(&o);
        assert!(o.status.success(), "device lost at submission {n}: {t}");
        assert!(t.contains("120 iterations") && !t.contains("panicked"), "{n}: {t}");
        assert!(fsot::io::exr::read(&dir.path().join("mask.exr")).is_ok(), "{n}");
    }
}
