//! Scene plans: what each sampling decision reads and why, and the masks made
//! from a plan.

use fsot::core::kernel::Spatial;
use fsot::core::objective::score;
use fsot::core::tile::Tile;
use fsot::optimize::backend::BackendChoice;
use fsot::optimize::run::{CancelFlag, Outcome, RunOptions};
use fsot::scene::file::Scene;
use fsot::scene::plan::{
    kernel_for, share_offset, share_shift, tile_size, CostModel, Plan, PlanEvent, PlannedMask, SCALAR_EYE_PPD,
};

fn scene(display: &str, groups: &str) -> Scene {
    Scene::parse(&format!("[display]\n{display}\n{groups}"), "test").unwrap()
}

const ONE: &str = "[[group]]\nname = \"a\"\ndims = 2\n";

/// A cost model with a round figure (no calibration run).
fn model() -> CostModel {
    CostModel { seconds_per_point: 1e-6, backend: "test".into() }
}

#[test]
fn the_display_chooses_the_kernel() {
    let k = |d: &str| kernel_for(&scene(d, ONE).display).unwrap().0.describe();
    assert!(k("taa_alpha = 0.1").starts_with("perceptual-taa"), "{}", k("taa_alpha = 0.1"));
    // No TAA: a blend whose half-life is one 60 fps frame, whatever the rate.
    assert!(k("fps = 60").starts_with("taa ("), "{}", k("fps = 60"));
    assert!(k("fps = 60").contains("alpha = 0.5"), "{}", k("fps = 60"));
    for fps in [24.0f64, 30.0, 60.0, 144.0] {
        let spec = kernel_for(&scene(&format!("fps = {fps}"), ONE).display).unwrap().0;
        let fsot::core::kernel::Temporal::Taa { alpha } = spec.temporal else { panic!("{spec:?}") };
        // The weight a frame keeps after 1/60 s of later frames is one half.
        let frames = fps / 60.0;
        assert!(((1.0 - alpha).powf(frames) - 0.5).abs() < 1e-12, "{fps} fps: alpha {alpha}");
    }
    assert!(k("animated = false\ntaa_alpha = 0.1").starts_with("spatial"));
    assert!(
        k("sigma = 1.5\ntaa_alpha = 0.2").contains("sigma = 1.5")
            && k("taa_alpha = 0.2").contains("alpha = 0.2")
    );
}

#[test]
fn the_taa_history_that_matters_sets_the_frames() {
    let t = |d: &str| tile_size(&scene(d, ONE)).0;
    assert_eq!(t("taa_alpha = 0.1"), (128, 128, 64), "0.9^29 < 5%: 29 frames, twice that rounded up to 64");
    assert_eq!(t("taa_alpha = 0.2"), (128, 128, 32));
    assert_eq!(t("taa_alpha = 1.0"), (128, 128, 2));
    assert_eq!(t("taa_alpha = 0.001"), (128, 128, 256), "2995 frames: the most planned, 256");
    assert_eq!(t("taa_alpha = 0.0001"), (128, 128, 256), "the smallest alpha: the most planned");
    assert_eq!(t("fps = 60"), (128, 128, 16), "no TAA: a quarter second of the eye's filter");
    assert_eq!(t("fps = 120"), (128, 128, 32));
    assert_eq!(t("animated = false"), (128, 128, 16));
    let given = Scene::parse(&format!("[tile]\nsize = \"16x8x4\"\n{ONE}"), "t").unwrap();
    assert_eq!(tile_size(&given).0, (16, 8, 4));
    // A mask of 64 spp of 2 values: 128 frames at most, a tile that holds them.
    let wide = scene("taa_alpha = 0.01", "[[group]]\nname = \"a\"\ndims = 2\nspp = 64\n");
    let ((w, h, frames), why) = tile_size(&wide);
    assert_eq!((w, h, frames), (128, 128, 128), "{why}");
    assert!(why.contains("at most 128"), "{why}");
    assert!(Tile::new(w, h, frames, 64, 2).is_ok());
    assert!(Plan::new(&wide, &model()).is_ok());
}

