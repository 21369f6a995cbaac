//! `compare`'s reference: chosen from `--reference`, `--ref-rate`, `--edge-reference` and the
//! pattern, and taken from the per-user reference cache when an earlier `compare` computed it
//! on the same scene and frame (`--cache DIR`, `--no-cache`; `reports::cache`).

use super::{input, EdgeReference, Failure, ReferenceName};
use analysis::{exact::ExactCoverage, Reference, ReferenceImage};
use instrumentation::Recorder;
use methods::{pattern::PatternKind, Frame};
use reports::cache::ReferenceCache;
use std::path::{Path, PathBuf};

/// Where `compare` keeps references.
#[derive(clap::Args)]
pub struct CacheArgs {
    /// Reference cache folder: a reference computed once is read back by every later
    /// `compare` of the same scene, frame, reference, edge reference, rate and pattern (by the
    /// same build of shadowbench; content-addressed, verified on read); default
    /// `$XDG_CACHE_HOME/shadowbench/references`, else `~/.cache/shadowbench/references` (when
    /// that folder cannot be made, the reference is computed without a cache, with a note).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Compute the reference without reading or writing a cache.
    #[arg(long, conflicts_with = "cache")]
    no_cache: bool,
}

/// The per-user cache folder: `$XDG_CACHE_HOME/shadowbench/references` (when set to an
/// absolute path), else `$HOME/.cache/shadowbench/references`; `None` with neither.
fn default_cache_dir() -> Option<PathBuf> {
    let xdg = std::env::var_os("XDG_CACHE_HOME").map(PathBuf::from);
    let base = match xdg.filter(|p| p.is_absolute()) {
        Some(dir) => dir,
        None => Path::new(&std::env::var_os("HOME")?).join(".cache"),
    };
    Some(base.join("shadowbench").join("references"))
}

/// The cache `compare` uses: `--cache DIR` (a folder that cannot be one is bad input), the
/// per-user folder, or none: `--no-cache`, or a per-user folder that cannot be found or made,
/// which is said on standard error.
pub fn open_cache(a: &CacheArgs) -> Result<Option<ReferenceCache>, Failure> {
    if a.no_cache {
        return Ok(None);
    }
    if let Some(dir) = &a.cache {
        super::check_folder_path(dir, "--cache")?;
        let cache = ReferenceCache::open(dir).map_err(|e| {
            input(anyhow::anyhow!("--cache {}: cannot create the folder: {e}", dir.display()))
        })?;
        return Ok(Some(cache));
    }
    let Some(dir) = default_cache_dir() else {
        eprintln!("note: neither XDG_CACHE_HOME nor HOME is set; the reference is not cached");
        return Ok(None);
    };
    match ReferenceCache::open(&dir) {
        Ok(cache) => Ok(Some(cache)),
        Err(e) => {
            eprintln!("note: the reference is not cached: cannot create {}: {e}", dir.display());
            Ok(None)
        }
    }
}

/// The ground truth a comparison is made against, and how its error is drawn: `compare`'s and
/// `animate`'s flags.
#[derive(clap::Args)]
pub struct TruthArgs {
    /// The ground truth to compare against.
    #[arg(long, value_enum, default_value_t = ReferenceName::Exact)]
    pub reference: ReferenceName,
    /// Sub-samples per pixel of the `raytrace` reference, and of `exact`'s edge pixels
    /// (1, 4, 8, ..., 1024); default 256.
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub ref_rate: Option<u32>,
    /// With `--reference exact`: the reference of the `edge` pixels (silhouettes, depth
    /// discontinuities, several objects or background in the square), which `exact` does not
    /// evaluate; default raytrace.
    #[arg(long, value_enum, value_name = "REF")]
    pub edge_reference: Option<EdgeReference>,
    /// The absolute error at the top of the colour scale (magma) of the error images, written
    /// on their colour bar; larger errors take the top colour; default 0.1.
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub error_scale: Option<f64>,
    #[command(flatten)]
    pub cache: CacheArgs,
}

