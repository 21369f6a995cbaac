//! `embree-side-by-side`: our ray tracer and shadow methods beside Intel Embree, in one
//! process, on the same frames and sample points, at one thread count (see the library's
//! documentation). Prints one Markdown table, with ratios (ours / Embree: above 1, Embree is
//! faster); on `bunny-plane` also `spsm` against `sm` at 1920x1080 (there the ratio is
//! `spsm / sm`, the "Embree" column holding `sm`'s time).
//!
//! Usage: `embree-side-by-side [--threads N] [--repeats R] [--scenes a,b,...]` (built with
//! `--features embree`; `scripts/embree-bench` runs it at 1 and 2 threads), or
//! `embree-side-by-side scaling [...]`: cost against work (the `papers` report's two
//! cost-against-work tables), without Embree.

fn main() -> anyhow::Result<()> {
    if std::env::args().nth(1).as_deref() == Some("scaling") {
        return scaling::run();
    }
    side_by_side()
}

#[cfg(not(feature = "embree"))]
fn side_by_side() -> anyhow::Result<()> {
    eprintln!(
        "embree-side-by-side was built without Embree: run scripts/embree-bench (it installs \
         Debian's libembree-dev and builds with --features embree); `embree-side-by-side \
         scaling` needs no Embree"
    );
    std::process::exit(2);
}

#[cfg(feature = "embree")]
fn side_by_side() -> anyhow::Result<()> {
    side_by_side::run()
}

/// `embree-side-by-side scaling [--threads N] [--repeats R] [--out DIR]`: cost against work,
/// the `papers` report's two cost-against-work tables (`reports::tables`, measured by the
/// same code), as Markdown on standard output and log-log charts in DIR (default
/// `shadowbench-out`): `cost-against-triangles.{png,svg}` and `cost-against-pixels.{png,svg}`.
mod scaling {
    use anyhow::{bail, Context};
    use reports::sweep::run_table;
    use reports::tables::{chart, markdown, PaperTable, TableSpec};
    use std::path::PathBuf;

    pub fn run() -> anyhow::Result<()> {
        let (mut threads, mut repeats, mut out) = (0usize, 1u32, PathBuf::from("shadowbench-out"));
        let mut it = std::env::args().skip(2);
        while let Some(flag) = it.next() {
            let mut value = || it.next().with_context(|| format!("{flag} needs a value"));
            match flag.as_str() {
                "--threads" => threads = value()?.parse().context("--threads: a count")?,
                "--repeats" => repeats = value()?.parse().context("--repeats: a count")?,
                "--out" => out = PathBuf::from(value()?),
                other => {
                    bail!("unknown flag {other}: scaling [--threads N] [--repeats R] [--out DIR]")
                }
            }
        }
        if threads > 0 {
            rayon::ThreadPoolBuilder::new().num_threads(threads).build_global()?;
        }
        std::fs::create_dir_all(&out)
            .with_context(|| format!("cannot create {}", out.display()))?;
        println!(
            "# Cost against work ({} rayon threads, median of {repeats} runs)\n",
            rayon::current_num_threads()
        );
        for paper in [PaperTable::CostAgainstTriangles, PaperTable::CostAgainstPixels] {
            let spec = TableSpec { paper, scenes: Vec::new(), width: 0, height: 0 };
            let mut skipped = Vec::new();
            let protocol = instrumentation::measure::Protocol::fixed(0, repeats as u32);
            let table = run_table(&spec, &protocol, &mut skipped, |_| {});
            for s in &skipped {
                eprintln!("note: {s}");
            }
            println!("{}", markdown(&table));
            if let Some(c) = chart(&table) {
                reports::plots::write_chart(&out.join(paper.name()), &c)?;
            }
        }
        println!("charts: {}", out.join("cost-against-*.png").display());
        Ok(())
    }
}

#[cfg(feature = "embree")]
mod side_by_side {
    use anyhow::{bail, Context};
    use bench::embree_tracer::{trace, Api};
    use bench::{median, Samples};
    use instrumentation::Recorder;
    use methods::pattern::{PatternKind, SamplePattern};
    use methods::{Frame, MethodOptions};

    const SCENES: [&str; 6] =
        ["random-10k", "random-100k", "random-1m", "bunny-plane", "cage", "bumpy"];

