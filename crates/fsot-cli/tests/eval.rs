//! The evaluation (`fsot eval`): scenes rendered with each method's mask,
//! measured with and without TAA. Tiny sizes here; the figures come from the
//! command itself (RESULTS.md).

use fsot::core::tile::Tile;
use fsot_cli::eval::render::Shot;
use fsot_cli::eval::scenes::Scene;
use fsot_cli::eval::suite::{run_eval, to_json, to_markdown, EvalSize, METHODS};

/// The eye of the evaluation's display, which `fsot-planned` plans for.
fn judged_on() -> fsot::core::kernel::Spatial {
    fsot::core::kernel::Spatial::Display {
        ppd: fsot::core::display::preset_ppd(fsot_cli::eval::jod::DISPLAY).unwrap(),
    }
}

fn tiny() -> EvalSize {
    EvalSize {
        tile: Tile::new(16, 16, 8, 1, 2).unwrap(),
        iterations: 40,
        passes: 2,
        shot: Shot { image: 40, frames: 24 },
        warmup: 16,
        seeds: 2,
        renders: 1,
        reference_samples: 16,
        planned: false,
        planned_without_taa: true,
        planned_unshared: true,
        planned_masks: 2,
        displays: vec![fsot_cli::eval::jod::DISPLAY],
        plan_tile: true,
        grey: fsot_cli::eval::jod::Grey::Rgb,
        flip: false,
        anatomy: false,
        judged: [true, true],
    }
}

#[test]
fn every_scene_and_method_gets_a_record_with_and_without_taa() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = [Scene::LightPick, Scene::DefocusMotion];
    let pictures = dir.path().join("pictures");
    let records =
        run_eval(&tiny(), &[2.1], &scenes, dir.path(), Some(&pictures), &[], Default::default(), |_| {})
            .unwrap();
    assert_eq!(records.len(), scenes.len() * METHODS.len() * 2);
    for r in &records {
        assert!(r.prelmse.is_finite() && r.prelmse > 0.0, "{r:?}");
        assert!(r.relmse.is_finite() && r.relmse > 0.0, "{r:?}");
        // The eye averages noise away: what it sees is less than the raw error,
        // by the column's sigma and by the display's eye.
        assert!(r.prelmse < r.relmse, "{r:?}");
        assert!(r.prelmse_display > 0.0 && r.prelmse_display < r.relmse, "{r:?}");
        // Two seeds each: finite intervals; ColorVideoVDP sees a difference.
        assert_eq!(r.seeds, 2, "{r:?}");
        assert!(r.prelmse_ci95.is_finite() && r.relmse_ci95.is_finite() && r.jod_ci95.is_finite(), "{r:?}");
        assert!(r.jod < 10.0 && r.jod > -5.0, "{r:?}");
        // Each placement's values, whose mean is the record's.
        let p = &r.placements;
        for (values, mean) in [(&p.prelmse, r.prelmse), (&p.relmse, r.relmse), (&p.jod, r.jod)] {
            assert_eq!(values.len(), 2, "{r:?}");
            assert!((values.iter().sum::<f64>() / 2.0 - mean).abs() <= 1e-12 * mean.abs(), "{r:?}");
        }
        assert_eq!(p.prelmse_display.len(), 2, "{r:?}");
    }
    // TAA averages 1-spp noise over frames: far less error than without.
    for scene in ["light-pick", "defocus-motion"] {
        let get =
            |taa| records.iter().find(|r| r.scene == scene && r.method == "white" && r.taa == taa).unwrap();
        assert!(get(true).relmse < 0.5 * get(false).relmse, "{scene}");
    }
    let json = to_json(&records).unwrap();
    assert_eq!(json.matches("\"scene\"").count(), records.len());
    for key in [
        "\"method\"",
        "\"taa\"",
        "\"sigma\"",
        "\"jod_ci95\"",
        "\"prelmse_ci95\"",
        "\"prelmse_display_ci95\"",
        "\"seeds\"",
    ] {
        assert_eq!(json.matches(key).count(), records.len(), "{key}");
    }
    // The means, and again in each record's placements.
    for key in ["\"prelmse\"", "\"relmse\"", "\"jod\"", "\"prelmse_display\""] {
        assert_eq!(json.matches(key).count(), 2 * records.len(), "{key}");
    }
    // Four picture strips per scene, each a PNG as wide as the reference (if
    // any) and eight methods.
    for scene in ["light-pick", "defocus-motion"] {
        for (kind, cells) in [("frames", 9), ("errors", 8), ("spectra-xy", 8), ("spectra-xt", 8)] {
            let path = pictures.join(format!("{scene}-{kind}.png"));
            let decoder = png::Decoder::new(std::fs::File::open(&path).unwrap());
            let info = decoder.read_info().unwrap().info().clone();
            let cell = (info.width as usize + 2) / cells - 2;
            assert_eq!((cell + 2) * cells - 2, info.width as usize, "{path:?}");
        }
    }
    let md = to_markdown(&records);
    assert!(md.contains("| light-pick |") && md.contains("with TAA") && md.contains("without TAA"));
    assert!(md.contains("### JOD on standard_4k, sigma 2.1, with TAA") && md.contains(" +- "));
    assert!(md.contains("### pRelMSE on standard_4k, the display's eye, without TAA (masks of sigma 2.1;"));
    // A second run reads the masks from the cache: white noise's cached masks
    // replaced by a constant (every pixel takes the same sample) change white's
    // figures alone; every other method's come out the same.
    let mut replaced = 0;
    for entry in std::fs::read_dir(dir.path()).unwrap() {
        let path = entry.unwrap().path();
        if path.file_name().unwrap().to_string_lossy().starts_with("mask-white-") {
            let mut mask = fsot::io::exr::read(&path).unwrap();
            mask.samples.iter_mut().for_each(|v| *v = 0.5);
            fsot::io::exr::write(&mask, fsot::io::atomic::AtomicFile::create(&path).unwrap()).unwrap();
            replaced += 1;
        }
    }
    assert_eq!(replaced, 2, "white noise's two seeds are cached");
    let again =
        run_eval(&tiny(), &[2.1], &scenes, dir.path(), None, &[], Default::default(), |_| {}).unwrap();
    assert_eq!(records.len(), again.len());
    for (before, after) in records.iter().zip(&again) {
        if before.method == "white" {
            assert_ne!(before.relmse, after.relmse, "{before:?}");
        } else {
            assert_eq!(before, after);
        }
    }
}