#[test]
fn each_decision_reads_masks_of_its_own_dimensions_and_invisible_ones_read_white_noise() {
    let groups = "[[group]]\nname = \"pick\"\ndims = 1\n[[group]]\nname = \"lens\"\ndims = 2\n\
                  [[group]]\nname = \"vol\"\ndims = 3\nshare = false\n[[group]]\nname = \"quad\"\ndims = 4\n\
                  [[group]]\nname = \"deep\"\ndims = 2\nvisible = false\n";
    let plan = Plan::new(&scene("taa_alpha = 0.1", groups), &model()).unwrap();
    let parts = |name: &str| {
        let g = plan.groups.iter().find(|g| g.name == name).unwrap();
        g.parts.iter().map(|p| (p.mask.clone(), p.first, p.dims)).collect::<Vec<_>>()
    };
    assert_eq!(parts("pick"), [("pick.exr".to_string(), 0, 1)]);
    assert_eq!(parts("lens"), [("lens.exr".to_string(), 0, 2)]);
    assert_eq!(parts("vol"), [("vol-0.exr".to_string(), 0, 2), ("vol-2.exr".to_string(), 2, 1)]);
    // quad's pairs are 2-D at spp 1, like lens: they read lens's mask (below).
    assert_eq!(parts("quad"), [("lens.exr".to_string(), 0, 2), ("lens.exr".to_string(), 2, 2)]);
    let deep = plan.groups.iter().find(|g| g.name == "deep").unwrap();
    assert_eq!(deep.skipped.as_deref(), Some("not visible: white noise"));
    let white: Vec<&str> = plan.masks.iter().filter(|m| m.white).map(|m| m.file.as_str()).collect();
    assert_eq!(white, ["deep.exr"]);
    // Every mask its own seed; estimates from the cost model.
    let seeds: std::collections::HashSet<u64> = plan.masks.iter().map(|m| m.seed).collect();
    assert_eq!(seeds.len(), plan.masks.len(), "two masks share a seed");
    let lens = plan.masks.iter().find(|m| m.file == "lens.exr").unwrap();
    let per = model().seconds_per_iteration(&Tile::new(128, 128, 64, 1, 2).unwrap());
    assert!((per - 1e-6 * 128.0 * 128.0 * 64.0).abs() < 1e-12, "d = 2, spp 1 is the calibration's unit");
    assert_eq!(lens.estimated_seconds, per * lens.estimated_iterations as f64);
    let total: f64 = plan.masks.iter().map(|m| m.estimated_seconds).sum();
    assert_eq!(plan.estimated_seconds, total);
}

#[test]
fn a_scalar_mask_is_made_for_an_eye_no_sharper_than_standard_4ks() {
    assert_eq!(SCALAR_EYE_PPD, fsot::core::display::preset_ppd("standard_4k").unwrap());
    let groups = "[[group]]\nname = \"pick\"\ndims = 1\n[[group]]\nname = \"lens\"\ndims = 2\n\
                  [[group]]\nname = \"vol\"\ndims = 3\nshare = false\n";
    // The eye each mask is made for: pixels per degree, or a Gaussian's sigma.
    let eyes = |display: &str| {
        let plan = Plan::new(&scene(display, groups), &model()).unwrap();
        plan.masks
            .iter()
            .map(|m| {
                assert_eq!(m.kernel, m.spec.describe());
                let eye = match m.spec.spatial {
                    Spatial::Display { ppd } => format!("ppd {ppd}"),
                    Spatial::Gaussian { sigma } => format!("sigma {sigma}"),
                };
                (m.file.clone(), eye)
            })
            .collect::<Vec<_>>()
    };
    let want = |e: [&str; 4]| {
        ["pick.exr", "lens.exr", "vol-0.exr", "vol-2.exr"]
            .iter()
            .map(|f| f.to_string())
            .zip(e.map(String::from))
            .collect::<Vec<_>>()
    };
    // standard_fhd (the default, 37.84 pixels per degree): the scalar masks take
    // the wider eye, the 2-D masks the display's own.
    assert_eq!(eyes("taa_alpha = 0.1"), want(["ppd 75.4", "ppd 37.84", "ppd 37.84", "ppd 75.4"]));
    assert_eq!(eyes("name = \"standard_4k\""), want(["ppd 75.4"; 4]));
    assert_eq!(eyes("ppd = 120"), want(["ppd 120"; 4]), "an eye wider still is kept");
    assert_eq!(eyes("sigma = 1.2"), want(["sigma 1.2"; 4]), "a Gaussian the scene gives is kept");
    // The reason says so where it applies, and plan.json's parts name each kernel.
    let plan = Plan::new(&scene("taa_alpha = 0.1", groups), &model()).unwrap();
    let reason = |name: &str| plan.groups.iter().find(|g| g.name == name).unwrap().reason.clone();
    assert!(reason("pick").contains("75.4 pixels per degree"), "{}", reason("pick"));
    assert!(reason("vol").contains("75.4 pixels per degree"), "{}", reason("vol"));
    assert!(!reason("lens").contains("pixels per degree"), "{}", reason("lens"));
    assert!(
        reason("vol").starts_with("a 3-D decision, read in pairs as renderers consume it: a 2-D mask per pair and a scalar mask of its own (share = false)"),
        "{}",
        reason("vol")
    );
    let vol = plan.groups.iter().find(|g| g.name == "vol").unwrap();
    let kernels: Vec<&str> = vol.parts.iter().map(|p| p.kernel.as_deref().unwrap()).collect();
    assert!(kernels[0].contains("ppd = 37.84") && kernels[1].contains("ppd = 75.4"), "{kernels:?}");
}