/// The reference a `compare` asked for.
pub struct Chosen {
    /// The reference.
    pub reference: Box<dyn Reference>,
    /// The ray-traced part's rate (`None` when nothing is ray traced).
    pub ref_rate: Option<u32>,
    /// How `exact`'s edge pixels are referenced (`None` for `raytrace`).
    pub edge: Option<&'static str>,
    /// What the reference's values depend on besides the scene and frame, the name of its
    /// cache entries: the reference, its edge reference, rate and pattern.
    pub cache_name: String,
}

/// The reference of `c` (`--reference`, `--ref-rate`, `--edge-reference`) with `pattern`
/// (`--pattern`), with notes for the flags it does not use.
pub fn choose(c: &TruthArgs, pattern: PatternKind) -> Result<Chosen, Failure> {
    let rate = c.ref_rate.unwrap_or(analysis::registry::DEFAULT_REF_RATE);
    let edge_reference = c.edge_reference.unwrap_or(EdgeReference::Raytrace);
    let (reference, ref_rate, edge): (Box<dyn Reference>, _, _) =
        match (c.reference, edge_reference) {
            (ReferenceName::Exact, EdgeReference::Raytrace) => (
                analysis::registry::reference("exact", rate, pattern).map_err(input)?,
                Some(rate),
                Some("raytrace"),
            ),
            (ReferenceName::Exact, EdgeReference::None) => {
                if c.ref_rate.is_some() {
                    eprintln!(
                        "note: exact with --edge-reference none does not use --ref-rate; ignored"
                    );
                }
                (Box::new(ExactCoverage { edge: None }), None, Some("none"))
            }
            (ReferenceName::Raytrace, _) => {
                if c.edge_reference.is_some() {
                    eprintln!("note: raytrace does not use --edge-reference; ignored");
                }
                (
                    analysis::registry::reference("raytrace", rate, pattern).map_err(input)?,
                    Some(rate),
                    None,
                )
            }
        };
    let traced = ref_rate.map_or(String::new(), |_| format!(" {pattern}"));
    let cache_name = format!("{} edge={}{traced}", reference.name(), edge.unwrap_or("-"));
    Ok(Chosen { reference, ref_rate, edge, cache_name })
}

/// A reference's values and where they came from.
pub struct Evaluated {
    /// The values.
    pub image: ReferenceImage,
    /// The time its computation took (by this run, or by the run that stored it in the
    /// cache), milliseconds.
    pub computed_ms: f64,
    /// The time this run took to read it from the cache, when it did, milliseconds.
    pub read_ms: Option<f64>,
    /// `raytrace` at one sample per pixel on the same frame, for Lecocq et al.'s pixel match of
    /// a binary result, from the cache (`None` without one, or for a result that is not
    /// binary: the comparison traces it when it needs it).
    pub one_ray: Option<ReferenceImage>,
}

/// Evaluates `chosen` on `frame` of `scene`, through `cache` when there is one; with a cache
/// and a binary `result` (every value 0 or 1), also the one-ray image its pixel match needs.
pub fn evaluate(
    chosen: &Chosen,
    scene: &scenes::Scene,
    frame: &Frame<'_>,
    cache: Option<&mut ReferenceCache>,
    result: &methods::Visibility,
) -> Result<Evaluated, Failure> {
    let compute = || {
        let mut rec = Recorder::default();
        let image = chosen.reference.evaluate(frame, &mut rec).map_err(input)?;
        Ok::<_, Failure>((image, rec.stages.total_ms()))
    };
    let Some(cache) = cache else {
        let (image, computed_ms) = compute()?;
        return Ok(Evaluated { image, computed_ms, read_ms: None, one_ray: None });
    };
    let provenance = instrumentation::Provenance::capture(String::new(), None);
    let build = reports::cache::build_id(&provenance.commit, provenance.dirty);
    let hits = cache.stats.hits;
    let started = std::time::Instant::now();
    let (image, computed_ms) =
        cache.get_or_compute(scene, frame, &chosen.cache_name, chosen.ref_rate, &build, compute)?;
    let read_ms = (cache.stats.hits > hits).then(|| started.elapsed().as_secs_f64() * 1e3);
    // The same entry as `compare --reference raytrace --ref-rate 1` (grid pattern) would use.
    let one_ray = if result.lit.iter().all(|&x| x == 0.0 || x == 1.0) {
        let traced = || {
            let one = analysis::registry::reference("raytrace", 1, PatternKind::Grid);
            let mut rec = Recorder::default();
            let image = one.and_then(|r| r.evaluate(frame, &mut rec)).map_err(input)?;
            Ok::<_, Failure>((image, rec.stages.total_ms()))
        };
        let name = "raytrace edge=- grid";
        Some(cache.get_or_compute(scene, frame, name, Some(1), &build, traced)?.0)
    } else {
        None
    };
    if cache.stats.write_failures > 0 {
        eprintln!("note: the reference could not be stored in {}", cache.dir().display());
    }
    Ok(Evaluated { image, computed_ms, read_ms, one_ray })
}

