//! Pixel match of `sm`, `spsm` and `spsm-f32` (no antialiasing) against the `raytrace`
//! reference at rate 1 (Lecocq et al. 2014, Fig. 12: 99.63% for SPSM against 97.93% for SM
//! with a 2K map at 1920 x 1080).
//!
//! `cargo run --release --example spsm_pixel_match -- [W H] [--maps 1024,2048]
//! [--scenes spheres,bunny-plane] [--out DIR]`; with `--out`, writes each scene's class image
//! (Fig. 14 colours) as `DIR/SCENE-MAP-classes.png`.
//!
//! Besides the pixel match over every evaluated pixel, the `lf` columns give it over the
//! pixels whose surface faces the light: the paper compares shaded images, where a surface
//! facing away from the light is dark whatever its shadow.

use analysis::{raytrace::RayTrace, Metrics, Reference};
use instrumentation::Recorder;
use methods::{
    pattern::{PatternKind, SamplePattern},
    spsm::{class_image, Spsm, SpsmOptions, TexelFormat},
    Frame, MethodOptions,
};
use std::path::PathBuf;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut size = (1920u32, 1080u32);
    let mut maps = vec![1024u32, 2048];
    let mut names = vec!["spheres".to_string(), "bunny-plane".to_string()];
    let mut out: Option<PathBuf> = None;
    let mut positional = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let value = |it: &mut std::slice::Iter<String>| {
            it.next().cloned().ok_or_else(|| anyhow::anyhow!("{a} needs a value"))
        };
        match a.as_str() {
            "--maps" => {
                maps = value(&mut it)?.split(',').map(str::parse).collect::<Result<_, _>>()?
            }
            "--scenes" => names = value(&mut it)?.split(',').map(String::from).collect(),
            "--out" => out = Some(PathBuf::from(value(&mut it)?)),
            _ => positional.push(a.parse::<u32>()?),
        }
    }
    if let [w, h] = positional[..] {
        size = (w, h);
    }
    if let Some(dir) = &out {
        std::fs::create_dir_all(dir)?;
    }
    println!("frame {}x{}, raytrace at 1 sample per pixel (the pixel centre)", size.0, size.1);
    println!(
        "{:<12} {:>5} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "scene",
        "map",
        "sm %",
        "spsm %",
        "f32 %",
        "sm lf%",
        "spsm lf%",
        "lit1",
        "shad1",
        "shad3x3",
        "uncert",
        "spsm ms"
    );
    for name in &names {
        let scene = match scenes::load(name) {
            Ok(s) => s,
            Err(e) => {
                println!("{name}: skipped ({e})");
                continue;
            }
        };
        let frame = Frame::new(&scene, size.0, size.1, &mut Recorder::default());
        let reference = RayTrace { pattern: SamplePattern::new(1, PatternKind::Grid)? }
            .evaluate(&frame, &mut Recorder::default())?;
        let score = |v: &methods::Visibility| {
            100.0 * Metrics::compare(v, &reference.lit, &reference.evaluated).pixel_match
        };
        let g = &frame.gbuffer;
        let facing: Vec<bool> = (0..g.triangle.len())
            .map(|k| {
                reference.evaluated[k]
                    && g.normal[k].dot(scene.light.direction_to_light(g.position[k])) > 0.0
            })
            .collect();
        let score_facing = |v: &methods::Visibility| {
            100.0 * Metrics::compare(v, &reference.lit, &facing).pixel_match
        };
        for &map_res in &maps {
            let options = MethodOptions { map_res: Some(map_res), ..Default::default() };
            let sm = methods::method("sm", &options)?.run(&frame, &mut Recorder::default())?;
            let mut spsm_opts = SpsmOptions::default();
            spsm_opts.map.map_res = map_res;
            let mut rec = Recorder::default();
            let (spsm, classes) = Spsm { options: spsm_opts }.run_classified(&frame, &mut rec)?;
            spsm_opts.texel = TexelFormat::F32;
            let f32v =
                Spsm { options: spsm_opts }.run_classified(&frame, &mut Recorder::default())?.0;
            let c = &rec.counters;
            println!(
                "{:<12} {:>5} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8.3} {:>8} {:>8} {:>8} {:>8} \
                 {:>8.0}",
                name,
                map_res,
                score(&sm),
                score(&spsm),
                score(&f32v),
                score_facing(&sm),
                score_facing(&spsm),
                c.lit_by_one_lookup,
                c.shadowed_by_one_lookup,
                c.shadowed_by_neighbourhood,
                c.uncertain_pixels,
                rec.stages.total_ms()
            );
            if let Some(dir) = &out {
                let rgb = class_image(&classes, &spsm.lit);
                let img = image::RgbImage::from_fn(size.0, size.1, |x, y| {
                    image::Rgb(rgb[(y * size.0 + x) as usize])
                });
                img.save(dir.join(format!("{name}-{map_res}-classes.png")))?;
            }
        }
    }
    Ok(())
}