#[test]
fn a_decision_reads_an_earlier_mask_of_its_dimension_at_its_own_offset_and_shift() {
    let groups = "[[group]]\nname = \"light\"\ndims = 2\n[[group]]\nname = \"bsdf\"\ndims = 2\n\
                  [[group]]\nname = \"quad\"\ndims = 4\n[[group]]\nname = \"own\"\ndims = 2\nshare = false\n";
    let plan = Plan::new(&scene("taa_alpha = 0.1", groups), &model()).unwrap();
    let files: Vec<&str> = plan.masks.iter().map(|m| m.file.as_str()).collect();
    assert_eq!(files, ["light.exr", "own.exr"], "share = false: masks of their own");
    // Groups of another spp cannot share a plan block, which holds one spp.
    let mixed =
        format!("[display]\ntaa_alpha = 0.1\n{groups}[[group]]\nname = \"many\"\ndims = 2\nspp = 4\n");
    let err = Scene::parse(&mixed, "mixed").map(|_| ()).unwrap_err().to_string();
    assert!(err.contains("share one spp"), "{err}");
    let reads: Vec<&fsot::scene::plan::Part> = plan.groups.iter().flat_map(|g| &g.parts).collect();
    let shared: Vec<&&fsot::scene::plan::Part> = reads.iter().filter(|p| p.mask == "light.exr").collect();
    assert_eq!(shared.len(), 4, "light, bsdf and quad's two pairs");
    assert_eq!(
        (shared[0].offset, shared[0].shift.as_slice(), &shared[0].shares),
        ([0; 3], &[0.0f32, 0.0][..], &None)
    );
    for (k, p) in shared.iter().enumerate().skip(1) {
        assert_eq!(p.offset, share_offset(k as u32, [128, 128, 64]));
        assert_eq!(p.shift, share_shift(k as u32, 2));
        assert_eq!(p.shares.as_deref(), Some("light"));
    }
    // Readers spread over the tile: no two at the same offset or shift.
    for i in 0..shared.len() {
        for j in 0..i {
            assert_ne!(shared[i].offset, shared[j].offset);
            assert_ne!(shared[i].shift, shared[j].shift);
        }
    }
    assert!(plan.groups[1].reason.contains("sharing light.exr"), "{}", plan.groups[1].reason);
    assert!(plan.groups[3].reason.contains("share = false"), "{}", plan.groups[3].reason);
}

#[test]
fn a_scene_may_ask_for_a_scalar_mask_per_dimension_read_at_offsets_of_one_mask() {
    let groups = "[[group]]\nname = \"light\"\ndims = 2\n[[group]]\nname = \"pick\"\ndims = 1\n";
    let text = format!("[display]\ntaa_alpha = 0.1\n[tile]\nreading = \"scalar\"\n{groups}");
    let plan = Plan::new(&Scene::parse(&text, "scalar").unwrap(), &model()).unwrap();
    assert_eq!(plan.reading, "scalar");
    let files: Vec<&str> = plan.masks.iter().map(|m| m.file.as_str()).collect();
    assert_eq!(files, ["light-0.exr"], "one scalar mask for every dimension");
    let reads: Vec<(usize, usize, [u32; 3])> =
        plan.groups.iter().flat_map(|g| g.parts.iter().map(|p| (p.first, p.dims, p.offset))).collect();
    let tile = [128, 128, 64];
    assert_eq!(reads, [(0, 1, [0; 3]), (1, 1, share_offset(1, tile)), (0, 1, share_offset(2, tile))]);
    // plan.json: each group's iterations count the one mask it reads once; a
    // group that owns none spent no seconds on it (0, not -0).
    let made = [fsot::scene::plan::Made { file: "light-0.exr".into(), iterations: 100, seconds: 2.0 }];
    let doc: serde_json::Value = serde_json::from_str(&plan.document(&made).unwrap()).unwrap();
    let group = |k: usize| (doc["groups"][k]["iterations"].as_u64(), doc["groups"][k]["seconds"].as_f64());
    assert_eq!((group(0), group(1)), ((Some(100), Some(2.0)), (Some(100), Some(0.0))));
    assert!(doc["groups"][1]["seconds"].as_f64().unwrap().is_sign_positive());
    // The default: masks of pairs.
    let plan = Plan::new(&scene("taa_alpha = 0.1", groups), &model()).unwrap();
    assert_eq!(plan.reading, "vector");
    assert_eq!(plan.masks.iter().map(|m| m.dims).collect::<Vec<_>>(), [2, 1]);
    assert!(Scene::parse(&format!("[tile]\nreading = \"both\"\n{groups}"), "bad")
        .unwrap_err()
        .contains("line 2"));
}

#[test]
fn shared_offsets_and_shifts_are_the_r_sequences() {
    // R_1 is the golden ratio's; R3's first point from x^4 = x + 1.
    assert!((share_shift(1, 1)[0] - 0.618_034).abs() < 1e-6);
    assert!((share_shift(2, 1)[0] - 0.236_068).abs() < 1e-6);
    let r2 = share_shift(1, 2);
    assert!((r2[0] - 0.754_878).abs() < 1e-6 && (r2[1] - 0.569_840).abs() < 1e-6, "{r2:?}");
    // 1 / 1.2207440846 = 0.81917, its square 0.67104, cube 0.54970.
    assert_eq!(share_offset(1, [100, 100, 100]), [81, 67, 54]);
    assert!(share_offset(1000, [64, 64, 32]).iter().zip([64, 64, 32]).all(|(o, n)| *o < n));
}

