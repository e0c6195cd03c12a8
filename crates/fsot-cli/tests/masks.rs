//! The ready-made masks in masks/: the script's smallest mask remade by the
//! command it names gives the shipped bytes, and the manifest describes every
//! shipped file.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The masks scripts/make-masks.sh lists: (name, KTX2 format, optimize flags).
fn listed() -> Vec<(String, String, Vec<String>)> {
    let script = std::fs::read_to_string(root().join("scripts/make-masks.sh")).unwrap();
    script
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with('"') && l.ends_with('"') && l.matches('|').count() == 2)
        .map(|l| {
            let parts: Vec<&str> = l.trim_matches('"').split('|').collect();
            (
                parts[0].to_string(),
                parts[1].to_string(),
                parts[2].split_whitespace().map(String::from).collect(),
            )
        })
        .collect()
}

fn texels(flags: &[String]) -> usize {
    let size = &flags[flags.iter().position(|f| f == "--size").unwrap() + 1];
    size.split('x').map(|v| v.parse::<usize>().unwrap()).product()
}

#[test]
fn the_smallest_shipped_mask_is_remade_byte_for_byte() {
    let masks = listed();
    assert!(masks.len() >= 3, "make-masks.sh lists {} masks", masks.len());
    let (name, format, flags) = masks.iter().min_by_key(|(_, _, f)| texels(f)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_fsot"))
        .args(["optimize", "--backend", "cpu"])
        .args(flags)
        .args(["--out", "m.ktx2", "--ktx2-format", format, "--png", "slices", "--png-bits", "8"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let shipped = root().join("masks");
    assert!(
        std::fs::read(dir.path().join("m.ktx2")).unwrap()
            == std::fs::read(shipped.join(format!("{name}.ktx2"))).unwrap(),
        "{name}.ktx2 differs from the remade mask"
    );
    let mut slices: Vec<_> =
        std::fs::read_dir(dir.path().join("slices")).unwrap().map(|e| e.unwrap().file_name()).collect();
    slices.sort();
    let mut shipped_slices: Vec<_> =
        std::fs::read_dir(shipped.join(name)).unwrap().map(|e| e.unwrap().file_name()).collect();
    shipped_slices.sort();
    assert_eq!(slices, shipped_slices);
    for s in &slices {
        assert!(
            std::fs::read(dir.path().join("slices").join(s)).unwrap()
                == std::fs::read(shipped.join(name).join(s)).unwrap(),
            "{name}/{s:?} differs from the remade slice"
        );
    }
}

#[test]
fn the_manifest_describes_every_shipped_mask_within_16_mb() {
    let shipped = root().join("masks");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(shipped.join("manifest.json")).unwrap()).unwrap();
    assert!(manifest["licence"].as_str().unwrap().starts_with("CC0-1.0"));
    let entries = manifest["masks"].as_array().unwrap();
    let listed = listed();
    assert_eq!(entries.len(), listed.len());
    let mut bytes = 0;
    for ((name, format, flags), entry) in listed.iter().zip(entries) {
        assert_eq!(entry["name"], name.as_str());
        assert_eq!(entry["ktx2_format"], format.as_str());
        let command = entry["command"].as_str().unwrap();
        assert!(command.contains(&flags.join(" ")), "{name}: {command}");
        // The viewing it names is the one its flags made it for.
        let display = entry["display"].as_str().unwrap();
        let alpha = flags.iter().position(|f| f == "--alpha").map_or("0.1", |i| flags[i + 1].as_str());
        let taa = flags.windows(2).any(|w| w == ["--kernel", "perceptual-taa"]);
        let viewing = if taa {
            format!("TAA alpha {alpha}")
        } else {
            format!("no TAA: the eye's integration over frames as a blend of weight {alpha}")
        };
        assert!(display.contains(&viewing), "{name}: {display} (made with {flags:?})");
        let ktx2 = std::fs::metadata(shipped.join(format!("{name}.ktx2"))).unwrap().len();
        assert_eq!(entry["ktx2_bytes"].as_u64(), Some(ktx2), "{name}");
        bytes += ktx2;
        let frames = entry["frames"].as_u64().unwrap() as usize;
        assert_eq!(std::fs::read_dir(shipped.join(name)).unwrap().count(), frames, "{name}: PNG slices");
        for e in std::fs::read_dir(shipped.join(name)).unwrap() {
            bytes += e.unwrap().metadata().unwrap().len();
        }
        for display in ["standard_fhd", "standard_4k"] {
            let scenes = entry["eval"][display].as_object().unwrap();
            assert!(scenes.len() >= 6, "{name}: {} scenes judged on {display}", scenes.len());
            for (scene, cell) in scenes {
                for taa in ["taa", "no_taa"] {
                    let jod = cell[taa]["jod"].as_f64().unwrap();
                    let ratio = cell[taa]["prelmse_x_white"].as_f64().unwrap();
                    assert!(
                        (0.0..=10.0).contains(&jod) && ratio > 0.0,
                        "{name} {scene} {taa}: {jod} {ratio}"
                    );
                }
            }
        }
    }
    assert!(bytes <= 16_000_000, "masks/ holds {bytes} bytes");
}

#[test]
fn sha256sums_lists_every_shipped_mask_file_with_its_checksum() {
    let shipped = root().join("masks");
    let sums = std::fs::read_to_string(shipped.join("SHA256SUMS")).unwrap();
    let mut listed: Vec<String> = sums.lines().map(|l| l.split_once("  ").unwrap().1.to_string()).collect();
    listed.sort();
    let mut files = Vec::new();
    for e in std::fs::read_dir(&shipped).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().into_string().unwrap();
        if e.file_type().unwrap().is_dir() {
            for s in std::fs::read_dir(e.path()).unwrap() {
                files.push(format!("{name}/{}", s.unwrap().file_name().into_string().unwrap()));
            }
        } else if name.ends_with(".ktx2") {
            files.push(name);
        }
    }
    files.sort();
    assert_eq!(listed, files, "SHA256SUMS against the files in masks/");
    // coreutils' sha256sum, an implementation independent of fsot, checks each.
    match Command::new("sha256sum").args(["-c", "--quiet", "SHA256SUMS"]).current_dir(&shipped).output() {
        Ok(out) => assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stdout)),
        Err(e) => panic!("sha256sum (coreutils) is needed to check the checksums: {e}"),
    }
}
