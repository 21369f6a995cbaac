//! `embree-side-by-side`: our ray tracer and shadow methods beside Intel Embree, in one
//! process, on the same frames and sample points, at one thread count (see the library's
//! documentation). Prints one Markdown table, with ratios (ours / Embree: above 1, Embree is
//! faster) of the medians and, beside them, the range of the ratios of single rounds (a range
//! that holds 1 leaves the faster side undecided); on `bunny-plane` also `spsm` against `sm`
//! at 1920x1080 (there the ratio is `spsm / sm`, the "Embree" column holding `sm`'s time).
//! Then, for `bunny-plane`, `bumpy`, `cage` and `random-1m` among the scenes, a second table:
//! the exact reference beside `sm` at map 1024 on the same frame (with the range of single
//! rounds' ratios too), its largest stages, and `raytrace` at rate 64. Each table names the
//! machine (its CPU model and the 1-minute load average at its start) and ends with the load
//! average at its end, the share of the cores other processes took over its timed runs
//! (`Conditions::others_share` of each subject, weighted by its runs' time) and how many runs
//! were contended: ratios of two machines, or of a busy one, are not comparable.
//!
//! Timing: every figure is measured by the workbench's one timing loop,
//! `instrumentation::measure::measure_all`, under `Protocol::fixed(1, R)`: one untimed warm-up,
//! then exactly `R` timed runs (`--repeats`, default 3; the exact table at least 7), the runs
//! of one frame (ours and Embree's, every row of the frame) interleaved round by round.
//! Embree's BVH build, camera rays and shadow rays are stages of its runs
//! (`bench::embree_tracer`), as ours are of our methods', so both sides' times are the
//! wall-clock medians of the per-run stage sums (`Measured::wall_ms`), with the median CPU
//! time of the process's threads over a run beside them (`Measured::cpu_ms`: the rayon pool
//! and Embree's own threads included). Rays per second divide the median run's rays by the
//! median time of its ray stages (in the `afsm` row, Embree's BVH build and shadow rays
//! together).
//!
//! Usage: `embree-side-by-side [--threads N] [--repeats R] [--scenes a,b,...]` (built with
//! `--features embree`; `scripts/embree-bench` runs it at 1 and 2 threads), or
//! `embree-side-by-side scaling [...]`: cost against work (the `papers` report's two
//! cost-against-work tables), without Embree.

/// The command lines the binary takes.
const USAGE: &str = "embree-side-by-side [--threads N] [--repeats R] [--scenes a,b,...]   \
                     (built with --features embree)\n\
                     embree-side-by-side scaling [--threads N] [--repeats R] [--out DIR]";