    struct Args {
        threads: usize,
        repeats: usize,
        scenes: Vec<String>,
    }

    fn args() -> anyhow::Result<Args> {
        let mut a = Args { threads: 1, repeats: 3, scenes: SCENES.map(String::from).to_vec() };
        let mut it = std::env::args().skip(1);
        while let Some(flag) = it.next() {
            let mut value = || it.next().with_context(|| format!("{flag} needs a value"));
            match flag.as_str() {
                "--threads" => a.threads = value()?.parse().context("--threads: a count")?,
                "--repeats" => a.repeats = value()?.parse().context("--repeats: a count")?,
                "--scenes" => a.scenes = value()?.split(',').map(String::from).collect(),
                "--help" | "-h" => {
                    println!("embree-side-by-side [--threads N] [--repeats R] [--scenes a,b,...]");
                    std::process::exit(0);
                }
                other => bail!("unknown flag {other} (see --help)"),
            }
        }
        if a.threads == 0 || a.repeats == 0 {
            bail!("--threads and --repeats must be at least 1");
        }
        Ok(a)
    }

    /// Median over `repeats` runs of `f`'s milliseconds.
    fn timed(repeats: usize, mut f: impl FnMut() -> f64) -> f64 {
        let mut t: Vec<f64> = (0..repeats).map(|_| f()).collect();
        median(&mut t)
    }

    /// Our `raytrace` at `rate`: BVH build and ray tracing, milliseconds, and rays traced.
    fn ours_raytrace(
        frame: &Frame<'_>,
        rate: u32,
        repeats: usize,
    ) -> anyhow::Result<(f64, f64, u64)> {
        let pattern = SamplePattern::new(rate, PatternKind::Grid)?;
        let rt = analysis::raytrace::RayTrace { pattern };
        let mut rays = 0;
        let mut build = Vec::new();
        let mut tracing = Vec::new();
        for _ in 0..repeats {
            let mut rec = Recorder::default();
            analysis::Reference::evaluate(&rt, frame, &mut rec)?;
            let stage = |n: &str| {
                rec.stages.stages.iter().filter(|s| s.name == n).map(|s| s.ms).sum::<f64>()
            };
            build.push(stage(analysis::raytrace::STAGE_BVH_BUILD));
            tracing.push(stage(analysis::raytrace::STAGE_RAY_TRACING));
            rays = rec.counters.rays_traced;
        }
        Ok((median(&mut build), median(&mut tracing), rays))
    }

    /// A method's total stage time, milliseconds (the camera G-buffer is the frame's).
    fn ours_method(
        frame: &Frame<'_>,
        name: &str,
        options: &MethodOptions,
        repeats: usize,
    ) -> anyhow::Result<f64> {
        let t = analysis::registry::technique(name, options)?;
        let mut times = Vec::new();
        for _ in 0..repeats {
            let mut rec = Recorder::default();
            t.run(frame, &mut rec)?;
            times.push(rec.stages.total_ms());
        }
        Ok(median(&mut times))
    }