#[test]
fn a_blue_noise_mask_beats_white_noise_in_every_scene_under_taa() {
    // Even tiny, briefly optimised masks: fsot's spatial mask against white
    // noise, every scene, TAA on.
    let dir = tempfile::tempdir().unwrap();
    let mut size = tiny();
    size.iterations = 100;
    let records = run_eval(
        &size,
        &[2.1],
        &fsot_cli::eval::scenes::SCENES,
        dir.path(),
        None,
        &[],
        Default::default(),
        |_| {},
    )
    .unwrap();
    // Measured ratios 0.208, 0.250, 0.330, 0.481, 0.592, 0.366 (scene order);
    // each bound 15% above.
    let bounds = [0.24, 0.29, 0.38, 0.56, 0.69, 0.43];
    let ratios: Vec<(&str, f64)> = fsot_cli::eval::scenes::SCENES
        .into_iter()
        .map(|scene| {
            let get = |m: &str| {
                records.iter().find(|r| r.scene == scene.name() && r.method == m && r.taa).unwrap().prelmse
            };
            (scene.name(), get("ours-taa") / get("white"))
        })
        .collect();
    for ((scene, ratio), bound) in ratios.iter().zip(bounds) {
        assert!(*ratio < bound, "{scene}: {ratio:.3} x white (every scene: {ratios:.3?})");
    }
}