fn main() -> anyhow::Result<()> {
    match std::env::args().nth(1).as_deref() {
        Some("scaling") => scaling::run(),
        Some("--help" | "-h") => {
            println!("{USAGE}");
            Ok(())
        }
        _ => side_by_side(),
    }
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
            let protocol = instrumentation::measure::Protocol::fixed(0, repeats);
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
    use anyhow::{anyhow, bail, Context};
    use bench::embree_tracer::{
        camera_hits, shadows_on, trace_on, Api, STAGE_CAMERA_RAYS, STAGE_SHADOW_RAYS,
    };
    use bench::Samples;
    use embree::Device;
    use instrumentation::clock::Load;
    use instrumentation::measure::{measure_all, Measured, Protocol, Sample};
    use instrumentation::Recorder;
    use methods::pattern::{PatternKind, SamplePattern};
    use methods::{Frame, MethodOptions, ShadowMethod};

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
                    println!("{}", super::USAGE);
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

    /// One timed run of a subject: ours or Embree's, on one frame.
    type Subject<'a> = Box<dyn FnMut(&mut Recorder) -> anyhow::Result<()> + 'a>;

    /// Our method `t` on `frame`: its stages are the run's.
    fn ours<'a>(frame: &'a Frame<'_>, t: &'a dyn ShadowMethod) -> Subject<'a> {
        Box::new(move |rec: &mut Recorder| {
            t.run(frame, rec)?;
            Ok(())
        })
    }

    /// Embree tracing `samples` of `frame` through `api`: BVH build, camera and shadow rays,
    /// each a stage; the rays traced counted as `rays_traced`.
    fn embree<'a>(
        device: &'a Device,
        frame: &'a Frame<'_>,
        samples: &'a Samples,
        api: Api,
    ) -> Subject<'a> {
        Box::new(move |rec: &mut Recorder| {
            let t = trace_on(device, frame, samples, api, &mut rec.stages);
            rec.counters.rays_traced = t.camera_rays + t.shadow_rays;
            Ok(())
        })
    }

    /// The smallest and largest ratio `ours / theirs` of the wall-clock times of one round:
    /// the runs of a frame are interleaved round by round, so the two runs of a round met the
    /// same machine. A range that holds 1 leaves undecided which side is faster. `None`
    /// without a round that both ran.
    fn round_ratios(ours: &[Sample], theirs: &[Sample]) -> Option<(f64, f64)> {
        let ratios = ours.iter().zip(theirs).map(|(a, b)| a.wall_ms / b.wall_ms);
        ratios.fold(None, |range, r| match range {
            None => Some((r, r)),
            Some((lo, hi)) => Some((r.min(lo), r.max(hi))),
        })
    }

    /// The "per round" cell of a table: [`round_ratios`] of the runs of `ours` and `theirs`
    /// as `lo-hi`, or `–`.
    fn per_round(ours: &Measured<()>, theirs: &Measured<()>) -> String {
        round_ratios(&ours.samples, &theirs.samples)
            .map_or_else(|| "–".into(), |(lo, hi)| format!("{lo:.2}-{hi:.2}"))
    }

    /// The median of the stages `names` of `m`, summed (ms).
    fn stages_ms(m: &Measured<()>, names: &[&str]) -> f64 {
        m.stages.iter().filter(|s| names.contains(&s.name.as_str())).map(|s| s.ms.median).sum()
    }

    /// Measures `subjects` interleaved under `protocol`, noting the machine's condition over
    /// their runs in `machine`; the first failure is the error.
    fn measure_frame(
        protocol: &Protocol,
        subjects: &mut [Subject<'_>],
        machine: &mut Machine,
    ) -> anyhow::Result<Vec<Measured<()>>> {
        let measured: Vec<_> =
            measure_all(protocol, subjects, |_, _| {}).into_iter().collect::<Result<_, _>>()?;
        for m in &measured {
            machine.note(m);
        }
        Ok(measured)
    }

    /// What the machine did while a table was measured, for the line under it: a ratio taken
    /// while other processes held cores is not one of a quiet machine.
    struct Machine {
        /// The 1-minute load average before the table's first run.
        load_before: Option<f64>,
        /// Core-milliseconds other processes took during the timed runs, and the runs'
        /// wall-clock milliseconds: their ratio is the share of the cores others took.
        others_ms: f64,
        wall_ms: f64,
        /// Timed runs kept, and those of them contended (their threads held less than
        /// `Protocol::min_share` of their time, also when run again).
        runs: usize,
        contended: usize,
    }

    impl Machine {
        /// Starts a table: prints the CPU and the load average now.
        fn start() -> Self {
            let load_before = Load::now().map(|l| l.loadavg);
            println!(
                "Machine: {}; 1-minute load average {} at the start\n",
                instrumentation::cpu_model(),
                Self::shown(load_before),
            );
            Machine { load_before, others_ms: 0.0, wall_ms: 0.0, runs: 0, contended: 0 }
        }

        /// A load average as printed: two decimals, or `unknown` where it could not be read.
        fn shown(load: Option<f64>) -> String {
            load.map_or_else(|| "unknown".into(), |l| format!("{l:.2}"))
        }

        fn note(&mut self, m: &Measured<()>) {
            // A subject's share is over its timed runs: weighted by their time, the shares of
            // the subjects make the table's (one subject's alone is coarse: 10 ms jiffies).
            let wall: f64 = m.samples.iter().map(|s| s.wall_ms).sum();
            self.others_ms += m.conditions.others_share.unwrap_or(0.0) * wall;
            self.wall_ms += wall;
            self.runs += m.samples.len();
            self.contended += m.samples.iter().filter(|s| s.contended).count();
        }

        /// Ends a table: prints the load average now and what others took during its runs.
        fn end(self) {
            println!(
                "\nLoad average {} at the start, {} at the end (this process's own threads \
                 count in it); other processes took {:.1} % of the cores over the timed \
                 runs; {} of {} timed runs contended",
                Self::shown(self.load_before),
                Self::shown(Load::now().map(|l| l.loadavg)),
                100.0 * self.others_ms / self.wall_ms.max(f64::MIN_POSITIVE),
                self.contended,
                self.runs,
            );
        }
    }

    pub fn run() -> anyhow::Result<()> {
        let a = args()?;
        rayon::ThreadPoolBuilder::new().num_threads(a.threads).build_global()?;
        let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
        let protocol = Protocol::fixed(1, u32::try_from(a.repeats).context("--repeats")?);
        println!(
            "# Embree 3 beside shadowbench: {} rayon threads ({cores} cores available to the \
             process, which bounds Embree's BVH build); wall-clock medians of {} runs after one \
             warm-up (instrumentation::measure, the runs of a frame interleaved); CPU time of \
             the process's threads beside (Embree's threads included)\n",
            a.threads, a.repeats
        );
        let mut machine = Machine::start();
        println!("| scene | frame | triangles | camera G-buffer ms | measure | ours ms | Embree ms | ours / Embree | per round | ours Mrays/s | Embree Mrays/s | ours CPU ms | Embree CPU ms |");
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        let device = Device::new();
        for name in &a.scenes {
            let scene = match scenes::load(name) {
                Ok(s) => s,
                Err(e) => {
                    println!("| {name} | skipped: {e} ||||||||||||");
                    continue;
                }
            };
            for (rate_frame, rate) in [(None, 1u32), (Some((320, 240)), 64)] {
                let (w, h) = rate_frame.unwrap_or((scene.width, scene.height));
                let mut rec = Recorder::default();
                let frame = Frame::new(&scene, w, h, &mut rec);
                let gbuffer = rec.stages.total_ms();
                let triangles = frame.geometry.len();
                let pattern = SamplePattern::new(rate, PatternKind::Grid)?;
                let samples = Samples::new(&frame, &pattern);
                let rt = analysis::raytrace::RayTrace { pattern };
                // At rate 1, what the rows after the ray tracers need: `afsm`, `pan09` at 32x,
                // the 32x samples and Embree's camera hits (traced once here, untimed).
                let at_rate_1 = (rate == 1)
                    .then(|| -> anyhow::Result<_> {
                        let afsm =
                            analysis::registry::technique("afsm", &MethodOptions::default())?;
                        let options = MethodOptions { rate: Some(32), ..Default::default() };
                        let pan = analysis::registry::technique("pan09", &options)?;
                        let s32 = Samples::new(&frame, &SamplePattern::new(32, PatternKind::Grid)?);
                        let hits = camera_hits(&device, &frame, &samples, Api::PerRay);
                        Ok((afsm, pan, s32, hits))
                    })
                    .transpose()?;
                // The frame's subjects, in the order of the rows: our `raytrace`, then Embree
                // per ray and in streams of 16; at rate 1 also `afsm` and Embree's BVH plus
                // shadow rays from the camera's hits, and `pan09` at 32x and Embree
                // supersampling the frame at 32x.
                let mut subjects: Vec<Subject<'_>> = vec![
                    Box::new(|rec: &mut Recorder| {
                        analysis::Reference::evaluate(&rt, &frame, rec)?;
                        Ok(())
                    }),
                    embree(&device, &frame, &samples, Api::PerRay),
                    embree(&device, &frame, &samples, Api::Stream16),
                ];
                if let Some((afsm, pan, s32, hits)) = &at_rate_1 {
                    let (device, frame) = (&device, &frame);
                    subjects.push(ours(frame, afsm.as_ref()));
                    subjects.push(Box::new(move |rec: &mut Recorder| {
                        rec.counters.rays_traced =
                            shadows_on(device, frame, hits, Api::PerRay, &mut rec.stages);
                        Ok(())
                    }));
                    subjects.push(ours(frame, pan.as_ref()));
                    subjects.push(embree(device, frame, s32, Api::PerRay));
                }
                let measured = measure_frame(&protocol, &mut subjects, &mut machine)?;
                let line = |measure: &str, ours: &Measured<()>, theirs: &Measured<()>, rates| {
                    row(name, (w, h), triangles, gbuffer, measure, ours, theirs, rates)
                };
                let rays = |m: &Measured<()>| m.record.counters.rays_traced as f64;
                let ours_rt = &measured[0];
                for (theirs, api) in measured[1..3].iter().zip([Api::PerRay, Api::Stream16]) {
                    let traced = stages_ms(theirs, &[STAGE_CAMERA_RAYS, STAGE_SHADOW_RAYS]);
                    let ours_traced = stages_ms(ours_rt, &[analysis::raytrace::STAGE_RAY_TRACING]);
                    line(
                        &format!(
                            "raytrace rate {rate} vs Embree {api:?} (BVH + camera + shadow rays)"
                        ),
                        ours_rt,
                        theirs,
                        (rays(ours_rt) / ours_traced, rays(theirs) / traced),
                    );
                }
                if let [_, _, _, afsm, shadows, pan, ss32] = &measured[..] {
                    // afsm decides the same pixel-centre shadows: its stages against Embree's
                    // BVH build plus the shadow rays from the camera's hits.
                    line(
                        "afsm vs Embree BVH + shadow rays",
                        afsm,
                        shadows,
                        (f64::NAN, rays(shadows) / shadows.wall_ms.median),
                    );
                    // pan09 at 32x against Embree supersampling the same frame at 32x.
                    line("pan09 32x vs Embree 32x supersampling", pan, ss32, (f64::NAN, f64::NAN));
                }
                if rate == 1 && name == "bunny-plane" {
                    // Lecocq et al.'s Table 2: the sub-pixel shadow map's cost over a shadow map
                    // of the same size, at 1920x1080, the four runs interleaved on the frame.
                    let mut rec = Recorder::default();
                    let hd = Frame::new(&scene, 1920, 1080, &mut rec);
                    let gbuffer = rec.stages.total_ms();
                    let maps = [1024, 4096];
                    let built = maps
                        .iter()
                        .flat_map(|&map| {
                            let options =
                                MethodOptions { map_res: Some(map), ..Default::default() };
                            ["spsm", "sm"].map(|m| analysis::registry::technique(m, &options))
                        })
                        .collect::<Result<Vec<_>, _>>()?;
                    let mut subjects: Vec<Subject<'_>> =
                        built.iter().map(|t| ours(&hd, t.as_ref())).collect();
                    let measured = measure_frame(&protocol, &mut subjects, &mut machine)?;
                    for (map, pair) in maps.iter().zip(measured.chunks(2)) {
                        let [spsm, sm] = pair else {
                            return Err(anyhow!("two runs per map size, {} measured", pair.len()));
                        };
                        let what = format!("spsm vs sm, map {map} (Lecocq et al.: 1.27-1.81)");
                        row(
                            name,
                            (1920, 1080),
                            hd.geometry.len(),
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
        machine.end();
        let repeats = u32::try_from(a.repeats).context("--repeats")?.max(EXACT_REPEATS);
        exact_table(&a.scenes, &Protocol::fixed(1, repeats))
    }

    /// The scenes of the exact reference's table (issue table of `exact`'s cost), at their
    /// own frame sizes.
    const EXACT_SCENES: [&str; 4] = ["bunny-plane", "bumpy", "cage", "random-1m"];

    /// Fewest timed runs of the exact table (more when `--repeats` asks): with three, `sm`'s
    /// median at map 1024 on cage moved from 14.7 to 22.7 ms between runs of the bench, and the
    /// ratio `exact / sm` with it; the table's runs cost seconds, not the minutes of the rows
    /// above.
    const EXACT_REPEATS: u32 = 7;

    /// The second table: what the references cost beside a shadow map on the same frame.
    /// `exact` (edge pixels ray traced at rate 1, as `render --method exact`) and `sm` at map
    /// 1024 interleaved under `protocol` (at least [`EXACT_REPEATS`] timed runs); `raytrace` at
    /// rate 64 once (one cold run: seconds a frame), on the frames up to 800x600. Ratios are
    /// given without and with the frame's camera G-buffer (which `render` counts in a run's
    /// total and the methods share), itself made under `protocol` interleaved with the two:
    /// one cold G-buffer, as this table took before, moved cage's ratio with it from 2.92 to
    /// 3.34 between two runs (17.0 and 10.2 ms).
    fn exact_table(names: &[String], protocol: &Protocol) -> anyhow::Result<()> {
        let chosen: Vec<&String> =
            names.iter().filter(|n| EXACT_SCENES.contains(&n.as_str())).collect();
        if chosen.is_empty() {
            return Ok(());
        }
        println!(
            "\n# The references beside a shadow map: `exact`, `sm` (map 1024) and the camera \
             G-buffer interleaved, wall-clock medians of {} runs after one warm-up; `raytrace \
             --rate 64` one cold run\n",
            protocol.min_repeats
        );
        let mut machine = Machine::start();
        println!("| scene | frame | triangles | camera G-buffer ms | exact ms | exact CPU ms | exact's largest stages (ms) | sm ms | exact / sm | per round | exact / sm with G-buffer | raytrace rate 64 ms |");
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
        let exact = analysis::registry::technique("exact", &MethodOptions::default())?;
        let options = MethodOptions { map_res: Some(1024), ..Default::default() };
        let sm = analysis::registry::technique("sm", &options)?;
        let options = MethodOptions { rate: Some(64), ..Default::default() };
        let rt64 = analysis::registry::technique("raytrace", &options)?;
        for name in chosen {
            let scene = match scenes::load(name) {
                Ok(s) => s,
                Err(e) => {
                    println!("| {name} | skipped: {e} |||||||||||");
                    continue;
                }
            };
            let (w, h) = (scene.width, scene.height);
            let frame = Frame::new(&scene, w, h, &mut Recorder::default());
            let mut subjects = vec![
                ours(&frame, exact.as_ref()),
                ours(&frame, sm.as_ref()),
                // The camera G-buffer, as `render` makes it before a method runs.
                Box::new(|rec: &mut Recorder| {
                    Frame::new(&scene, w, h, rec);
                    Ok(())
                }),
            ];
            let measured = measure_frame(protocol, &mut subjects, &mut machine)?;
            let [e, s, g] = &measured[..] else {
                return Err(anyhow!("three subjects, {} measured", measured.len()));
            };
            let gbuffer = g.wall_ms.median;
            let mut stages: Vec<_> =
                e.stages.iter().map(|st| (st.name.as_str(), st.ms.median)).collect();
            stages.sort_by(|a, b| b.1.total_cmp(&a.1));
            let largest: Vec<String> =
                stages.iter().take(3).map(|(n, ms)| format!("{n} {ms:.0}")).collect();
            let brute = if w * h <= 800 * 600 {
                let once = Protocol::fixed(0, 1);
                let m = measure_frame(&once, &mut [ours(&frame, rt64.as_ref())], &mut machine)?;
                m.first().map_or_else(|| "–".into(), |m| format!("{:.0}", m.wall_ms.median))
            } else {
                "–".into()
            };
            let (ew, sw) = (e.wall_ms.median, s.wall_ms.median);
            let cpu = e.cpu_ms.map_or_else(|| "–".into(), |c| format!("{:.1}", c.median));
            let rounds = per_round(e, s);
            println!(
                "| {name} | {w}x{h} | {} | {gbuffer:.1} | {ew:.1} | {cpu} | {} | {sw:.1} | {:.2} | {rounds} | {:.2} | {brute} |",
                frame.geometry.len(),
                largest.join(", "),
                ew / sw,
                (ew + gbuffer) / (sw + gbuffer),
            );
        }
        machine.end();
        Ok(())
    }

    /// One row of the table: `ours` against `embree` (their wall-clock medians, ratio, rays
    /// per millisecond shown as Mrays/s, and CPU medians).
    #[allow(clippy::too_many_arguments)]
    fn row(
        scene: &str,
        (w, h): (u32, u32),
        triangles: usize,
        gbuffer: f64,
        measure: &str,
        ours: &Measured<()>,
        embree: &Measured<()>,
        (ours_rate, embree_rate): (f64, f64),
    ) {
        let mrays = |r: f64| if r.is_finite() { format!("{:.2}", r / 1e3) } else { "–".into() };
        let cpu =
            |m: &Measured<()>| m.cpu_ms.map_or_else(|| "–".into(), |c| format!("{:.1}", c.median));
        let (o, e) = (ours.wall_ms.median, embree.wall_ms.median);
        let rounds = per_round(ours, embree);
        println!(
            "| {scene} | {w}x{h} | {triangles} | {gbuffer:.1} | {measure} | {o:.1} | {e:.1} | {:.2} | {rounds} | {} | {} | {} | {} |",
            o / e,
            mrays(ours_rate),
            mrays(embree_rate),
            cpu(ours),
            cpu(embree)
        );
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        fn runs(ms: &[f64]) -> Vec<Sample> {
            let run = |&wall_ms: &f64| Sample {
                wall_ms,
                cpu_ms: None,
                share: None,
                contended: false,
                retried: false,
            };
            ms.iter().map(run).collect()
        }

        /// The range is that of the rounds' own ratios, not of the medians' or of the extremes
        /// of the two sides apart; rounds only one side ran are left out.
        #[test]
        fn round_ratios_pair_the_runs_of_each_round() {
            let ours = runs(&[10.0, 30.0, 12.0, 99.0]);
            let theirs = runs(&[10.0, 20.0, 16.0]);
            assert_eq!(round_ratios(&ours, &theirs), Some((0.75, 1.5)));
            assert_eq!(round_ratios(&ours, &[]), None);
        }
    }
}