/// What is scored: a method's run or an outside result.
pub struct Compared {
    /// The method's name, or the outside result's (`--name`).
    pub method: String,
    /// The method's parameters (none for an outside result).
    pub params: serde_json::Map<String, serde_json::Value>,
    /// The method's time, milliseconds (an outside result's when given).
    pub method_ms: Option<f64>,
    /// Whether it is an outside result.
    pub external: bool,
}

/// Scores `v`, the result on `frame`, against the reference `evaluated` (`chosen`): writes
/// error.png and error_boundary.png (absolute error up to `error_scale`) and metrics.json
/// into `staging`, and gives the record.
pub fn score(
    frame: &Frame<'_>,
    v: &methods::Visibility,
    chosen: &Chosen,
    evaluated: Evaluated,
    compared: Compared,
    error_scale: f64,
    staging: &Path,
) -> Result<reports::MetricsRecord, Failure> {
    use anyhow::Context;
    // A reference without classes (`raytrace`) is measured per class all the same: the
    // classes are the camera's view of the triangles, whatever the reference.
    let mut rec = Recorder::default();
    let mut truth = analysis::compare::Truth::new(frame, evaluated.image, &mut rec);
    if let Some(image) = evaluated.one_ray {
        truth = truth.with_one_ray(image);
    }
    let comparison = truth.compare(frame, v).map_err(input)?;
    for (name, mask) in [("error.png", &truth.headline), ("error_boundary.png", &truth.boundary())]
    {
        let path = staging.join(name);
        analysis::error_map::error_map(v, &truth.reference.lit, mask, error_scale)?
            .save(&path)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let metrics = reports::MetricsRecord {
        comparison,
        reference: chosen.reference.name().to_owned(),
        ref_rate: chosen.ref_rate,
        edge_reference: chosen.edge.map(String::from),
        scene: frame.scene.name.clone(),
        method: compared.method,
        params: compared.params,
        width: frame.width(),
        height: frame.height(),
        method_ms: compared.method_ms,
        reference_ms: evaluated.computed_ms + rec.stages.total_ms(),
        reference_cached: evaluated.read_ms.is_some(),
        reference_read_ms: evaluated.read_ms,
        external: compared.external,
    };
    let text = serde_json::to_string_pretty(&metrics)?;
    let path = staging.join("metrics.json");
    std::fs::write(&path, format!("{text}\n"))
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(metrics)
}

/// Prints the record: as JSON with `json`, else as `compare`'s table with the method's `time`;
/// then, on standard error, what the cache did.
pub fn report(
    m: &reports::MetricsRecord,
    json: bool,
    time: &str,
    cache: Option<&ReferenceCache>,
) -> Result<(), Failure> {
    if json {
        println!("{}", serde_json::to_string_pretty(m)?);
    } else {
        super::print_metrics(m, time);
    }
    match cache {
        Some(c) => {
            let what = if m.reference_cached { "read from" } else { "computed and stored in" };
            eprintln!("reference {what} the cache {}", c.dir().display());
        }
        None => eprintln!("reference computed (no cache)"),
    }
    Ok(())
}