    pub fn run() -> anyhow::Result<()> {
        let a = args()?;
        rayon::ThreadPoolBuilder::new().num_threads(a.threads).build_global()?;
        let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
        println!(
            "# Embree 3 beside shadowbench: {} rayon threads ({cores} cores available to the \
             process, which bounds Embree's BVH build), median of {} runs\n",
            a.threads, a.repeats
        );
        println!("| scene | frame | triangles | camera G-buffer ms | measure | ours ms | Embree ms | ours / Embree | ours Mrays/s | Embree Mrays/s |");
        println!("|---|---|---|---|---|---|---|---|---|---|");
        for name in &a.scenes {
            let scene = match scenes::load(name) {
                Ok(s) => s,
                Err(e) => {
                    println!("| {name} | skipped: {e} |||||||||");
                    continue;
                }
            };
            for (rate_frame, rate) in [(None, 1u32), (Some((320, 240)), 64)] {
                let (w, h) = rate_frame.unwrap_or((scene.width, scene.height));
                let mut rec = Recorder::default();
                let frame = Frame::new(&scene, w, h, &mut rec);
                let gbuffer = rec.stages.total_ms();
                let pattern = SamplePattern::new(rate, PatternKind::Grid)?;
                let samples = Samples::new(&frame, &pattern);
                let (ob, ot, rays) = ours_raytrace(&frame, rate, a.repeats)?;
                for api in [Api::PerRay, Api::Stream16] {
                    let mut last = None;
                    let e = timed(a.repeats, || {
                        let t = trace(&frame, &samples, api);
                        let ms = t.build_ms + t.camera_ms + t.shadow_ms;
                        last = Some(t);
                        ms
                    });
                    let Some(t) = last else { continue };
                    let erays = t.camera_rays + t.shadow_rays;
                    row(
                        name,
                        (w, h),
                        frame.geometry.len(),
                        gbuffer,
                        &format!(
                            "raytrace rate {rate} vs Embree {api:?} (BVH + camera + shadow rays)"
                        ),
                        ob + ot,
                        e,
                        (rays as f64 / ot, erays as f64 / (t.camera_ms + t.shadow_ms)),
                    );
                }
                if rate != 1 {
                    continue;
                }
                // afsm decides the same pixel-centre shadows: its stages against Embree's BVH
                // over the casters plus the shadow rays from the camera's hits.
                let afsm = ours_method(&frame, "afsm", &MethodOptions::default(), a.repeats)?;
                let mut last = None;
                let e = timed(a.repeats, || {
                    let t = trace(&frame, &samples, Api::PerRay);
                    let ms = t.build_ms + t.shadow_ms;
                    last = Some(t);
                    ms
                });
                let shadow_rays = last.map_or(0, |t| t.shadow_rays);
                row(
                    name,
                    (w, h),
                    frame.geometry.len(),
                    gbuffer,
                    "afsm vs Embree BVH + shadow rays",
                    afsm,
                    e,
                    (f64::NAN, shadow_rays as f64 / e),
                );
                // pan09 at 32x against Embree supersampling the same frame at 32x.
                let options = MethodOptions { rate: Some(32), ..Default::default() };
                let pan = ours_method(&frame, "pan09", &options, a.repeats)?;
                let p32 = SamplePattern::new(32, PatternKind::Grid)?;
                let s32 = Samples::new(&frame, &p32);
                let e = timed(a.repeats, || {
                    let t = trace(&frame, &s32, Api::PerRay);
                    t.build_ms + t.camera_ms + t.shadow_ms
                });
                row(
                    name,
                    (w, h),
                    frame.geometry.len(),
                    gbuffer,
                    "pan09 32x vs Embree 32x supersampling",
                    pan,
                    e,
                    (f64::NAN, f64::NAN),
                );
                if name == "bunny-plane" {
                    // Lecocq et al.'s Table 2: the sub-pixel shadow map's cost over a shadow map
                    // of the same size, at 1920x1080.
                    let mut rec = Recorder::default();
                    let hd = Frame::new(&scene, 1920, 1080, &mut rec);
                    for map in [1024, 4096] {
                        let options = MethodOptions { map_res: Some(map), ..Default::default() };
                        let spsm = ours_method(&hd, "spsm", &options, a.repeats)?;
                        let sm = ours_method(&hd, "sm", &options, a.repeats)?;
                        let what = format!("spsm vs sm, map {map} (Lecocq et al.: 1.27-1.81)");
                        let triangles = hd.geometry.len();
                        let gbuffer = rec.stages.total_ms();
                        row(
                            name,
                            (1920, 1080),
                            triangles,
                            gbuffer,
                            &what,
                            spsm,
                            sm,
                            (f64::NAN, f64::NAN),
                        );
                    }
                }
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn row(
        scene: &str,
        (w, h): (u32, u32),
        triangles: usize,
        gbuffer: f64,
        measure: &str,
        ours: f64,
        embree: f64,
        (ours_rate, embree_rate): (f64, f64),
    ) {
        let mrays = |r: f64| if r.is_finite() { format!("{:.2}", r / 1e3) } else { "–".into() };
        println!(
            "| {scene} | {w}x{h} | {triangles} | {gbuffer:.1} | {measure} | {ours:.1} | {embree:.1} | {:.2} | {} | {} |",
            ours / embree,
            mrays(ours_rate),
            mrays(embree_rate)
        );
    }
}
