//! Scene files: what a renderer samples, read strictly; every mistake is named
//! with its line.

use fsot::core::kernel::Spatial;
use fsot::scene::file::{Group, Scene};

const EXAMPLE: &str = r#"
[display]
fps = 60
taa_alpha = 0.1
sigma = 2.1
animated = true

[tile]
size = "64x64x32"

[[group]]
name = "pick"
dims = 1
spp = 1
[[group]]
name = "lens"
dims = 2
[[group]]
name = "bounce2"
dims = 2
visible = false
"#;

#[test]
fn the_example_scene_reads_as_written() {
    let s = Scene::parse(EXAMPLE, "example").unwrap();
    assert_eq!(s.display.taa_alpha, Some(0.1));
    assert_eq!(
        (s.display.fps, s.display.spatial, s.display.animated),
        (60.0, Spatial::Gaussian { sigma: 2.1 }, true)
    );
    assert_eq!(s.size, Some((64, 64, 32)));
    let names: Vec<&str> = s.groups.iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, ["pick", "lens", "bounce2"], "the renderer's order");
    assert_eq!(s.groups[2], Group { name: "bounce2".into(), dims: 2, spp: 1, visible: false, share: true });
}

#[test]
fn what_is_absent_takes_its_default() {
    let s = Scene::parse("[[group]]\nname = \"a\"\ndims = 2\n", "minimal").unwrap();
    assert_eq!(s.display.taa_alpha, None, "no [display]: no TAA");
    let fhd = fsot::core::display::preset_ppd("standard_fhd").unwrap();
    assert_eq!(
        (s.display.fps, s.display.spatial, s.display.animated),
        (60.0, Spatial::Display { ppd: fhd }, true)
    );
    assert_eq!(s.size, None);
    assert_eq!(s.groups[0], Group { name: "a".into(), dims: 2, spp: 1, visible: true, share: true });
}

#[test]
fn every_mistake_is_refused_naming_its_line() {
    let group = "[[group]]\nname = \"a\"\ndims = 2\n";
    let cases: &[(String, &str, &str)] = &[
        (format!("[display]\nfsp = 60\n{group}"), "line 2", "unknown field"),
        (format!("{group}colour = 1\n"), "line 4", "unknown field"),
        ("[display]\nfps = 60\n".to_string(), "", "no [[group]]"),
        ("[[group]]\nname = \"a\"\ndims = 0\n".to_string(), "line 3", "dims must be 1 to 8"),
        ("[[group]]\nname = \"a\"\ndims = 9\n".to_string(), "line 3", "dims must be 1 to 8"),
        ("[[group]]\nname = \"a\"\n".to_string(), "line 1", "missing field `dims`"),
        (format!("{group}[[group]]\nname = \"a\"\ndims = 1\n"), "line 5", "a second group named \"a\""),
        ("[[group]]\nname = \"Lens\"\ndims = 2\n".to_string(), "line 2", "[a-z0-9_]"),
        ("[[group]]\nname = \"\"\ndims = 2\n".to_string(), "line 2", "[a-z0-9_]"),
        (format!("[[group]]\nname = \"{}\"\ndims = 2\n", "a".repeat(65)), "line 2", "1 to 64 of [a-z0-9_]"),
        (
            format!("[display]\nresolution = [2560, 1440, 3]\ndiagonal = 27.0\ndistance = 0.7\n{group}"),
            "line 2",
            "resolution is [width, height]",
        ),
        (format!("[display]\ntaa_alpha = 1.5\n{group}"), "line 2", "taa_alpha must be in [0.0001, 1]"),
        (format!("[display]\ntaa_alpha = 0\n{group}"), "line 2", "taa_alpha must be in [0.0001, 1]"),
        (format!("[display]\ntaa_alpha = 5e-324\n{group}"), "line 2", "taa_alpha must be in [0.0001, 1]"),
        (format!("[display]\nfps = -5\n{group}"), "line 2", "fps"),
        (format!("[display]\nfps = 4\ntaa_alpha = 0.1\n{group}"), "line 2", "fps must be in [8, 1000]"),
        (format!("[display]\nsigma = nan\n{group}"), "line 2", "sigma"),
        (format!("[display]\nsigma = 1e-200\n{group}"), "line 2", "sigma must be in [0.01, 8]"),
        (format!("[tile]\nsize = \"64xx\"\n{group}"), "line 2", "size must look like"),
        (format!("[tile]\nsize = \"0x0\"\n{group}"), "line 2", "tile width must be at least 1"),
        (format!("[plan]\nbudget = \"1e-300s\"\n{group}"), "line 2", "must be at least 0.001 s"),
        (format!("[tile]\nsize = \"65536x65536x65536\"\n{group}"), "line 2", "holds more than"),
        // A tile the scene's size allows, that a group's spp takes past the largest.
        (format!("[tile]\nsize = \"16384x16384x1\"\n{group}spp = 2\n"), "line 6", "holds more than"),
        (
            (0..2048).map(|k| format!("[[group]]\nname = \"g{k}\"\ndims = 1\n")).collect(),
            "line 6142",
            "more than 2047 groups",
        ),
        (format!("{group}spp = 0\n"), "line 4", "spp must be 1 to 64"),
        (format!("{group}dims = 3\n"), "line 4", "duplicate key"),
        ("[[group]\nname = 1".to_string(), "line 1", ""),
        (format!("[display]\nanimated = \"yes\"\n{group}"), "line 2", "invalid type"),
        (format!("[display]\nname = \"standard_8k\"\n{group}"), "line 2", "unknown display"),
        (format!("[display]\nppd = 2\n{group}"), "line 2", "pixels per degree must be in"),
        (format!("[display]\nppd = 60\nsigma = 2.1\n{group}"), "line 3", "give the display one way"),
        (format!("[display]\nresolution = [2560, 1440]\ndiagonal = 27.0\n{group}"), "line 2", "needs all of"),
        (
            format!("[display]\nresolution = [2560, 0]\ndiagonal = 27.0\ndistance = 0.7\n{group}"),
            "line 2",
            "resolution",
        ),
    ];
    for (text, line, what) in cases {
        let err = Scene::parse(text, "bad").err().unwrap_or_else(|| panic!("accepted: {text}"));
        assert!(
            err.contains(line) && err.contains(what),
            "{text:?}: expected {line:?} and {what:?} in {err:?}"
        );
    }
}