#[test]
fn a_plan_makes_its_masks_and_a_plan_file_a_renderer_can_read() {
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n\
                [[group]]\nname = \"pick\"\ndims = 1\n[[group]]\nname = \"lens\"\ndims = 2\n\
                [[group]]\nname = \"deep\"\ndims = 2\nvisible = false\n";
    let scene = Scene::parse(text, "small").unwrap();
    let options = RunOptions::default().backend(BackendChoice::Cpu);
    let plan = Plan::new(&scene, &CostModel::calibrate(&options).unwrap()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut done = Vec::new();
    let outcome = plan
        .execute(dir.path(), &options, 50, false, &CancelFlag::new(), &mut |e| {
            if let PlanEvent::Done { file, iterations, .. } = e {
                done.push((file.to_string(), iterations))
            }
        })
        .unwrap();
    assert_eq!(outcome, Outcome::Reached);
    assert_eq!(done.iter().map(|d| d.0.as_str()).collect::<Vec<_>>(), ["pick.exr", "lens.exr"]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("plan.json")).unwrap()).unwrap();
    assert_eq!(json["tile"], serde_json::json!([8, 8, 4]));
    let groups = json["groups"].as_array().unwrap();
    assert_eq!(groups.len(), 3);
    for (g, (name, dims)) in groups.iter().zip([("pick", 1), ("lens", 2), ("deep", 2)]) {
        assert_eq!(g["name"], name);
        assert_eq!(g["dims"], dims);
        assert_eq!(g["mask"], format!("{name}.exr"));
        assert_eq!(g["offset"], serde_json::json!([0, 0, 0]));
        assert_eq!(g["shift"].as_array().unwrap().len(), dims);
        let mask = fsot::io::exr::read(&dir.path().join(format!("{name}.exr"))).unwrap();
        assert_eq!((mask.tile.dims, mask.tile.width, mask.tile.frames), (dims, 8, 4));
        if name == "deep" {
            assert_eq!(g["skipped"], "not visible: white noise");
            assert!(g["iterations"].is_null() && g["kernel"].is_null());
            assert_eq!(mask.meta("method"), Some("white"));
        } else {
            assert!(g["skipped"].is_null());
            assert_eq!(mask.meta("start"), Some("animated"), "{name}: a plan's masks start animated");
            let iterations = g["iterations"].as_u64().unwrap();
            assert_eq!(done.iter().find(|d| d.0 == format!("{name}.exr")).unwrap().1 as u64, iterations);
            assert!(iterations > 0 && iterations < 10_000, "stopped by the rule: {iterations}");
            // Each mask is made for its own kernel (a scalar mask's eye is wider).
            let planned = plan.masks.iter().find(|m| m.file == format!("{name}.exr")).unwrap();
            assert_eq!(mask.meta("kernel"), Some(planned.kernel.as_str()));
            assert_eq!(g["kernel"], planned.kernel.as_str());
            let s = score(&mask, planned.spec, 4096);
            // Measured 0.143 (pick, for its wider eye) and 0.312 (lens); about 13-15% margins.
            let bound = if name == "pick" { 0.162 } else { 0.36 };
            assert!(s.ratio() < bound, "{name}: {} x white", s.ratio());
        }
    }
    assert!(std::fs::read_dir(dir.path()).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .ends_with(".ckpt")));
    // Each part's `layer`: its mask's first layer when the masks are stacked in
    // one array image in the order the parts first read them, T = 4 layers each;
    // the plan block the include reads (32 bytes of head, then 32 a part: the
    // base layer is the fourth u32) says the same.
    let layers: Vec<u64> = groups.iter().map(|g| g["parts"][0]["layer"].as_u64().unwrap()).collect();
    assert_eq!(layers, [0, 4, 8]);
    let read = fsot::SamplerPlan::read(dir.path()).unwrap();
    let block = read.plan_block().unwrap();
    let base = |k: usize| u32::from_le_bytes(block[44 + 32 * k..48 + 32 * k].try_into().unwrap()) as u64;
    assert_eq!((0..3).map(base).collect::<Vec<_>>(), layers);
    // Made in memory instead (no file, no checkpoint), the plan is the folder's:
    // the same block, and every texel the same float.
    let mut made_events = Vec::new();
    let made = fsot::SamplerPlan::make(&plan, options.clone(), &CancelFlag::new(), &mut |e| {
        if let PlanEvent::Done { file, iterations, .. } = e {
            made_events.push((file.to_string(), iterations))
        }
    })
    .unwrap()
    .unwrap();
    assert_eq!(made_events, done);
    assert_eq!(made.plan_block().unwrap(), block);
    let exact = fsot::TexelFormat::R32G32B32A32Sfloat;
    assert_eq!(made.texels(exact).unwrap(), read.texels(exact).unwrap());
    let checkpoint = fsot::Checkpointing { path: dir.path().join("c"), every: 5, resume: false };
    let checkpointed = options.checkpoint(Some(checkpoint));
    let err = fsot::SamplerPlan::make(&plan, checkpointed, &CancelFlag::new(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("no checkpoints"), "{err}");
}