#[test]
fn the_planned_method_reads_each_decision_from_its_own_mask_with_and_without_taa() {
    let dir = tempfile::tempdir().unwrap();
    let size = EvalSize { planned: true, ..tiny() };
    let scenes = [Scene::LightPick, Scene::DefocusMotion];
    let records =
        run_eval(&size, &[2.1], &scenes, dir.path(), None, &[], Default::default(), |_| {}).unwrap();
    assert_eq!(records.len(), scenes.len() * (METHODS.len() + 1) * 2);
    for scene in ["light-pick", "defocus-motion"] {
        for taa in [false, true] {
            let r = records
                .iter()
                .find(|r| r.scene == scene && r.method == "fsot-planned" && r.taa == taa)
                .unwrap();
            let white =
                records.iter().find(|r| r.scene == scene && r.method == "white" && r.taa == taa).unwrap();
            assert!(r.prelmse.is_finite() && r.prelmse > 0.0, "{r:?}");
            assert!(r.prelmse < white.prelmse, "{r:?} against {white:?}");
            assert!(r.prelmse_display < white.prelmse_display, "{r:?} against {white:?}");
        }
    }
    // defocus-motion: a 2-D lens mask and a 1-D time mask; light-pick: one 1-D mask.
    let planned = fsot_cli::eval::suite::planned_masks(
        Scene::DefocusMotion,
        judged_on(),
        true,
        true,
        &size,
        dir.path(),
        1,
    )
    .unwrap();
    let shape: Vec<(usize, usize)> =
        planned.reads.iter().map(|r| (planned.masks[r.0].tile.dims, r.1)).collect();
    assert_eq!(shape, [(2, 0), (1, 2)]);
    assert!(!planned.shares, "no two decisions of the same dimension");
    let planned = fsot_cli::eval::suite::planned_masks(
        Scene::LightPick,
        judged_on(),
        false,
        true,
        &size,
        dir.path(),
        1,
    )
    .unwrap();
    assert_eq!(planned.masks.iter().map(|m| m.tile.dims).collect::<Vec<_>>(), [1]);
    assert_eq!(planned.seconds, 0.0, "read from the cache");
    assert!(
        planned.masks[0].meta("kernel").unwrap().starts_with("taa ("),
        "no TAA: a short blend over frames"
    );
}

#[test]
fn a_run_judging_one_taa_setting_gives_that_settings_records_and_makes_only_its_planned_masks() {
    let dir = tempfile::tempdir().unwrap();
    let names = ["white".to_string(), "fsot-planned".to_string()];
    let only = fsot_cli::eval::suite::Only::Named(&names);
    let size = EvalSize { planned: true, planned_unshared: false, planned_masks: 1, ..tiny() };
    let run = |judged: [bool; 2], log: &mut Vec<String>| {
        let size = EvalSize { judged, ..size.clone() };
        run_eval(&size, &[2.1], &[Scene::LightPick], dir.path(), None, &[], only, |l| log.push(l.to_string()))
            .unwrap()
    };
    let mut without_log = Vec::new();
    let without = run([true, false], &mut without_log);
    assert!(without.iter().all(|r| !r.taa) && without.len() == 2, "{without:?}");
    // Masks measured: white noise's two seeds, the plan's one mask at both placements.
    let masks: Vec<(&str, u32)> = without.iter().map(|r| (r.method.as_str(), r.seeds)).collect();
    assert_eq!(masks, [("white", 2), ("fsot-planned", 1)]);
    // Only the no-TAA plan's mask was made: the TAA plan's is made by the run judging both.
    assert!(without_log.iter().any(|l| l.contains("(no-TAA plan)") && !l.contains("(cached)")));
    assert!(!without_log.iter().any(|l| l.contains("(TAA plan)")), "{without_log:?}");
    let mut both_log = Vec::new();
    let both = run([true, true], &mut both_log);
    assert!(both_log.iter().any(|l| l.contains("(TAA plan)") && !l.contains("(cached)")), "{both_log:?}");
    let both_without: Vec<_> = both.iter().filter(|r| !r.taa).cloned().collect();
    assert_eq!(without, both_without, "the same records as the run judging both settings");
    let with = run([false, true], &mut Vec::new());
    assert_eq!(with, both.iter().filter(|r| r.taa).cloned().collect::<Vec<_>>());
    let tables = to_markdown(&with);
    assert!(tables.contains("with TAA") && !tables.contains("without TAA"), "{tables}");
}

#[test]
fn the_records_do_not_depend_on_the_number_of_threads_the_placements_are_judged_on() {
    let dir = tempfile::tempdir().unwrap();
    let names = ["white".to_string(), "stbn".to_string()];
    let only = fsot_cli::eval::suite::Only::Named(&names);
    let size = EvalSize { seeds: 3, ..tiny() };
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| run_eval(&size, &[2.1], &[Scene::Occlusion], dir.path(), None, &[], only, |_| {}))
            .unwrap()
    };
    let one = on(1);
    assert_eq!(one.len(), 4);
    assert_eq!(on(3), one);
}

