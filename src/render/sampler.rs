//! What a renderer binds to read fsot's masks through `glsl/include/fsot.glsl`
//! (or `wgsl/fsot.wgsl`):
//! every mask of a plan stacked in one 2-D array image, and the plan block (the
//! tile and, per part in the order the renderer consumes them, the offset, the
//! base layer and the toroidal shift). A single mask is a one-part plan.
//!
//! `SamplerPlan::value` is the include's formula on the CPU (the same f32
//! operations), for tests and for renderers that sample on the host.

use std::path::Path;

use bytemuck::{Pod, Zeroable};
use serde::Deserialize;

use crate::core::kernel::Spatial;
use crate::core::mask::Mask;
use crate::error::{Error, Result};
use crate::io::ktx2::Format;
use crate::optimize::clock::{self, Stamp};
use crate::optimize::run::{CancelFlag, Outcome, Run, RunOptions};
use crate::optimize::settings::Until;
use crate::scene::plan::{Plan, PlanEvent};

/// Parts the include's plan block holds by default (`FSOT_MAX_PARTS`).
pub const MAX_PARTS: usize = 16;
pub use crate::scene::plan::MAX_BLOCK_PARTS;

/// Roberts' R4 sequence in 0.32 fixed point (`FSOT_R4` in the include).
pub const R4: [u32; 4] = [3_679_390_609, 3_152_041_523, 2_700_274_806, 2_313_257_605];

/// One part of the plan block (`FsotPart`, std140: 32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PartBlock {
    /// x, y, frame offset; the mask's base layer.
    pub offset_base: [u32; 4],
    pub shift: [f32; 4],
}

/// The head of the plan block (`FsotPlan` before its parts).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PlanHead {
    /// W, H, T, spp.
    pub tile: [u32; 4],
    /// Parts, then 0, 0, 0.
    pub count: [u32; 4],
}

/// One read of the plan: which mask, where, how shifted.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplerPart {
    /// Index of the mask it reads in `SamplerPlan::masks`.
    pub mask: usize,
    /// Dimensions it reads, at most the mask's (and at most 4).
    pub dims: usize,
    /// Pixel x, y and frame offset at which it reads the mask.
    pub offset: [u32; 3],
    /// Toroidal shift added to each dimension it reads (`dims` values).
    pub shift: Vec<f32>,
}

/// A plan ready to bind: masks that share W, H, T and spp (each of at most 4
/// dimensions), and the parts that read them. Made only by its constructors,
/// which check it, so every method below holds.
#[derive(Clone, Debug)]
pub struct SamplerPlan {
    masks: Vec<Mask>,
    parts: Vec<SamplerPart>,
}

#[derive(Deserialize)]
struct PlanFile {
    tile: [usize; 3],
    groups: Vec<GroupFile>,
}

#[derive(Deserialize)]
struct GroupFile {
    parts: Vec<PartFile>,
}

#[derive(Deserialize)]
struct PartFile {
    mask: String,
    dims: usize,
    offset: [u32; 3],
    shift: Vec<f32>,
}