#[test]
fn a_plan_set_out_of_range_by_hand_is_refused_before_any_file_is_written() {
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n\
                [[group]]\nname = \"pick\"\ndims = 1\n[[group]]\nname = \"lens\"\ndims = 2\n";
    let good = || Plan::new(&Scene::parse(text, "small").unwrap(), &model()).unwrap();
    assert!(good().check().is_ok());
    type SetByHand = fn(&mut Plan);
    let cases: [(&str, SetByHand); 17] = [
        ("no masks", |p| p.masks.clear()),
        ("no groups", |p| p.groups.clear()),
        ("a group that reads no mask", |p| p.groups[0].parts.clear()),
        ("a mask no group reads", |p| {
            let extra = PlannedMask { file: "extra.exr".into(), ..p.masks[1].clone() };
            p.masks.push(extra)
        }),
        ("a mask file in another folder", |p| p.masks[0].file = "../pick.exr".into()),
        ("a hidden mask file", |p| p.masks[0].file = ".pick.exr".into()),
        ("a mask file that is not EXR", |p| p.masks[0].file = "pick.ktx2".into()),
        ("two masks of one file", |p| p.masks[1].file = p.masks[0].file.clone()),
        ("a tile 0 wide", |p| p.tile[0] = 0),
        ("a mask of d = 9", |p| p.masks[0].dims = 9),
        ("a kernel of NaN sigma", |p| p.masks[0].spec.spatial = Spatial::Gaussian { sigma: f64::NAN }),
        ("a part reading no mask of the plan", |p| p.groups[0].parts[0].mask = "other.exr".into()),
        ("a part of a NaN shift", |p| p.groups[1].parts[0].shift[1] = f32::NAN),
        ("a part of a negative shift", |p| p.groups[1].parts[0].shift[1] = -1e-9),
        ("a part of a shift of 1", |p| p.groups[1].parts[0].shift[0] = 1.0),
        ("a mask file on a drive", |p| p.masks[0].file = "C:pick.exr".into()),
        ("a NaN budget", |p| p.budget = Some(f64::NAN)),
    ];
    let options = RunOptions::default().backend(BackendChoice::Cpu);
    for (what, set) in cases {
        let mut plan = good();
        set(&mut plan);
        assert!(plan.check().is_err(), "{what}: check");
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("plan");
        let result = plan.execute(&out, &options, 50, false, &CancelFlag::new(), &mut |_| {});
        assert!(result.is_err(), "{what}: executed");
        assert!(!out.exists(), "{what}: the folder was made");
    }
    // More parts than a plan block holds: 700 decisions of 3 dimensions read per dimension.
    let many: String = (0..700).map(|k| format!("[[group]]\nname = \"g{k}\"\ndims = 3\n")).collect();
    let scene =
        Scene::parse(&format!("[tile]\nsize = \"8x8x4\"\nreading = \"scalar\"\n{many}"), "many").unwrap();
    let err = Plan::new(&scene, &model()).unwrap_err();
    assert!(err.to_string().contains("2100 parts"), "{err}");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("plan");
    assert!(good().execute(&out, &options, 0, false, &CancelFlag::new(), &mut |_| {}).is_err(), "every 0");
    assert!(!out.exists(), "every 0: the folder was made");
}

#[test]
fn a_cancelled_plan_resumes_and_keeps_what_it_made() {
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n\
                [[group]]\nname = \"a\"\ndims = 1\n[[group]]\nname = \"b\"\ndims = 2\n";
    let scene = Scene::parse(text, "resumable").unwrap();
    let options = RunOptions::default().backend(BackendChoice::Cpu);
    let plan = Plan::new(&scene, &model()).unwrap();
    let straight = tempfile::tempdir().unwrap();
    plan.execute(straight.path(), &options, 10, false, &CancelFlag::new(), &mut |_| {}).unwrap();

    let dir = tempfile::tempdir().unwrap();
    // A plan.json left by an earlier plan in the folder must not describe this
    // plan's masks while they are made.
    std::fs::copy(straight.path().join("plan.json"), dir.path().join("plan.json")).unwrap();
    let cancel = CancelFlag::new();
    let outcome = plan
        .execute(dir.path(), &options, 10, false, &cancel, &mut |e| {
            if let PlanEvent::Run {
                index: 1,
                event: fsot::optimize::run::Event::Progress { iteration: 25, .. },
            } = e
            {
                cancel.cancel()
            }
        })
        .unwrap();
    assert!(matches!(outcome, Outcome::Cancelled { iteration: 25, .. }), "{outcome:?}");
    assert!(dir.path().join("a.exr").exists() && !dir.path().join("b.exr").exists());
    assert!(
        !dir.path().join("plan.json").exists(),
        "plan.json only once every mask is made; the earlier one gone"
    );
    let made_a = std::fs::read(dir.path().join("a.exr")).unwrap();
    let mut started = Vec::new();
    plan.execute(dir.path(), &options, 10, true, &CancelFlag::new(), &mut |e| {
        if let PlanEvent::Start { file, iteration, .. } = e {
            started.push((file.to_string(), iteration))
        }
    })
    .unwrap();
    assert_eq!(started, [("b.exr".to_string(), 25)], "a kept; b from the checkpoint written when cancelled");
    assert_eq!(std::fs::read(dir.path().join("a.exr")).unwrap(), made_a);
    for name in ["a.exr", "b.exr"] {
        let x = fsot::io::exr::read(&dir.path().join(name)).unwrap();
        let y = fsot::io::exr::read(&straight.path().join(name)).unwrap();
        let bits = |m: &fsot::Mask| m.samples.iter().map(|v| v.to_bits()).collect::<Vec<u32>>();
        assert_eq!(bits(&x), bits(&y), "{name} differs");
    }
}

