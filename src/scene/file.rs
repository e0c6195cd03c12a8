//! A scene file: what a renderer samples and how its frames are seen (TOML).
//!
//! ```toml
//! [display]
//! fps = 60            # frame rate, 8 to 1000, for the perceptual filter
//! taa_alpha = 0.1     # TAA blend weight of the current frame, 0.0001 to 1; absent: no TAA
//! name = "standard_fhd"  # the display the frames are seen on (default), or:
//! # ppd = 60          #   its pixels per degree, or:
//! # resolution = [2560, 1440]
//! # diagonal = 27.0   #   inches
//! # distance = 0.7    #   metres
//! # sigma = 2.1       # instead: the eye as a spatial Gaussian in pixels
//! animated = true     # false: still camera and scene (accumulation)
//!
//! [tile]              # optional; the planner chooses what is absent
//! size = "128x128x64"
//! reading = "scalar"  # "scalar": a 1-D mask per dimension; "vector": masks of pairs
//!
//! [plan]              # optional
//! budget = "10s"      # make every mask within this wall time (from the start),
//!                     # instead of until iterations no longer pay
//!
//! [[group]]           # one per sampling decision, in the order the renderer consumes them
//! name = "pick"       # unique, 1 to 64 of [a-z0-9_]
//! dims = 1            # 1 to 8
//! spp = 1             # optional, default 1; every group of a scene the same
//! visible = true      # optional; false: its error is not seen directly
//! share = true        # optional; false: never reads another decision's mask
//! ```
//!
//! Unknown keys are refused; every error names its line.

use std::ops::Range;
use std::path::Path;

use serde::Deserialize;
use toml::Spanned;

use crate::core::kernel::{Spatial, ALPHA_RANGE, FPS_RANGE};
use crate::core::tile::{Tile, MAX_DIMS, MAX_SPP};
use crate::error::{Error, Result};

/// How the renderer's frames are shown and seen.
#[derive(Clone, Debug, PartialEq)]
pub struct Display {
    /// Frame rate in frames per second, 8 to 1000 [default: 60].
    pub fps: f64,
    /// TAA's blend weight of the current frame; None: no TAA.
    pub taa_alpha: Option<f64>,
    /// The eye's spatial filter: the contrast sensitivity at the display's
    /// pixels per degree, or a Gaussian given in pixels.
    pub spatial: Spatial,
    /// Where `spatial` came from, for the plan's reasons.
    pub seen_on: String,
    /// False: a still camera and scene, frames accumulated.
    pub animated: bool,
}

/// One sampling decision of the renderer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Group {
    /// Unique in the scene, 1 to 64 of [a-z0-9_].
    pub name: String,
    /// Dimensions of the decision, 1 to `MAX_DIMS`.
    pub dims: usize,
    /// Samples per pixel and frame, 1 to `MAX_SPP` [default: 1].
    pub spp: usize,
    /// False: its error is not seen directly (deep bounces, roulette).
    pub visible: bool,
    /// False: the decision gets masks of its own even where it could share one.
    pub share: bool,
}