#[test]
fn decisions_of_one_dimension_share_a_mask_and_the_evaluation_measures_what_that_costs() {
    let dir = tempfile::tempdir().unwrap();
    let size = EvalSize { planned: true, ..tiny() };
    // veach-mis: a 2-D light sample and a 2-D BSDF sample read one mask.
    let shared =
        fsot_cli::eval::suite::planned_masks(Scene::VeachMis, judged_on(), true, true, &size, dir.path(), 1)
            .unwrap();
    assert!(shared.shares);
    assert_eq!(shared.masks.len(), 1);
    let [(a, 0, [0, 0, 0], _), (b, 2, offset, shift)] = &shared.reads[..] else {
        panic!("two reads: {:?}", shared.reads)
    };
    assert_eq!((a, b), (&0, &0), "both read the light's mask");
    assert_ne!(*offset, [0, 0, 0]);
    assert!(shift.iter().all(|s| *s > 0.0 && *s < 1.0));
    let own =
        fsot_cli::eval::suite::planned_masks(Scene::VeachMis, judged_on(), true, false, &size, dir.path(), 1)
            .unwrap();
    assert!(!own.shares);
    assert_eq!(own.masks.len(), 2);
    assert_eq!(own.masks[0].samples, shared.masks[0].samples, "the light's own mask is the one it lends");
    // Both are measured, with and without TAA; a scene without sharing has no
    // unshared column.
    let records = run_eval(
        &size,
        &[2.1],
        &[Scene::VeachMis, Scene::LightPick],
        dir.path(),
        None,
        &[],
        Default::default(),
        |_| {},
    )
    .unwrap();
    let count = |scene: &str, m: &str| records.iter().filter(|r| r.scene == scene && r.method == m).count();
    assert_eq!((count("veach-mis", "fsot-planned"), count("veach-mis", "fsot-planned-unshared")), (2, 2));
    assert_eq!((count("light-pick", "fsot-planned"), count("light-pick", "fsot-planned-unshared")), (2, 0));
}

fn record(
    method: &str,
    prelmse: f64,
    prelmse_ci95: f64,
    jod: f64,
    jod_ci95: f64,
) -> fsot_cli::eval::suite::Record {
    fsot_cli::eval::suite::Record {
        scene: "soft-shadow".into(),
        method: method.into(),
        display: "standard_4k".into(),
        taa: true,
        sigma: 2.1,
        prelmse,
        prelmse_ci95,
        relmse: 2.0 * prelmse,
        relmse_ci95: 0.0,
        prelmse_display: prelmse,
        prelmse_display_ci95: prelmse_ci95,
        jod,
        jod_ci95,
        flip: None,
        flip_ci95: None,
        seeds: 5,
        placements: Default::default(),
        anatomy: None,
    }
}

#[test]
fn a_winner_is_bold_only_where_its_interval_clears_the_runner_ups() {
    // pRelMSE: a (0.2 +- 0.01) clears b (0.3 +- 0.01); JOD: a (8.0 +- 0.5) and
    // b (7.8 +- 0.5) overlap, so no JOD winner.
    let records = [
        record("white", 1.0, 0.05, 6.0, 0.1),
        record("a", 0.2, 0.01, 8.0, 0.5),
        record("b", 0.3, 0.01, 7.8, 0.5),
    ];
    let md = to_markdown(&records);
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| soft-shadow |")).collect();
    assert_eq!(rows.len(), 3, "{md}");
    // pRelMSE by the column's sigma, then by the display's eye (here the same figures).
    assert_eq!(rows[0], "| soft-shadow | 1.000e0 +- 5.0e-2 | **0.200 +- 0.010** | 0.300 +- 0.010 |");
    assert_eq!(rows[1], rows[0]);
    assert_eq!(rows[2], "| soft-shadow | 6.000 +- 0.100 | 8.000 +- 0.500 | 7.800 +- 0.500 |");
    // Narrower JOD intervals: now a wins.
    let records = [
        record("white", 1.0, 0.05, 6.0, 0.1),
        record("a", 0.2, 0.01, 8.0, 0.05),
        record("b", 0.3, 0.01, 7.8, 0.05),
    ];
    assert!(to_markdown(&records).contains("| **8.000 +- 0.050** |"));
}