/// The masks of `plan` made one after another on the backend `options` choose
/// (white noise where the plan says so), each run under its share of the plan's
/// budget counted from `origin` (a clock checked for first). None when `cancel`
/// stopped a run.
pub(crate) fn plan_masks(
    plan: &Plan,
    origin: Stamp,
    options: &RunOptions,
    cancel: &CancelFlag,
    on: &mut dyn FnMut(PlanEvent),
) -> Result<Option<Vec<Mask>>> {
    plan.check()?;
    if plan.budget.is_some() {
        clock::needs_clock("a plan's time budget")?;
    }
    // Each display's eye fitted now (once per process), not out of the first
    // mask's share of the budget.
    for m in &plan.masks {
        if let Spatial::Display { ppd } = m.spec.spatial {
            crate::core::csf::mixture(ppd);
        }
    }
    let optimized: Vec<usize> = (0..plan.masks.len()).filter(|&i| !plan.masks[i].white).collect();
    let mut ends = plan.run_ends(&optimized, origin, false)?.into_iter();
    let mut masks = Vec::with_capacity(plan.masks.len());
    for (index, m) in plan.masks.iter().enumerate() {
        let tile = plan.tile(m)?;
        if m.white {
            masks.push(Mask::white(tile, m.seed));
            continue;
        }
        let mut settings = plan.settings(m);
        if let Some(Some(end)) = ends.next() {
            settings.until = Until::Seconds(end);
        }
        let options =
            RunOptions { budget_from: origin.instant(), cancel_start: Some(cancel.clone()), ..options.clone() };
        let mut run = match Run::start(tile, settings, None, options) {
            Err(Error::Interrupted) => return Ok(None),
            run => run?,
        };
        on(PlanEvent::Start { index, file: &m.file, iteration: 0, backend: run.note() });
        if let Outcome::Cancelled { .. } = run.run(cancel, &mut |event| on(PlanEvent::Run { index, event }))? {
            return Ok(None);
        }
        let (iterations, seconds) = (run.iteration(), run.seconds());
        masks.push(run.finish()?);
        on(PlanEvent::Done { index, file: &m.file, iterations, seconds });
    }
    Ok(Some(masks))
}

impl SamplerPlan {
    /// A plan of `masks` read by `parts`, checked: at least one mask, every
    /// mask valid (`Mask::check`) of at most 4 dimensions, all of one W, H, T
    /// and spp; every part reading a mask of the list, 1 to that mask's
    /// dimensions, with a shift in [0, 1) per dimension it reads; at most
    /// `MAX_BLOCK_PARTS` parts.
    pub fn new(masks: Vec<Mask>, parts: Vec<SamplerPart>) -> Result<Self> {
        let plan = Self { masks, parts };
        plan.check()?;
        Ok(plan)
    }

    /// One mask read as one part: offset 0, no shift.
    pub fn single(mask: Mask) -> Result<Self> {
        let dims = mask.tile.dims;
        Self::new(vec![mask], vec![SamplerPart { mask: 0, dims, offset: [0; 3], shift: vec![0.0; dims] }])
    }

    /// The masks, in the order the parts first read them.
    pub fn masks(&self) -> &[Mask] {
        &self.masks
    }

    /// The reads, in the order the renderer consumes them.
    pub fn parts(&self) -> &[SamplerPart] {
        &self.parts
    }

    /// A plan folder (`read`) or a mask file (`.exr` or `.ktx2`: `Mask::open`; a one-part plan).
    pub fn load(path: &Path) -> Result<Self> {
        match path.is_dir() {
            true => Self::read(path),
            false => Self::single(Mask::open(path)?),
        }
    }