/// How a decision of several dimensions reads its numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reading {
    /// A 1-D mask per dimension, each read at its own offset and shift.
    Scalar,
    /// Masks of pairs of dimensions (and a single for an odd last one).
    Vector,
}

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The file's stem.
    pub name: String,
    /// How its frames are shown and seen.
    pub display: Display,
    /// W, H, T when the file gives them.
    pub size: Option<(usize, usize, usize)>,
    /// How decisions of more than one dimension read masks, when the file says.
    pub reading: Option<Reading>,
    /// Seconds of wall time to make every mask in, when the file gives them.
    pub budget: Option<f64>,
    /// In the order the renderer consumes them.
    pub groups: Vec<Group>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileScene {
    display: Option<Spanned<FileDisplay>>,
    tile: Option<FileTile>,
    plan: Option<FilePlan>,
    #[serde(default)]
    group: Vec<Spanned<FileGroup>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileDisplay {
    fps: Option<Spanned<f64>>,
    taa_alpha: Option<Spanned<f64>>,
    name: Option<Spanned<String>>,
    ppd: Option<Spanned<f64>>,
    resolution: Option<Spanned<Vec<u32>>>,
    diagonal: Option<Spanned<f64>>,
    distance: Option<Spanned<f64>>,
    sigma: Option<Spanned<f64>>,
    animated: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileTile {
    size: Option<Spanned<String>>,
    reading: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FilePlan {
    budget: Option<Spanned<toml::Value>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileGroup {
    name: Spanned<String>,
    dims: Spanned<i64>,
    spp: Option<Spanned<i64>>,
    visible: Option<bool>,
    share: Option<bool>,
}

impl Scene {
    /// Reads and checks a scene file.
    pub fn read(path: &Path) -> Result<Self> {
        let text = crate::io::read_regular_text(path)
            .map_err(|e| Error::io(format!("cannot read the scene {}", path.display()), e))?;
        let name =
            path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
        Self::parse(&text, &name).map_err(|reason| Error::bad_file(path, reason))
    }

    /// Parses and checks scene text; the error names the line.
    pub fn parse(text: &str, name: &str) -> std::result::Result<Self, String> {
        let at = |span: Range<usize>, what: String| format!("line {}: {what}", line_of(text, span.start));
        let file: FileScene = toml::from_str(text).map_err(|e| match e.span() {
            Some(span) => at(span, e.message().trim().to_string()),
            None => e.message().trim().to_string(),
        })?;
        let display = match &file.display {
            Some(d) => check_display(d.get_ref(), &at)?,
            None => Display::default(),
        };
        let size = match file.tile.as_ref().and_then(|t| t.size.as_ref()) {
            Some(s) => {
                let (w, h, t) = Tile::parse_size(s.get_ref()).map_err(|e| at(s.span(), e.to_string()))?;
                Tile::new(w, h, t, 1, 1).map_err(|e| at(s.span(), e.to_string()))?;
                Some((w, h, t))
            }
            None => None,
        };
        if file.group.is_empty() {
            return Err("no [[group]]: a scene needs at least one sampling decision".into());
        }
        if file.group.len() > MAX_GROUPS {
            return Err(at(
                file.group[MAX_GROUPS].span(),
                format!("more than {MAX_GROUPS} groups: a renderer reads at most {MAX_GROUPS} parts"),
            ));
        }
        let mut groups: Vec<Group> = Vec::new();
        for g in &file.group {
            let group = check_group(g.get_ref(), &at)?;
            if groups.iter().any(|o| o.name == group.name) {
                return Err(at(g.get_ref().name.span(), format!("a second group named {:?}", group.name)));
            }
            // The largest mask the group can need: its dimensions up to a texel's
            // four (a white mask), at its spp, on the scene's tile.
            if let Some((w, h, t)) = size {
                let span = g.get_ref().spp.as_ref().map_or_else(|| g.get_ref().dims.span(), |s| s.span());
                Tile::new(w, h, t, group.spp, group.dims.min(4)).map_err(|e| at(span, e.to_string()))?;
            }
            if let Some(first) = groups.first().filter(|f| f.spp != group.spp) {
                let span = g.get_ref().spp.as_ref().map_or_else(|| g.get_ref().name.span(), |s| s.span());
                return Err(at(
                    span,
                    format!(
                        "group {} has spp {}, group {} spp {}: a scene's groups share one spp (a renderer reads \
                         every mask of a plan through one plan block, which holds one)",
                        group.name, group.spp, first.name, first.spp
                    ),
                ));
            }
            groups.push(group);
        }
        let reading = match file.tile.as_ref().and_then(|t| t.reading.as_ref()) {
            Some(r) => Some(match r.get_ref().as_str() {
                "scalar" => Reading::Scalar,
                "vector" => Reading::Vector,
                other => {
                    return Err(at(
                        r.span(),
                        format!("reading must be \"scalar\" or \"vector\", got {other:?}"),
                    ))
                }
            }),
            None => None,
        };
        let budget = match file.plan.as_ref().and_then(|p| p.budget.as_ref()) {
            Some(b) => Some(check_budget(b.get_ref()).map_err(|e| at(b.span(), e))?),
            None => None,
        };
        Ok(Self { name: name.to_string(), display, size, reading, budget, groups })
    }

    /// An error unless `parse` would accept every value: for a scene whose
    /// public fields were set by hand. `Plan::new` checks its scene.
    pub fn check(&self) -> Result<()> {
        let d = &self.display;
        if !FPS_RANGE.contains(&d.fps) {
            return Err(Error::invalid(format!("fps must be in [8, 1000], got {:?}", d.fps)));
        }
        if let Some(a) = d.taa_alpha.filter(|a| !ALPHA_RANGE.contains(a)) {
            return Err(Error::invalid(format!("taa_alpha must be in [0.0001, 1], got {a:?}")));
        }
        match d.spatial {
            Spatial::Gaussian { sigma } if !SCENE_SIGMA_RANGE.contains(&sigma) => {
                return Err(Error::invalid(format!("sigma must be in [0.01, 8] pixels, got {sigma:?}")))
            }
            Spatial::Gaussian { .. } => {}
            Spatial::Display { ppd } => {
                crate::core::display::check_ppd(ppd)?;
            }
        }
        if let Some((w, h, t)) = self.size {
            Tile::new(w, h, t, 1, 1)?;
        }
        if let Some(b) = self.budget.filter(|b| !crate::optimize::settings::BUDGET_SECONDS.contains(b)) {
            return Err(Error::invalid(format!("budget must be a millisecond to a day, got {b:?} s")));
        }
        if self.groups.is_empty() {
            return Err(Error::invalid("no group: a scene needs at least one sampling decision"));
        }
        if self.groups.len() > MAX_GROUPS {
            return Err(Error::invalid(format!("{} groups, more than {MAX_GROUPS}", self.groups.len())));
        }
        for (k, g) in self.groups.iter().enumerate() {
            if !valid_group_name(&g.name) {
                return Err(Error::invalid(format!("group name {:?} must be 1 to 64 of [a-z0-9_]", g.name)));
            }
            if self.groups[..k].iter().any(|o| o.name == g.name) {
                return Err(Error::invalid(format!("a second group named {:?}", g.name)));
            }
            if !(1..=MAX_DIMS).contains(&g.dims) {
                return Err(Error::invalid(format!("group {}: dims must be 1 to {MAX_DIMS}, got {}", g.name, g.dims)));
            }
            if !(1..=MAX_SPP).contains(&g.spp) {
                return Err(Error::invalid(format!("group {}: spp must be 1 to {MAX_SPP}, got {}", g.name, g.spp)));
            }
            if let Some(first) = self.groups.first().filter(|f| f.spp != g.spp) {
                return Err(Error::invalid(format!(
                    "group {} has spp {} and group {} spp {}: a scene's groups share one spp (a renderer reads \
                     every mask of a plan through one plan block, which holds one)",
                    first.name, first.spp, g.name, g.spp
                )));
            }
        }
        Ok(())
    }
}

/// `budget`: a time as text (`"10s"`, `"500ms"`, `"2m"`) or a number of seconds.
fn check_budget(v: &toml::Value) -> std::result::Result<f64, String> {
    let text = match v {
        toml::Value::String(t) => t.clone(),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::Float(x) => x.to_string(),
        other => other.to_string(),
    };
    crate::optimize::settings::parse_budget(&text).map_err(|e| format!("budget {e}"))
}

fn check_display(
    d: &FileDisplay,
    at: &impl Fn(Range<usize>, String) -> String,
) -> std::result::Result<Display, String> {
    let fps = match &d.fps {
        Some(f) if !FPS_RANGE.contains(f.get_ref()) => {
            return Err(at(f.span(), format!("fps must be in [8, 1000], got {:?}", f.get_ref())))
        }
        Some(f) => *f.get_ref(),
        None => 60.0,
    };
    let taa_alpha = match &d.taa_alpha {
        Some(a) if !ALPHA_RANGE.contains(a.get_ref()) => {
            return Err(at(a.span(), format!("taa_alpha must be in [0.0001, 1], got {:?}", a.get_ref())))
        }
        Some(a) => Some(*a.get_ref()),
        None => None,
    };
    let (spatial, seen_on) = viewing(d, at)?;
    Ok(Display { fps, taa_alpha, spatial, seen_on, animated: d.animated.unwrap_or(true) })
}

/// The spatial filter of a `[display]`: one of a name, ppd, the geometry
/// (resolution, diagonal, distance, all three) or sigma.
fn viewing(
    d: &FileDisplay,
    at: &impl Fn(Range<usize>, String) -> String,
) -> std::result::Result<(Spatial, String), String> {
    let geometry = [
        d.resolution.as_ref().map(|r| r.span()),
        d.diagonal.as_ref().map(|r| r.span()),
        d.distance.as_ref().map(|r| r.span()),
    ];
    let given: Vec<(&str, Range<usize>)> = [
        ("name", d.name.as_ref().map(|v| v.span())),
        ("ppd", d.ppd.as_ref().map(|v| v.span())),
        ("resolution, diagonal and distance", geometry.iter().flatten().next().cloned()),
        ("sigma", d.sigma.as_ref().map(|v| v.span())),
    ]
    .into_iter()
    .filter_map(|(k, s)| s.map(|s| (k, s)))
    .collect();
    if let [_, (second, span), ..] = given.as_slice() {
        return Err(at(
            span.clone(),
            format!(
                "{second} with {}: give the display one way (name, ppd, the geometry or sigma)",
                given[0].0
            ),
        ));
    }
    let on = |ppd: f64, span: Range<usize>, what: String| -> std::result::Result<(Spatial, String), String> {
        let ppd = crate::core::display::check_ppd(ppd).map_err(|e| at(span, e.to_string()))?;
        Ok((Spatial::Display { ppd }, format!("{what}: {ppd:.1} pixels per degree")))
    };
    if let Some(s) = &d.sigma {
        let sigma = *s.get_ref();
        if !SCENE_SIGMA_RANGE.contains(&sigma) {
            return Err(at(s.span(), format!("sigma must be in [0.01, 8] pixels, got {sigma:?}")));
        }
        return Ok((Spatial::Gaussian { sigma }, format!("the eye as a Gaussian of sigma {sigma} pixels")));
    }
    if let Some(p) = &d.ppd {
        return on(*p.get_ref(), p.span(), "the display".into());
    }
    if let Some(n) = &d.name {
        let ppd = crate::core::display::preset_ppd(n.get_ref()).map_err(|e| at(n.span(), e.to_string()))?;
        return on(ppd, n.span(), format!("display {}", n.get_ref()));
    }
    match (&d.resolution, &d.diagonal, &d.distance) {
        (None, None, None) => Ok(Display::default_viewing()),
        (Some(r), Some(g), Some(s)) => {
            let &[w, h] = r.get_ref().as_slice() else {
                return Err(at(r.span(), format!("resolution is [width, height], got {:?}", r.get_ref())));
            };
            let ppd = crate::core::display::pixels_per_degree([w, h], *g.get_ref(), *s.get_ref())
                .map_err(|e| at(r.span(), e.to_string()))?;
            on(ppd, r.span(), format!("a {w} x {h} display of {} in at {} m", g.get_ref(), s.get_ref()))
        }
        _ => {
            let span = geometry.iter().flatten().next().cloned().unwrap_or(0..0);
            Err(at(
                span,
                "the display's geometry needs all of resolution, diagonal (inches) and distance (metres)"
                    .into(),
            ))
        }
    }
}

impl Display {
    fn default_viewing() -> (Spatial, String) {
        let name = crate::core::display::DEFAULT_DISPLAY;
        let ppd = crate::core::display::preset_ppd(name).expect("the default display is a preset"); // ok: a constant
        (Spatial::Display { ppd }, format!("display {name} (the default): {ppd:.1} pixels per degree"))
    }
}

impl Default for Display {
    /// 60 fps, no TAA, animated, seen on the default display.
    fn default() -> Self {
        let (spatial, seen_on) = Display::default_viewing();
        Display { fps: 60.0, taa_alpha: None, spatial, seen_on, animated: true }
    }
}

fn check_group(
    g: &FileGroup,
    at: &impl Fn(Range<usize>, String) -> String,
) -> std::result::Result<Group, String> {
    let name = g.name.get_ref();
    if !valid_group_name(name) {
        return Err(at(g.name.span(), format!("group name {name:?} must be 1 to 64 of [a-z0-9_]")));
    }
    let dims = *g.dims.get_ref();
    if !(1..=MAX_DIMS as i64).contains(&dims) {
        return Err(at(g.dims.span(), format!("dims must be 1 to {MAX_DIMS}, got {dims}")));
    }
    let spp = match &g.spp {
        Some(s) if !(1..=MAX_SPP as i64).contains(s.get_ref()) => {
            return Err(at(s.span(), format!("spp must be 1 to {MAX_SPP}, got {}", s.get_ref())))
        }
        Some(s) => *s.get_ref() as usize,
        None => 1,
    };
    Ok(Group {
        name: name.clone(),
        dims: dims as usize,
        spp,
        visible: g.visible.unwrap_or(true),
        share: g.share.unwrap_or(true),
    })
}

/// A group's name: 1 to 64 of [a-z0-9_] (it names the group's mask files).
fn valid_group_name(name: &str) -> bool {
    (1..=64).contains(&name.len())
        && name.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

/// The most groups a scene holds: each reads at least one part of the plan
/// block, which holds at most this many.
pub const MAX_GROUPS: usize = crate::scene::plan::MAX_BLOCK_PARTS;

/// A scene's eye as a Gaussian: sigma in pixels.
const SCENE_SIGMA_RANGE: std::ops::RangeInclusive<f64> = 0.01..=8.0;

/// The 1-based line of a byte offset.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())].iter().filter(|&&b| b == b'\n').count() + 1
}