#[test]
fn a_scene_set_out_of_range_by_hand_is_refused_by_its_check_and_by_the_planner() {
    let good = || Scene::parse(EXAMPLE, "example").unwrap();
    assert!(good().check().is_ok());
    type SetByHand = fn(&mut Scene);
    let cases: [(&str, SetByHand); 15] = [
        ("no groups", |s| s.groups.clear()),
        ("2048 groups", |s| {
            let g = s.groups[0].clone();
            s.groups =
                (0..2048).map(|k| fsot::scene::file::Group { name: format!("g{k}"), ..g.clone() }).collect()
        }),
        ("a group named for another folder", |s| s.groups[0].name = "../pick".into()),
        ("two groups of one name", |s| s.groups[1].name = "pick".into()),
        ("d = 0", |s| s.groups[0].dims = 0),
        ("d = 9", |s| s.groups[0].dims = 9),
        ("spp = 0", |s| s.groups[0].spp = 0),
        ("fps NaN", |s| s.display.fps = f64::NAN),
        ("fps 4", |s| s.display.fps = 4.0),
        ("TAA alpha 0", |s| s.display.taa_alpha = Some(0.0)),
        ("sigma 0", |s| s.display.spatial = Spatial::Gaussian { sigma: 0.0 }),
        ("ppd NaN", |s| s.display.spatial = Spatial::Display { ppd: f64::NAN }),
        ("a tile 0 wide", |s| s.size = Some((0, 64, 32))),
        ("a NaN budget", |s| s.budget = Some(f64::NAN)),
        ("a budget of a year", |s| s.budget = Some(3.2e7)),
    ];
    let cost = fsot::scene::plan::CostModel::unmeasured();
    for (what, set) in cases {
        let mut scene = good();
        set(&mut scene);
        assert!(scene.check().is_err(), "{what}: check");
        assert!(fsot::scene::plan::Plan::new(&scene, &cost).is_err(), "{what}: planned");
    }
    for bad in [f64::NAN, -1.0, f64::INFINITY] {
        let cost = fsot::scene::plan::CostModel { seconds_per_point: bad, backend: "by hand".into() };
        assert!(fsot::scene::plan::Plan::new(&good(), &cost).is_err(), "{bad} s a point: planned");
    }
}

#[test]
fn a_file_that_cannot_be_read_says_so() {
    let err = Scene::read(std::path::Path::new("no/such/scene.toml")).unwrap_err();
    assert!(err.to_string().contains("cannot read the scene"), "{err}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.toml");
    std::fs::write(&path, "[[group]]\nname = \"a\"\ndims = 12\n").unwrap();
    let err = Scene::read(&path).unwrap_err().to_string();
    assert!(err.contains("s.toml") && err.contains("line 3"), "{err}");
}

#[test]
fn a_display_is_named_or_given_by_its_pixels_per_degree_or_its_geometry() {
    let group = "[[group]]\nname = \"a\"\ndims = 2\n";
    let ppd = |display: &str| match Scene::parse(&format!("[display]\n{display}\n{group}"), "d")
        .unwrap()
        .display
        .spatial
    {
        Spatial::Display { ppd } => ppd,
        other => panic!("{display}: {other:?}"),
    };
    assert_eq!(ppd("ppd = 60"), 60.0);
    assert_eq!(ppd("name = \"standard_4k\""), fsot::core::display::preset_ppd("standard_4k").unwrap());
    let fhd = ppd("resolution = [1920, 1080]\ndiagonal = 24.0\ndistance = 0.6");
    assert_eq!(fhd, ppd("name = \"standard_fhd\""));
    // Twice the distance: nearly twice the pixels per degree.
    let far = ppd("resolution = [1920, 1080]\ndiagonal = 24.0\ndistance = 1.2");
    assert!((far / fhd - 2.0).abs() < 1e-3, "{far} against {fhd}");
}