    /// The plan `fsot optimize --scene` wrote into `dir` (`plan.json` and its masks).
    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join("plan.json");
        let text = crate::io::read_regular_text(&path).map_err(|e| Error::io(path.display().to_string(), e))?;
        let file: PlanFile = serde_json::from_str(&text)
            .map_err(|e| Error::invalid(format!("{}: not a plan file: {e}", path.display())))?;
        let parts = file
            .groups
            .iter()
            .flat_map(|g| &g.parts)
            .map(|p| (p.mask.as_str(), p.dims, p.offset, &p.shift[..]));
        Self::assemble(&format!("{}: ", path.display()), parts, |name| {
            if !crate::scene::plan::is_plain_mask_name(name) {
                return Err(Error::invalid(format!("{}: bad mask name {name:?}", path.display())));
            }
            let mask = crate::io::exr::read(&dir.join(name))?;
            let t = mask.tile;
            if [t.width, t.height, t.frames] != file.tile {
                return Err(Error::invalid(format!(
                    "{}: {name} is {}x{}x{}, the plan's tile {:?}",
                    path.display(),
                    t.width,
                    t.height,
                    t.frames,
                    file.tile
                )));
            }
            Ok(mask)
        })
        .map_err(|e| match e {
            Error::Invalid(m) if m.starts_with("a part of") => {
                Error::invalid(format!("{}: {m}", path.display()))
            }
            e => e,
        })
    }

    /// Makes every mask of a scene plan in memory, on the backend `options`
    /// choose (on Vulkan one device for them all), and returns them as the
    /// includes read them: `texels(format)` for the image, `plan_block()` for the
    /// block. Each mask is the one `fsot optimize --scene` makes (the plateau rule
    /// stopping it, white noise for what is not visible): on the CPU the same
    /// samples (tested); under the plan's budget the masks run one after another,
    /// each in its share of it, where `--scene` on one device runs them side by
    /// side to the budget's end. No file is written and no checkpoint taken, so
    /// it runs on the web too (where the plan takes no budget: there is no
    /// clock). The budget counts from `options.budget_from`, else from this call;
    /// `cancel` stops it (None), the start of a mask's run included (it replaces
    /// `options.cancel_start`).
    ///
    /// ```
    /// use fsot::{CancelFlag, CostModel, Plan, RunOptions, SamplerPlan, Scene, TexelFormat};
    ///
    /// // A small tile, for the example.
    /// let text = "[display]\nfps = 60\ntaa_alpha = 0.1\n[tile]\nsize = \"16x16x4\"\n[[group]]\nname = \"light\"\ndims = 2\n";
    /// let scene = Scene::parse(text, "s").map_err(fsot::Error::invalid)?;
    /// let plan = Plan::new(&scene, &CostModel::unmeasured())?;
    /// let made = SamplerPlan::make(&plan, RunOptions::default(), &CancelFlag::new(), &mut |_| {})?
    ///     .ok_or_else(|| fsot::Error::invalid("cancelled"))?; // None: the flag stopped it
    /// let texels = made.texels(TexelFormat::R8G8Unorm)?; // the 2-D array image, layer by layer
    /// let block = made.plan_block()?; // the include's uniform block
    /// assert_eq!(texels.len(), 16 * 16 * 4 * 2);
    /// assert_eq!(block.len(), 32 + 32 * 16);
    /// # Ok::<(), fsot::Error>(())
    /// ```
    pub fn make(
        plan: &Plan,
        options: RunOptions,
        cancel: &CancelFlag,
        on: &mut dyn FnMut(PlanEvent),
    ) -> Result<Option<Self>> {
        let origin = options.budget_from.map_or_else(Stamp::now, Stamp::at);
        if options.checkpoint.is_some() {
            return Err(Error::invalid(
                "a plan made in memory takes no checkpoints (`Plan::execute` takes them into its folder)",
            ));
        }
        let options = crate::optimize::run::shared_context(&options)?;
        plan_masks(plan, origin, &options, cancel, on)?.map(|masks| Self::from_plan(plan, masks)).transpose()
    }

    /// A plan made in memory (`SamplerPlan::make`, `fsot::make_plan_into_image`): `masks[i]` is
    /// the mask of `plan.masks[i]`; laid out as `read` lays out the folder
    /// `Plan::execute` writes.
    pub fn from_plan(plan: &crate::scene::plan::Plan, masks: Vec<Mask>) -> Result<Self> {
        plan.check()?;
        if masks.len() != plan.masks.len() {
            return Err(Error::invalid(format!("{} masks for a plan of {}", masks.len(), plan.masks.len())));
        }
        for (planned, mask) in plan.masks.iter().zip(&masks) {
            let tile = plan.tile(planned)?;
            if mask.tile != tile {
                return Err(Error::invalid(format!(
                    "the mask given for {} is {}; the plan's is {}",
                    planned.file,
                    mask.tile.describe(),
                    tile.describe()
                )));
            }
            mask.check()?;
        }
        let mut masks: Vec<Option<Mask>> = masks.into_iter().map(Some).collect();
        let parts = plan
            .groups
            .iter()
            .flat_map(|g| &g.parts)
            .map(|p| (p.mask.as_str(), p.dims, p.offset, &p.shift[..]));
        Self::assemble("", parts, |name| {
            plan.masks
                .iter()
                .position(|m| m.file == name)
                .and_then(|i| masks[i].take())
                .ok_or_else(|| Error::invalid(format!("the plan has no mask {name}")))
        })
    }

    /// The masks in the order the parts first read them, each loaded once;
    /// errors start with `context`.
    fn assemble<'a>(
        context: &str,
        parts: impl Iterator<Item = (&'a str, usize, [u32; 3], &'a [f32])>,
        mut load: impl FnMut(&str) -> Result<Mask>,
    ) -> Result<Self> {
        let mut names: Vec<&str> = Vec::new();
        let mut plan = Self { masks: Vec::new(), parts: Vec::new() };
        for (name, dims, offset, shift) in parts {
            let index = match names.iter().position(|n| *n == name) {
                Some(i) => i,
                None => {
                    plan.masks.push(load(name)?);
                    names.push(name);
                    names.len() - 1
                }
            };
            if dims > plan.masks[index].tile.dims || shift.len() != dims {
                return Err(Error::invalid(format!("{context}a part of {name} does not fit it")));
            }
            plan.parts.push(SamplerPart { mask: index, dims, offset, shift: shift.to_vec() });
        }
        plan.check()?;
        Ok(plan)
    }

    fn check(&self) -> Result<()> {
        let first = self.masks.first().ok_or_else(|| Error::invalid("a plan without masks"))?.tile;
        for m in &self.masks {
            m.check()?;
            let t = m.tile;
            if (t.width, t.height, t.frames, t.spp) != (first.width, first.height, first.frames, first.spp) {
                return Err(Error::invalid("the masks of one sampler plan share W, H, T and spp"));
            }
            if t.dims > 4 {
                return Err(Error::invalid(format!(
                    "a mask of the sampler holds at most 4 dimensions, not {}",
                    t.dims
                )));
            }
        }
        if self.parts.len() > MAX_BLOCK_PARTS {
            return Err(Error::invalid(format!(
                "{} parts, a plan block holds at most {MAX_BLOCK_PARTS}",
                self.parts.len()
            )));
        }
        for (k, p) in self.parts.iter().enumerate() {
            let mask = self.masks.get(p.mask).ok_or_else(|| {
                Error::invalid(format!("part {k} reads mask {}, the plan has {}", p.mask, self.masks.len()))
            })?;
            if p.dims == 0 || p.dims > mask.tile.dims {
                return Err(Error::invalid(format!(
                    "part {k} reads {} dimensions of a mask of {}",
                    p.dims, mask.tile.dims
                )));
            }
            if p.shift.len() != p.dims || !p.shift.iter().all(|s| (0.0..1.0).contains(s)) {
                return Err(Error::invalid(format!(
                    "part {k} needs a shift in [0, 1) per dimension it reads ({}), got {:?}",
                    p.dims, p.shift
                )));
            }
        }
        Ok(())
    }

    /// W, H, T, spp.
    pub fn tile(&self) -> [u32; 4] {
        let t = self.masks[0].tile;
        [t.width as u32, t.height as u32, t.frames as u32, t.spp as u32]
    }

    /// Layers per mask (T x spp); mask m starts at layer m x this.
    pub fn layers_per_mask(&self) -> u32 {
        let t = self.tile();
        t[2] * t[3]
    }

    /// The largest dimension of the masks: the image's format needs that many channels.
    pub fn max_dims(&self) -> usize {
        self.masks.iter().map(|m| m.tile.dims).max().unwrap_or(1)
    }

    /// The plan block for the include with `FSOT_MAX_PARTS` = `capacity`, at
    /// most `MAX_BLOCK_PARTS`.
    pub fn plan_block_for(&self, capacity: usize) -> Result<Vec<u8>> {
        if capacity > MAX_BLOCK_PARTS {
            return Err(Error::invalid(format!(
                "a plan block of {capacity} parts; at most {MAX_BLOCK_PARTS} (64 KiB)"
            )));
        }
        if self.parts.len() > capacity {
            let hint = match capacity == MAX_PARTS {
                true => " (define FSOT_MAX_PARTS and use plan_block_for)",
                false => "",
            };
            return Err(Error::invalid(format!(
                "{} parts, the block holds {capacity}{hint}",
                self.parts.len()
            )));
        }
        let head = PlanHead { tile: self.tile(), count: [self.parts.len() as u32, 0, 0, 0] };
        let mut out = bytemuck::bytes_of(&head).to_vec();
        for k in 0..capacity {
            let block = match self.parts.get(k) {
                Some(p) => {
                    let mut shift = [0.0; 4];
                    shift[..p.shift.len()].copy_from_slice(&p.shift);
                    PartBlock {
                        offset_base: [
                            p.offset[0],
                            p.offset[1],
                            p.offset[2],
                            p.mask as u32 * self.layers_per_mask(),
                        ],
                        shift,
                    }
                }
                None => PartBlock::default(),
            };
            out.extend_from_slice(bytemuck::bytes_of(&block));
        }
        Ok(out)
    }

    /// The plan block for the include's default `FSOT_MAX_PARTS` (16).
    pub fn plan_block(&self) -> Result<Vec<u8>> {
        self.plan_block_for(MAX_PARTS)
    }

    /// The stacked 2-D array image's texels in `format` (checked to hold every
    /// mask): mask by mask, layer by layer, as `io::ktx2` lays out one mask.
    pub fn texels(&self, format: Format) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        for m in &self.masks {
            out.extend(crate::io::ktx2::texels(m, format)?);
        }
        Ok(out)
    }

    /// The include's `fsot_get` for `part` at pixel (x, y), frame and sample,
    /// from texels as `format` stores them; past the last part, None (the
    /// include's hash fallback), and None for a format with fewer channels than
    /// the part's mask. The include reads parts below its
    /// `FSOT_MAX_PARTS` (16 by default) and takes the fallback past them.
    pub fn value(
        &self,
        part: usize,
        x: u32,
        y: u32,
        frame: u32,
        sample: u32,
        format: Format,
    ) -> Option<[f32; 4]> {
        let p = self.parts.get(part)?;
        // A format with fewer channels than the mask's d cannot hold it (`texels`
        // refuses it): no value.
        if self.masks[p.mask].tile.dims > format.channels() {
            return None;
        }
        let [w, h, t, spp] = self.tile();
        let f = frame.wrapping_add(p.offset[2]);
        let turn = f / t;
        let m = &self.masks[p.mask];
        // 32-bit unsigned arithmetic, as the include's.
        let texel = m.sample(
            (x.wrapping_add(p.offset[0]) % w) as usize,
            (y.wrapping_add(p.offset[1]) % h) as usize,
            (f % t) as usize,
            (sample % spp) as usize,
        );
        let mut out = [0.0f32; 4];
        for (j, o) in out.iter_mut().enumerate() {
            let stored = texel.get(j).copied().unwrap_or(0.0);
            let v = match format.bits() {
                // A channel the format lacks reads as Vulkan fills it: 0, alpha 1.
                _ if j >= format.channels() => (j == 3) as u32 as f32,
                32 => stored,
                b => {
                    let top = ((1u64 << b) - 1) as f32;
                    crate::io::ktx2::quantize(stored, b) as f32 / top
                }
            };
            let r = (turn.wrapping_mul(R4[j]) >> 8) as f32 * (1.0 / 16_777_216.0);
            let s = p.shift.get(j).copied().unwrap_or(0.0);
            let sum = v + s + r;
            *o = sum - sum.floor();
        }
        Some(out)
    }
}
