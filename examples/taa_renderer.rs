//! A renderer that uses fsot the way a Vulkan renderer would: headless compute
//! on fsot's `vk` layer (its pipelines and barriers need fsot's `internals`
//! feature, which this crate's examples have), two passes of its own (`examples/shaders/`): the
//! soft-shadow scene of `fsot eval` at 1 sample per pixel per frame, its light
//! sample read through `glsl/include/fsot.glsl`, then TAA with alpha 0.1. The
//! mask is made on the same device and written into the renderer's image
//! (`fsot::make_into_image`), or loaded with `--mask` (a mask file or
//! a plan folder). The same frames are rendered with a white-noise mask through
//! the same include, and a reference with 256 jittered samples per pixel; the
//! pRelMSE after TAA of both against the reference's is `fsot eval`'s (eye
//! sigma 2.1 at 60 fps, the frames after a 48-frame warm-up).
//!
//! cargo run --release --example taa_renderer -- [--frames N] [--size WxH]
//!     [--mask FILE|DIR] [--iterations N | --budget SECONDS] [--seed N] [--out DIR] [--json FILE] [--no-validation]

use std::path::{Path, PathBuf};
use std::time::Instant;

use ash::vk;
use clap::Parser;
// The mask calls, through the public API a renderer uses.
use fsot::{
    layers_for, make_into_image, vk_format, write_plan, CancelFlag, Error, Event, KernelSpec, Mask, Result,
    SamplerPlan, Settings, TexelFormat as Format, Tile,
};
// This renderer's own passes and its measure, on fsot's modules (`internals`).
use fsot::io::atomic::{make_folder, AtomicFile};
use fsot::quality::eye::Eye;
use fsot::quality::metric::relative_errors_rect;
use fsot::vk::commands::barrier;
use fsot::vk::{
    Buffer, ComputeDesc, ComputePipeline, Context, ContextOptions, Image, ImageDesc, Location, Sampler,
};
use shaderc_link::shaderc;

/// TAA's weight of the current frame.
const ALPHA: f32 = 0.1;
/// Samples per pixel of the reference (a 16 x 16 jittered grid).
const REFERENCE_SAMPLES: u32 = 256;
/// Frames before the judge looks (TAA's history settles), as in `fsot eval`.
const WARMUP: usize = 48;
/// The judge's eye: Gaussian sigma in pixels, frames per second.
const SIGMA: f64 = 2.1;
const FPS: f64 = 60.0;

#[derive(Parser)]
#[command(about = "A headless Vulkan TAA renderer sampling with fsot's masks, against white noise")]
struct Args {
    /// Frames to render (the judge skips the first 48).
    #[arg(long, default_value_t = 80)]
    frames: usize,
    /// Image size, WxH (the scene's unit square across the longer side).
    #[arg(long, default_value = "64x64")]
    size: String,
    /// A mask (.exr) or a plan folder (`fsot optimize --scene`) to use instead of
    /// making one on the device; its first part must be 2-D.
    #[arg(long)]
    mask: Option<PathBuf>,
    /// Iterations of the mask made on the device (32x32x16, d = 2, perceptual-taa).
    #[arg(long, default_value_t = 500)]
    iterations: u32,
    /// Make the mask on the device within this many seconds instead of a count
    /// of iterations (`Until::Seconds`).
    #[arg(long)]
    budget: Option<f64>,
    /// Seed of the mask made on the device.
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Write PNG frames (reference | white | fsot, after TAA) and an animated
    /// preview (APNG) here.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the figures as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Run without Vulkan's validation layer (on by default where it is
    /// installed; any message it gives fails the run).
    #[arg(long)]
    no_validation: bool,
}

/// `taa_scene.comp`'s push constants.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ScenePush {
    width: u32,
    height: u32,
    samples: u32,
    seed: u32,
}

/// `taa_resolve.comp`'s push constants.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ResolvePush {
    pixels: u32,
    frames: u32,
    alpha: f32,
}

/// The renderer's shader, compiled as a renderer would: shaderc, with fsot's
/// include directory on the include path.
fn compile(name: &str) -> Result<Vec<u8>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("examples/shaders").join(name);
    let source = std::fs::read_to_string(&path).map_err(|e| Error::io(path.display().to_string(), e))?;
    let compiler = shaderc::Compiler::new().map_err(|e| Error::invalid(format!("shaderc: {e}")))?;
    let mut options = shaderc::CompileOptions::new().map_err(|e| Error::invalid(format!("shaderc: {e}")))?;
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    let include = root.join("glsl/include");
    options.set_include_callback(move |name, _, _, _| {
        let path = include.join(name);
        std::fs::read_to_string(&path)
            .map(|content| shaderc::ResolvedInclude { resolved_name: path.display().to_string(), content })
            .map_err(|e| format!("{}: {e}", path.display()))
    });
    let spirv = compiler
        .compile_into_spirv(&source, shaderc::ShaderKind::Compute, name, "main", Some(&options))
        .map_err(|e| Error::invalid(format!("{name}: {e}")))?;
    Ok(spirv.as_binary_u8().to_vec())
}

