//! A web build (wasm32-unknown-unknown: one thread, no clock) makes its mask at
//! start-up through fsot's CPU path: `examples/web-host`, built for that target
//! and loaded in Node.js as a page would load it, imports nothing, hands over
//! the same 8-bit KTX2 bytes and the same objective (to four digits) as this
//! machine's build makes from the same settings, and is told plainly that a time
//! budget needs a clock. A scene file's plan made there is this machine's: the
//! same plan block and stacked texels.

use std::path::{Path, PathBuf};
use std::process::Command;

use std::sync::OnceLock;

use fsot::{
    BackendChoice, CancelFlag, CostModel, KernelSpec, Mask, Plan, Run, RunOptions, SamplerPlan, Scene,
    Settings, Start, TexelFormat, Tile,
};

mod common;

const TARGET: &str = "wasm32-unknown-unknown";

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn run(what: &mut Command) -> String {
    let out = what.output().unwrap_or_else(|e| panic!("{what:?}: {e}"));
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{what:?}:\n{text}");
    text
}

/// What this machine lacks to build and load the module, if anything.
fn missing() -> Option<String> {
    if Command::new("node").arg("--version").output().map_or(true, |o| !o.status.success()) {
        return Some(
            "Node.js (`node`) is not installed (scripts/install-deps.sh --tests installs it)".into(),
        );
    }
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let libdir = match Command::new(rustc).args(["--print", "target-libdir", "--target", TARGET]).output() {
        Ok(o) if o.status.success() => PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()),
        _ => return Some(format!("rustc could not say where its {TARGET} library would be")),
    };
    match libdir.is_dir() {
        true => None,
        false => Some(format!(
            "Rust's standard library for {TARGET} is not installed (scripts/install-deps.sh --tests adds it)"
        )),
    }
}

/// The web host's module, built for the web on the workspace's locked versions
/// (once per process).
fn module() -> &'static Path {
    static MODULE: OnceLock<PathBuf> = OnceLock::new();
    MODULE.get_or_init(build)
}

fn build() -> PathBuf {
    let target = root().join("target/web-host");
    std::fs::copy(root().join("Cargo.lock"), root().join("examples/web-host/Cargo.lock")).unwrap();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    run(Command::new(cargo)
        .args(["build", "--release", "--offline", "--target", TARGET])
        .current_dir(root().join("examples/web-host"))
        .env("CARGO_TARGET_DIR", &target));
    target.join(TARGET).join("release/fsot_web_host.wasm")
}

#[test]
fn a_web_build_makes_this_machines_mask_in_node_and_refuses_a_time_budget() {
    if let Some(reason) = missing() {
        if common::skip(&reason) {
            return;
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("web.ktx2");
    let said = run(Command::new("node")
        .arg(root().join("examples/web-host/run.mjs"))
        .arg(module())
        .args(["16x16x4", "2", "8"])
        .arg(&out));
    assert!(said.contains("imports: none"), "{said}");
    assert!(said.contains("made 16x16x4, d = 2,"), "{said}");
    assert!(
        said.contains("a time budget: a time budget needs a wall clock, and this platform has none"),
        "{said}"
    );

    // The same settings here, in this process.
    let tile = Tile::new(16, 16, 4, 1, 2).unwrap();
    let kernel = KernelSpec::named("perceptual-taa").unwrap().on_display_named("standard_fhd").unwrap();
    let settings = Settings::new(kernel, 1).iterations(8).start(Start::Animated);
    // This machine's CPU path (a GPU here would make another, valid mask).
    let cpu = RunOptions::default().backend(BackendChoice::Cpu);
    let mut run = Run::start(tile, settings, None, cpu).unwrap();
    run.run(&CancelFlag::new(), &mut |_| {}).unwrap();
    let here = run.finish().unwrap();
    let web = Mask::open(&out).unwrap();
    assert_eq!((web.tile.width, web.tile.height, web.tile.frames, web.tile.dims), (16, 16, 4, 2));
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(
        bytes,
        here.ktx2(Some(TexelFormat::R8G8Unorm)).unwrap(),
        "the web's mask differs from this machine's"
    );
    let ratio = here.score(kernel).unwrap().ratio();
    assert!(said.contains(&format!("objective {ratio:.4} x white noise")), "{said}\nhere: {ratio:.4}");
    assert!(ratio < 0.8, "{ratio}");
}

#[test]
fn a_scene_plan_made_in_a_web_build_is_this_machines() {
    if let Some(reason) = missing() {
        if common::skip(&reason) {
            return;
        }
    }
    let text = "[display]\nfps = 60\ntaa_alpha = 0.1\n[tile]\nsize = \"16x16x4\"\n\
                [[group]]\nname = \"pick\"\ndims = 1\n[[group]]\nname = \"lens\"\ndims = 2\n";
    let dir = tempfile::tempdir().unwrap();
    let scene_file = dir.path().join("scene.toml");
    std::fs::write(&scene_file, text).unwrap();
    let out = dir.path().join("plan");
    let said = run(Command::new("node")
        .arg(root().join("examples/web-host/run.mjs"))
        .arg(module())
        .arg("--scene")
        .arg(&scene_file)
        .arg(&out));
    assert!(said.contains("imports: none") && said.contains("a 544-byte block"), "{said}");

    let plan = Plan::new(&Scene::parse(text, "scene").unwrap(), &CostModel::unmeasured()).unwrap();
    assert_eq!(plan.masks.len(), 2, "a mask for each decision");
    // This machine's CPU path (a GPU here would make other, valid masks).
    let cpu = RunOptions::default().backend(BackendChoice::Cpu);
    let here = SamplerPlan::make(&plan, cpu, &CancelFlag::new(), &mut |_| {}).unwrap().unwrap();
    assert_eq!(std::fs::read(out.with_extension("block")).unwrap(), here.plan_block().unwrap());
    let texels = std::fs::read(out.with_extension("texels")).unwrap();
    assert_eq!(texels.len(), 16 * 16 * 4 * 2 * 2, "two masks of 16x16x4, two channels");
    assert!(
        texels == here.texels(TexelFormat::R8G8Unorm).unwrap(),
        "the web's texels differ from this machine's"
    );
}