#[test]
fn a_plan_remakes_a_mask_of_its_seed_and_kernel_that_started_from_white_noise() {
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n[[group]]\nname = \"a\"\ndims = 1\n";
    let scene = Scene::parse(text, "restart").unwrap();
    let options = RunOptions::default().backend(BackendChoice::Cpu);
    let plan = Plan::new(&scene, &model()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut settings = plan.settings(&plan.masks[0]);
    settings.start = fsot::Start::White;
    settings.iterations = 10;
    let white_start =
        fsot::optimize::run::optimize(plan.tile(&plan.masks[0]).unwrap(), settings, None).unwrap();
    fsot::io::exr::write(
        &white_start,
        fsot::io::atomic::AtomicFile::create(&dir.path().join("a.exr")).unwrap(),
    )
    .unwrap();
    let mut started = Vec::new();
    plan.execute(dir.path(), &options, 10, true, &CancelFlag::new(), &mut |e| {
        if let PlanEvent::Start { file, .. } = e {
            started.push(file.to_string())
        }
    })
    .unwrap();
    assert_eq!(started, ["a.exr"], "the white-noise start was taken for the plan's mask");
    let made = fsot::io::exr::read(&dir.path().join("a.exr")).unwrap();
    assert_eq!(made.meta("start"), Some("animated"));
}

#[test]
fn a_scene_may_give_a_time_budget_as_a_time_or_a_number_of_seconds() {
    let budget = |plan: &str| Scene::parse(&format!("{plan}\n{ONE}"), "t").map(|s| s.budget);
    assert_eq!(budget(""), Ok(None));
    assert_eq!(budget("[plan]\nbudget = \"10s\""), Ok(Some(10.0)));
    assert_eq!(budget("[plan]\nbudget = \"500ms\""), Ok(Some(0.5)));
    assert_eq!(budget("[plan]\nbudget = 3"), Ok(Some(3.0)));
    assert_eq!(budget("[plan]\nbudget = 2.5"), Ok(Some(2.5)));
    for (bad, says) in [
        ("[plan]\nbudget = \"soon\"", "line 2: budget must be a time above zero"),
        ("[plan]\nbudget = 0", "line 2: budget must be a time above zero"),
        ("[plan]\nbudget = true", "line 2: budget must be a time above zero"),
        ("[plan]\ndeadline = 3", "unknown field `deadline`"),
    ] {
        let e = budget(bad).expect_err(bad);
        assert!(e.contains(says), "{bad}: {e}");
    }
}

#[test]
fn under_a_budget_each_mask_gets_a_share_of_it_in_proportion_to_its_work_per_iteration() {
    let groups = "[plan]\nbudget = 12\n[[group]]\nname = \"pick\"\ndims = 1\nspp = 4\n\
                  [[group]]\nname = \"lens\"\ndims = 2\nspp = 4\n[[group]]\nname = \"deep\"\ndims = 2\nspp = 4\n\
                  visible = false\n";
    let plan = Plan::new(&scene("taa_alpha = 0.1", groups), &model()).unwrap();
    assert_eq!(plan.budget, Some(12.0));
    let m = |f: &str| plan.masks.iter().find(|m| m.file == f).unwrap();
    assert_eq!((m("deep.exr").estimated_seconds, m("deep.exr").estimated_iterations), (0.0, 0));
    // The scaling suite's factors: d = 1 costs 0.52 of d = 2 per point, spp 4
    // 0.60 of spp 1 per point, and spp 4 is four times the points.
    let (pick, lens) = (0.52 * 0.60 * 4.0, 1.0 * 0.60 * 4.0);
    let expected = 12.0 * pick / (pick + lens);
    assert!((m("pick.exr").estimated_seconds - expected).abs() < 1e-9, "{}", m("pick.exr").estimated_seconds);
    assert!((plan.estimated_seconds - 12.0).abs() < 1e-9);
    // So each gets about the same number of iterations: the budget over the
    // work of one iteration of every mask.
    let per_pick = 1e-6 * (128 * 128 * 64) as f64 * pick;
    let iterations = (12.0 / (per_pick / pick * (pick + lens))) as u32;
    for f in ["pick.exr", "lens.exr"] {
        assert!(m(f).estimated_iterations.abs_diff(iterations) <= 1, "{f}: {}", m(f).estimated_iterations);
    }
}

#[test]
fn a_plan_under_a_budget_makes_every_mask_within_it_one_after_the_other_on_the_cpu() {
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"16x16x8\"\n[plan]\nbudget = 1.5\n\
                [[group]]\nname = \"pick\"\ndims = 1\n[[group]]\nname = \"lens\"\ndims = 2\n";
    let scene = Scene::parse(text, "budgeted").unwrap();
    let began = std::time::Instant::now();
    let options = RunOptions::default().backend(BackendChoice::Cpu).budget_from(began);
    let plan = Plan::new(&scene, &CostModel::calibrate(&options).unwrap()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (mut order, mut slowest) = (Vec::new(), 0.0f64);
    let mut last = std::time::Instant::now();
    plan.execute(dir.path(), &options, 10, false, &CancelFlag::new(), &mut |e| match e {
        PlanEvent::Start { file, .. } => order.push(format!("start {file}")),
        PlanEvent::Done { file, iterations, .. } => order.push(format!("done {file} {}", iterations > 0)),
        PlanEvent::Run { event: fsot::optimize::run::Event::Progress { .. }, .. } => {
            slowest = slowest.max(last.elapsed().as_secs_f64());
            last = std::time::Instant::now();
        }
        _ => {}
    })
    .unwrap();
    let seconds = began.elapsed().as_secs_f64();
    assert_eq!(order, ["start pick.exr", "done pick.exr true", "start lens.exr", "done lens.exr true"]);
    assert!(seconds <= 1.5 + slowest + 0.3, "{seconds} s for a budget of 1.5 s ({slowest} s a step)");
    assert!(seconds >= 0.75, "{seconds} s: the budget was not used");
    for (name, planned) in ["pick.exr", "lens.exr"].iter().zip(&plan.masks) {
        let mask = fsot::io::exr::read(&dir.path().join(name)).unwrap();
        assert!(mask.meta("budget_seconds").is_some(), "{name}: {:?}", mask.meta);
        assert_eq!(planned.file, *name);
        let s = score(&mask, planned.spec, 4096);
        assert!(s.ratio() < 0.6, "{name}: {} x white", s.ratio());
    }
    assert!(dir.path().join("plan.json").exists());
    assert!(std::fs::read_dir(dir.path()).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .ends_with(".ckpt")));
}

#[test]
fn masks_given_for_a_plan_in_memory_are_checked_against_its_tiles() {
    let text = format!("[tile]\nsize = \"8x8x4\"\n{ONE}");
    let plan = Plan::new(&Scene::parse(&text, "t").unwrap(), &model()).unwrap();
    let tile = plan.tile(&plan.masks[0]).unwrap();
    let good = vec![fsot::Mask::white(tile, 1)];
    assert!(fsot::render::sampler::SamplerPlan::from_plan(&plan, good).is_ok());
    let other = vec![fsot::Mask::white(Tile::new(8, 8, 1, 1, 4).unwrap(), 1)];
    let e = fsot::render::sampler::SamplerPlan::from_plan(&plan, other).err().unwrap().to_string();
    assert!(e.contains("the plan's is 8x8x4"), "{e}");
    // A plan set by hand that `Plan::check` refuses (a mask named twice).
    let mut twice = plan.clone();
    twice.masks.push(twice.masks[0].clone());
    let masks = vec![fsot::Mask::white(tile, 1), fsot::Mask::white(tile, 2)];
    assert!(fsot::render::sampler::SamplerPlan::from_plan(&twice, masks).is_err());
}

#[test]
fn masks_whose_names_differ_by_a_second_exr_keep_checkpoints_of_their_own() {
    let dir = std::path::Path::new("out");
    let (a, b) = (
        fsot::scene::plan::checkpoint_path(dir, "a.exr"),
        fsot::scene::plan::checkpoint_path(dir, "a.exr.exr"),
    );
    assert_eq!(a, dir.join(".a.ckpt"));
    assert_ne!(a, b);
}

#[test]
fn an_invisible_decision_of_more_than_four_dimensions_reads_white_masks_a_renderer_can_bind() {
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n[[group]]\nname = \"pick\"\ndims = 1\n\
                [[group]]\nname = \"deep\"\ndims = 6\nvisible = false\n";
    let plan = Plan::new(&Scene::parse(text, "deep").unwrap(), &model()).unwrap();
    let white: Vec<(&str, usize)> =
        plan.masks.iter().filter(|m| m.white).map(|m| (m.file.as_str(), m.dims)).collect();
    assert_eq!(white, [("deep-0.exr", 4), ("deep-4.exr", 2)], "a texel holds four dimensions");
    let dir = tempfile::tempdir().unwrap();
    let options = RunOptions::default().backend(BackendChoice::Cpu);
    plan.execute(dir.path(), &options, 50, false, &CancelFlag::new(), &mut |_| {}).unwrap();
    let sampler = fsot::SamplerPlan::read(dir.path()).unwrap();
    let parts: Vec<usize> = sampler.parts().iter().map(|p| p.dims).collect();
    assert_eq!(parts, [1, 4, 2]);
}

#[test]
fn a_plan_that_fails_or_stops_before_its_first_mask_keeps_the_folder_s_plan_json_and_a_linked_one_is_replaced_through_the_link(
) {
    let text = "[display]\ntaa_alpha = 0.1\n[tile]\nsize = \"8x8x4\"\n\
                [[group]]\nname = \"a\"\ndims = 1\n[[group]]\nname = \"b\"\ndims = 2\n";
    let plan = Plan::new(&Scene::parse(text, "kept").unwrap(), &model()).unwrap();
    let options = RunOptions::default().backend(BackendChoice::Cpu);
    // A folder where b.exr should go: refused while the files are reserved.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("plan.json"), b"an earlier plan").unwrap();
    std::fs::create_dir(dir.path().join("b.exr")).unwrap();
    assert!(plan.execute(dir.path(), &options, 10, false, &CancelFlag::new(), &mut |_| {}).is_err());
    assert_eq!(std::fs::read(dir.path().join("plan.json")).unwrap(), b"an earlier plan");
    assert!(!dir.path().join("a.exr").exists(), "no mask written");
    // Stopped before its first mask is written: the folder as it was.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("plan.json"), b"an earlier plan").unwrap();
    std::fs::write(dir.path().join("a.exr"), b"an earlier mask").unwrap();
    let cancel = CancelFlag::new();
    let outcome = plan
        .execute(dir.path(), &options, 10, false, &cancel, &mut |e| {
            if let PlanEvent::Run {
                event: fsot::optimize::run::Event::Progress { iteration: 5, .. }, ..
            } = e
            {
                cancel.cancel()
            }
        })
        .unwrap();
    assert!(matches!(outcome, Outcome::Cancelled { .. }), "{outcome:?}");
    assert_eq!(std::fs::read(dir.path().join("plan.json")).unwrap(), b"an earlier plan");
    assert_eq!(std::fs::read(dir.path().join("a.exr")).unwrap(), b"an earlier mask");
    #[cfg(unix)]
    {
        let dir = tempfile::tempdir().unwrap();
        let (out, kept) = (dir.path().join("out"), dir.path().join("kept.json"));
        std::fs::create_dir(&out).unwrap();
        std::fs::write(&kept, b"an earlier plan").unwrap();
        std::os::unix::fs::symlink(&kept, out.join("plan.json")).unwrap();
        plan.execute(&out, &options, 10, false, &CancelFlag::new(), &mut |_| {}).unwrap();
        assert!(std::fs::symlink_metadata(out.join("plan.json")).unwrap().file_type().is_symlink());
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&kept).unwrap()).unwrap();
        assert_eq!(json["scene"], "kept");
    }
}