/// The renderer's sampling resources for one plan: the masks' image and the plan block.
struct Bound {
    image: Image,
    block: Buffer,
    plan: SamplerPlan,
}

/// An image for `masks` masks of `tile` in r16g16_unorm (d = 2).
fn mask_image(ctx: &Context, tile: &Tile, masks: usize, name: &str) -> Result<Image> {
    let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    let desc = ImageDesc {
        format: vk_format(Format::R16G16Unorm),
        width: tile.width as u32,
        height: tile.height as u32,
        layers: layers_for(tile, masks),
        usage,
    };
    Ok(Image::new(ctx, desc, name)?)
}

/// A plan written into a new image of the renderer's, with its block.
fn bind_plan(ctx: &Context, plan: SamplerPlan, name: &str) -> Result<Bound> {
    let tile = plan.masks()[0].tile;
    let mut image = mask_image(ctx, &tile, plan.masks().len(), name)?;
    // SAFETY: the renderer's own image on this context's device, as `target` states
    // it, used by nothing else until the call returns.
    unsafe { write_plan(ctx, &plan, &image.target(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL))? };
    // SAFETY: `write_plan` left every layer in the target's `layout_after`.
    unsafe { image.set_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL) };
    let block = Buffer::with_data(ctx, &plan.plan_block()?, Location::Device, "plan-block")?;
    Ok(Bound { image, block, plan })
}

/// fsot's mask: loaded, or made on the device straight into the renderer's image.
fn fsot_plan(ctx: &Context, args: &Args) -> Result<(Bound, String)> {
    if let Some(path) = &args.mask {
        let plan = SamplerPlan::load(path)?;
        if plan.parts()[0].dims < 2 {
            return Err(Error::invalid(format!(
                "{}: the scene's light sample is 2-D, the first part of the mask has d = {}",
                path.display(),
                plan.parts()[0].dims
            )));
        }
        if plan.max_dims() > 2 {
            return Err(Error::invalid("this renderer binds r16g16_unorm images: masks of d <= 2"));
        }
        let what = format!("{} (loaded)", path.display());
        return Ok((bind_plan(ctx, plan, "fsot-masks")?, what));
    }
    let tile = Tile::new(32, 32, 16, 1, 2)?;
    let mut settings =
        Settings::new(KernelSpec::from_name("perceptual-taa", SIGMA, None, 0.1, FPS)?, args.seed);
    settings.iterations = args.iterations;
    if let Some(budget) = args.budget {
        settings = settings.iterations(100_000).until(fsot::Until::Seconds(budget));
    }
    let mut image = mask_image(ctx, &tile, 1, "fsot-mask")?;
    let target = image.target(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
    let start = Instant::now();
    let mut report = |e: Event| {
        if let Event::Progress { iteration, iterations, .. } = e {
            if iteration % 100 == 0 || iteration == iterations {
                eprint!("\rmaking the mask on the device: {iteration}/{iterations}");
            }
        }
    };
    // SAFETY: the renderer's own image on this context's device, as `target` states
    // it, used by nothing else until the call returns.
    let mask = unsafe { make_into_image(ctx, tile, settings, &target, &CancelFlag::new(), &mut report)? }
        .ok_or(Error::Interrupted)?;
    eprintln!();
    // SAFETY: `make_into_image` left every layer in the target's `layout_after`.
    unsafe { image.set_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL) };
    let what = format!(
        "32x32x16 perceptual-taa, seed {}, {} iterations made on the device in {:.1} s",
        args.seed,
        mask.meta("iterations").unwrap_or("?"),
        start.elapsed().as_secs_f64()
    );
    let plan = SamplerPlan::single(mask)?;
    let block = Buffer::with_data(ctx, &plan.plan_block()?, Location::Device, "plan-block")?;
    Ok((Bound { image, block, plan }, what))
}

/// Frames as the judge takes them: one f64 image per frame.
fn frames_of(values: &[f32], pixels: usize) -> Vec<Vec<f64>> {
    values.chunks_exact(pixels).map(|f| f.iter().map(|&v| v as f64).collect()).collect()
}