#[test]
fn without_white_noise_the_error_tables_show_absolute_values_in_scientific_notation() {
    let records = [record("a", 2.24e-4, 1.4e-5, 9.05, 0.17), record("b", 1.38e-4, 1.6e-5, 8.70, 0.06)];
    let md = to_markdown(&records);
    assert!(
        md.contains("### pRelMSE on standard_4k, sigma 2.1, with TAA (absolute; +- the 95% interval)"),
        "{md}"
    );
    let rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| soft-shadow |")).collect();
    assert_eq!(rows[0], "| soft-shadow | 2.240e-4 +- 1.4e-5 | **1.380e-4 +- 1.6e-5** |");
    assert_eq!(rows[2], "| soft-shadow | **9.050 +- 0.170** | 8.700 +- 0.060 |");
}

#[test]
fn a_run_measures_only_the_methods_named_and_dissects_their_error_when_asked() {
    use fsot_cli::eval::anatomy::{SPATIAL_EDGES, TEMPORAL_EDGES};
    let dir = tempfile::tempdir().unwrap();
    let names = ["white".to_string(), "ours-taa".to_string()];
    let size = EvalSize { anatomy: true, ..tiny() };
    let only = fsot_cli::eval::suite::Only::Named(&names);
    let records = run_eval(&size, &[2.1], &[Scene::SoftShadow], dir.path(), None, &[], only, |_| {}).unwrap();
    let mut methods: Vec<&str> = records.iter().map(|r| r.method.as_str()).collect();
    methods.dedup();
    assert_eq!(methods, ["white", "ours-taa"]);
    // The anatomy's JOD is the judge's own: the records of a run without it.
    let plain = EvalSize { anatomy: false, ..tiny() };
    let judged = run_eval(&plain, &[2.1], &[Scene::SoftShadow], dir.path(), None, &[], only, |_| {}).unwrap();
    assert_eq!(records.len(), judged.len());
    for (r, j) in records.iter().zip(&judged) {
        let a = r.anatomy.as_ref().expect("an anatomy for every record");
        assert!((a.jod - j.jod).abs() < 1e-9 && r.jod == a.jod, "{r:?} against {j:?}");
        assert_eq!(a.spatial.len(), SPATIAL_EDGES.len() - 1);
        assert_eq!(a.temporal.len(), TEMPORAL_EDGES.len() - 1);
        // Every spatial band holds power; the 8 judged frames reach some temporal bands only.
        assert!(a.spatial.iter().all(|&p| p > 0.0), "{a:?}");
        assert!(a.temporal[0] > 0.0 && a.temporal.iter().filter(|&&p| p > 0.0).count() >= 3, "{a:?}");
        // Four channels (video), each with a value per band.
        assert_eq!(a.bands.len(), 4);
        assert!(a.bands.iter().all(|b| b.len() == a.band_frequencies.len()));
        assert!(a.bands.iter().flatten().all(|&q| q.is_finite() && q >= 0.0), "{a:?}");
    }
    // An optimised mask leaves less error power at the lowest spatial frequencies
    // than white noise does, with TAA and without.
    for taa in [false, true] {
        let low = |m: &str| {
            let r = records.iter().find(|r| r.method == m && r.taa == taa).unwrap();
            r.anatomy.as_ref().unwrap().spatial[0]
        };
        assert!(
            low("ours-taa") < 0.8 * low("white"),
            "TAA {taa}: {} against {}",
            low("ours-taa"),
            low("white")
        );
    }
    assert!(fsot_cli::eval::suite::anatomy_markdown(&records).contains("| ours-taa |"));
}

#[test]
fn fsots_display_geometry_gives_colorvideovdps_pixels_per_degree() {
    // An independent reference: ColorVideoVDP's own display models.
    for (name, ..) in fsot::core::display::PRESETS {
        let theirs = colorvideovdp::DisplayModel::from_name(name).unwrap().geometry.pixels_per_degree();
        let ours = fsot::core::display::preset_ppd(name).unwrap();
        assert!((ours - theirs).abs() <= 0.005 + 1e-9, "{name}: {ours} against {theirs}");
    }
}

#[test]
fn flip_judges_the_frames_after_taa_only() {
    let dir = tempfile::tempdir().unwrap();
    let size = EvalSize { flip: true, ..tiny() };
    let names = ["white".to_string()];
    let only = fsot_cli::eval::suite::Only::Named(&names);
    let records = run_eval(&size, &[2.1], &[Scene::SoftShadow], dir.path(), None, &[], only, |_| {}).unwrap();
    assert!(!records.is_empty());
    for r in &records {
        assert_eq!(r.flip.is_some(), r.taa, "{r:?}");
    }
}