#[test]
fn each_part_in_plan_json_names_the_layer_its_mask_starts_at_in_the_stacked_image() {
    // Two samples a pixel, a 3-D decision split over two masks, a decision that
    // shares an earlier one's mask, and white noise: the layers plan.json gives
    // are the plan block's base layers (the include's), part by part.
    let groups =
        "[[group]]\nname = \"light\"\ndims = 3\nspp = 2\n[[group]]\nname = \"bounce\"\ndims = 2\nspp = 2\n\
                  [[group]]\nname = \"deep\"\ndims = 2\nspp = 2\nvisible = false\n";
    let plan = Plan::new(&scene("taa_alpha = 0.1", groups), &model()).unwrap();
    let parts: Vec<&fsot::scene::plan::Part> = plan.groups.iter().flat_map(|g| &g.parts).collect();
    assert!(plan.groups[0].parts.len() == 2, "a split decision: {:?}", plan.groups[0].parts);
    assert!(parts.iter().any(|p| p.shares.is_some()), "a shared mask: {parts:?}");
    let doc: serde_json::Value = serde_json::from_str(&plan.document(&[]).unwrap()).unwrap();
    let layers: Vec<u64> = doc["groups"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|g| g["parts"].as_array().unwrap().iter().map(|p| p["layer"].as_u64().unwrap()))
        .collect();
    let masks = plan.masks.iter().map(|m| fsot::Mask::white(plan.tile(m).unwrap(), 1)).collect();
    let block = fsot::SamplerPlan::from_plan(&plan, masks).unwrap().plan_block_for(parts.len()).unwrap();
    let base = |k: usize| u32::from_le_bytes(block[44 + 32 * k..48 + 32 * k].try_into().unwrap()) as u64;
    assert_eq!(layers, (0..parts.len()).map(base).collect::<Vec<_>>());
    let t = plan.tile[2] as u64;
    assert!(layers.iter().all(|l| l % (2 * t) == 0), "T x spp layers a mask: {layers:?}");
    assert!(layers.iter().max().unwrap() > &0);
}