fn main() {
    let args = Args::parse();
    if let Err(e) = run(&args) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run(args: &Args) -> Result<()> {
    let begin = Instant::now();
    let (width, height) = parse_size(&args.size)?;
    let eye = Eye::new(SIGMA, FPS);
    let start = WARMUP.max(eye.history());
    if args.frames <= start {
        return Err(Error::invalid(format!("--frames {}: the judge needs more than {start}", args.frames)));
    }
    if width.min(height) <= 2 * eye.margin {
        return Err(Error::invalid(format!(
            "--size {}: the judge's eye needs more than {} pixels a side",
            args.size,
            2 * eye.margin
        )));
    }
    // Outputs reserved before the work, so a bad path fails now.
    if let Some(dir) = &args.out {
        make_folder(dir)?;
    }
    let json_file = args.json.as_deref().map(AtomicFile::create).transpose()?;
    let (ctx, validation) =
        match Context::new(&ContextOptions { validation: !args.no_validation, device: None }) {
            Err(e) if !args.no_validation => {
                eprintln!("validation layer unavailable ({e}): running without it");
                (Context::new(&ContextOptions::default())?, false)
            }
            made => (made?, !args.no_validation),
        };
    let device = ctx.info().name.clone();
    eprintln!("device: {device}");

    let (fsot, mask_note) = fsot_plan(&ctx, args)?;
    let white_mask = Mask::white(fsot.plan.masks()[0].tile, 1234);
    let white = bind_plan(&ctx, SamplerPlan::single(white_mask)?, "white-mask")?;

    let (pixels, frames) = (width * height, args.frames);
    let bytes = (pixels * frames * 4) as u64;
    let buffer = |name| Buffer::new(&ctx, bytes, Location::Device, name);
    let raw = [buffer("reference")?, buffer("white")?, buffer("fsot")?];
    let resolved = [buffer("reference-taa")?, buffer("white-taa")?, buffer("fsot-taa")?];

    // The scene pass, a descriptor set per render: 0 the reference (fsot's masks
    // bound, none read), 1 white noise, 2 fsot; each writes its own frames.
    let scene_spirv = compile("taa_scene.comp")?;
    let scene = ComputePipeline::new(
        &ctx,
        &ComputeDesc {
            spirv: &scene_spirv,
            bindings: 3,
            images: &[1],
            uniforms: &[2],
            texels: &[],
            full_subgroups: false,
            push_bytes: std::mem::size_of::<ScenePush>() as u32,
            spec: &[],
            sets: 3,
        },
    )?;
    let sampler = Sampler::nearest(&ctx)?;
    let layout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    for (set, (bound, out)) in [(&fsot, &raw[0]), (&white, &raw[1]), (&fsot, &raw[2])].into_iter().enumerate()
    {
        // SAFETY: the images, the sampler and the buffers live until the renders
        // below are done; the mask images are sampled in `layout`.
        unsafe {
            scene.bind_image(set, 1, bound.image.view(), sampler.raw(), layout)?;
            scene.bind(set, &[(0, out), (2, &bound.block)])?;
        }
    }
    let resolve_spirv = compile("taa_resolve.comp")?;
    let resolve = ComputePipeline::new(
        &ctx,
        &ComputeDesc {
            spirv: &resolve_spirv,
            bindings: 2,
            images: &[],
            uniforms: &[],
            texels: &[],
            full_subgroups: false,
            push_bytes: std::mem::size_of::<ResolvePush>() as u32,
            spec: &[],
            sets: 3,
        },
    )?;
    for (set, (input, output)) in raw.iter().zip(&resolved).enumerate() {
        // SAFETY: the buffers live until the renders below are done.
        unsafe { resolve.bind(set, &[(0, input), (1, output)])? };
    }

    let render_start = Instant::now();
    let groups = [(width as u32).div_ceil(8), (height as u32).div_ceil(8), frames as u32];
    ctx.submit(|cmd| {
        for (set, samples) in [(0, REFERENCE_SAMPLES), (1, 1), (2, 1)] {
            let push = ScenePush { width: width as u32, height: height as u32, samples, seed: 99 };
            scene.dispatch(cmd, set, groups, bytemuck::bytes_of(&push));
        }
        barrier(cmd);
        let push = ResolvePush { pixels: pixels as u32, frames: frames as u32, alpha: ALPHA };
        for set in 0..3 {
            resolve.dispatch(cmd, set, [(pixels as u32).div_ceil(64), 1, 1], bytemuck::bytes_of(&push));
        }
        barrier(cmd);
    })?;
    let after_taa: Vec<Vec<Vec<f64>>> = resolved
        .iter()
        .map(|b| b.download::<f32>(pixels * frames).map(|v| frames_of(&v, pixels)))
        .collect::<fsot::vk::Result<_>>()?;
    let render_seconds = render_start.elapsed().as_secs_f64();
    if let Some(first) = ctx.validation_messages().first() {
        return Err(Error::invalid(format!("the Vulkan validation layer reported: {first}")));
    }

    let [reference, white_taa, fsot_taa] = [&after_taa[0], &after_taa[1], &after_taa[2]];
    let seen: Vec<Vec<f64>> = (start..frames).map(|f| eye.filter_rect(reference, f, width, height)).collect();
    let (prelmse_white, _) = relative_errors_rect(white_taa, reference, &seen, &eye, start, [width, height]);
    let (prelmse_mask, _) = relative_errors_rect(fsot_taa, reference, &seen, &eye, start, [width, height]);
    if let Some(dir) = &args.out {
        pictures(dir, width, height, &after_taa)?;
    }
    let seconds = begin.elapsed().as_secs_f64();
    println!("mask: {mask_note}");
    println!(
        "soft-shadow, {width}x{height}, {frames} frames, 1 spp + TAA (alpha {ALPHA}) on {device}, validation {}",
        if validation { "on: no message" } else { "off" }
    );
    println!("render and TAA of the reference, white and fsot: {render_seconds:.2} s");
    println!("pRelMSE after TAA (eye sigma {SIGMA}, {FPS} fps, frames {start}..{frames}):");
    println!("  white noise {prelmse_white:.4e}");
    println!("  fsot        {prelmse_mask:.4e}  ({:.3} x white)", prelmse_mask / prelmse_white);
    println!("{seconds:.1} s in all");
    if let Some(file) = json_file {
        let doc = serde_json::json!({
            "scene": "soft-shadow",
            "frames": frames,
            "width": width,
            "height": height,
            "device": device,
            "validation": validation,
            "mask": mask_note,
            "prelmse_mask": prelmse_mask,
            "prelmse_white": prelmse_white,
            "seconds": seconds,
        });
        file.commit(format!("{}\n", serde_json::to_string_pretty(&doc).unwrap_or_default()).as_bytes())?;
    }
    Ok(())
}

fn parse_size(text: &str) -> Result<(usize, usize)> {
    let bad = || Error::invalid(format!("--size {text:?}: expected WxH, for example 64x64"));
    let (w, h) = text.split_once('x').ok_or_else(bad)?;
    let (w, h): (usize, usize) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if w == 0 || h == 0 || w > 4096 || h > 4096 {
        return Err(Error::invalid(format!("--size {text}: each side from 1 to 4096")));
    }
    Ok((w, h))
}

/// Each frame after TAA as one PNG strip (reference | white | fsot, 3x
/// enlarged), tone-mapped by the reference's brightest pixel with gamma 2.2 as
/// `fsot eval`'s pictures are, and all of them as an animated PNG.
fn pictures(dir: &Path, width: usize, height: usize, sets: &[Vec<Vec<f64>>]) -> Result<()> {
    const SCALE: usize = 3;
    const GAP: usize = 4;
    let frames = sets[0].len();
    let peak = sets[0].iter().flatten().fold(1e-9f64, |a, &b| a.max(b));
    let (w, h) = (3 * width * SCALE + 2 * GAP, height * SCALE);
    let strip = |f: usize| -> Vec<u8> {
        let mut out = vec![255u8; w * h];
        for (k, set) in sets.iter().enumerate() {
            for y in 0..h {
                for x in 0..width * SCALE {
                    let v = (set[f][(y / SCALE) * width + x / SCALE] / peak).clamp(0.0, 1.0);
                    out[y * w + k * (width * SCALE + GAP) + x] = (v.powf(1.0 / 2.2) * 255.0).round() as u8;
                }
            }
        }
        out
    };
    let png_error = |e: png::EncodingError| Error::invalid(format!("PNG: {e}"));
    let frames_dir = dir.join("frames");
    make_folder(&frames_dir)?;
    let mut animation = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut animation, w as u32, h as u32);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_animated(frames as u32, 0).map_err(png_error)?;
        encoder.set_frame_delay(1, 30).map_err(png_error)?;
        let mut writer = encoder.write_header().map_err(png_error)?;
        for f in 0..frames {
            let pixels = strip(f);
            writer.write_image_data(&pixels).map_err(png_error)?;
            let mut one = Vec::new();
            let mut encoder = png::Encoder::new(&mut one, w as u32, h as u32);
            encoder.set_color(png::ColorType::Grayscale);
            encoder.set_depth(png::BitDepth::Eight);
            let mut single = encoder.write_header().map_err(png_error)?;
            single.write_image_data(&pixels).map_err(png_error)?;
            single.finish().map_err(png_error)?;
            AtomicFile::create(&frames_dir.join(format!("{f:04}.png")))?.commit(&one)?;
        }
        writer.finish().map_err(png_error)?;
    }
    AtomicFile::create(&dir.join("preview.png"))?.commit(&animation)
}
