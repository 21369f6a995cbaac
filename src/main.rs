//! `shadowbench`: the command line of the shadow-map antialiasing workbench.
//!
//! Argument parsing and wiring only; the algorithms live in the workspace's crates. Exit
//! codes: 0 success, 2 bad input (one message naming the file, line, key or flag), 1 internal
//! failure.

use anyhow::Context;
use clap::{Parser, Subcommand, ValueEnum};
use instrumentation::{Recorder, RunRecord};
use methods::{Frame, MethodOptions};
use std::path::PathBuf;
use std::process::ExitCode;

/// Research workbench for shadow-map antialiasing: runs the published techniques on the same
/// scenes, counts their work, times every stage and writes what they compute.
#[derive(Parser)]
#[command(name = "shadowbench", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenes: name, triangle count, effects, default resolution.
    Scenes {
        /// Print the list as JSON instead of a table.
        #[arg(long)]
        json: bool,
        /// Print the scene file (TOML) of one built-in scene, to copy and edit.
        #[arg(long, value_name = "NAME", conflicts_with = "json")]
        toml: Option<String>,
    },
    /// Run one method on one scene; write visibility.exr, shadow.png and run.json.
    Render(RenderArgs),
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Device {
    /// The CPU implementation (rayon over all cores).
    Cpu,
    /// The GPU implementation (not available yet).
    Gpu,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene: a built-in name (see `shadowbench scenes`), a scene file (.toml), or a mesh
    /// file (.obj, .off, .ply) placed over a ground plane with a default light and camera.
    #[arg(long)]
    scene: String,
    /// Method: `sm` (standard shadow map).
    #[arg(long)]
    method: String,
    /// Shadow map resolution R (the map is R x R texels); default 1024.
    #[arg(long, value_name = "R")]
    map_res: Option<u32>,
    /// Constant depth bias as a fraction of the scene's light depth range; default 1e-5.
    #[arg(long, value_name = "B")]
    constant_bias: Option<f64>,
    /// Slope-scaled depth bias in units of the receiver's depth change per texel; default 1.
    /// Values >= 1 keep lit planes free of shadow acne.
    #[arg(long, value_name = "S")]
    slope_bias: Option<f64>,
    /// Upper bound of the receiver slope ratio used by the slope bias; default 10 (about 84°).
    #[arg(long, value_name = "M")]
    max_slope: Option<f64>,
    /// Image width in pixels; default: the scene's.
    #[arg(long, value_name = "W")]
    width: Option<u32>,
    /// Image height in pixels; default: the scene's.
    #[arg(long, value_name = "H")]
    height: Option<u32>,
    /// Where the method runs.
    #[arg(long, value_enum, default_value_t = Device::Cpu)]
    device: Device,
    /// Output folder; default `shadowbench-out/SCENE-METHOD`.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Also print run.json to standard output.
    #[arg(long)]
    json: bool,
}

/// A failure and the exit code it maps to.
enum Failure {
    /// Bad input: exit code 2.
    Input(anyhow::Error),
    /// Internal failure: exit code 1.
    Internal(anyhow::Error),
}

impl<E: Into<anyhow::Error>> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure::Internal(e.into())
    }
}

fn input(e: impl Into<anyhow::Error>) -> Failure {
    Failure::Input(e.into())
}

fn scenes(json: bool, toml: Option<String>) -> Result<(), Failure> {
    if let Some(name) = toml {
        let desc = scenes::registry::builtin(&name).ok_or_else(|| {
            input(anyhow::anyhow!(
                "--toml: unknown built-in scene `{name}`; known: {}",
                scenes::BUILTINS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ))
        })?;
        print!("{}", desc.to_toml());
        return Ok(());
    }
    let mut rows = Vec::new();
    for (name, description) in scenes::BUILTINS {
        let row = match scenes::registry::load_builtin(name) {
            Some(Ok(s)) => serde_json::json!({
                "name": name,
                "description": description,
                "available": true,
                "triangles": s.triangle_count(),
                "effects": s.effects().names(),
                "resolution": [s.width, s.height],
            }),
            Some(Err(e)) => serde_json::json!({
                "name": name,
                "description": description,
                "available": false,
                "triangles": null,
                "effects": [],
                "missing": e.to_string(),
            }),
            None => continue,
        };
        rows.push(row);
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        println!(
            "{:<14} {:>10}  {:<11} {:<44} description",
            "scene", "triangles", "resolution", "effects"
        );
        for r in &rows {
            let tris = r["triangles"].as_u64().map_or("missing".to_string(), |t| t.to_string());
            let res = r["resolution"]
                .as_array()
                .map_or(String::from("-"), |a| format!("{}x{}", a[0], a[1]));
            let effects: Vec<&str> =
                r["effects"].as_array().into_iter().flatten().filter_map(|e| e.as_str()).collect();
            println!(
                "{:<14} {:>10}  {:<11} {:<44} {}",
                r["name"].as_str().unwrap_or_default(),
                tris,
                res,
                effects.join(","),
                r["description"].as_str().unwrap_or_default()
            );
        }
    }
    Ok(())
}

fn render(a: RenderArgs) -> Result<(), Failure> {
    if a.device == Device::Gpu {
        return Err(input(anyhow::anyhow!(
            "--device gpu: the GPU path is not available yet; use --device cpu"
        )));
    }
    let scene = scenes::load(&a.scene).map_err(|e| input(anyhow::anyhow!("--scene: {e}")))?;
    let options = MethodOptions {
        map_res: a.map_res,
        constant_bias: a.constant_bias,
        slope_bias: a.slope_bias,
        max_slope: a.max_slope,
    };
    let method = methods::method(&a.method, &options).map_err(input)?;
    let width = a.width.unwrap_or(scene.width);
    let height = a.height.unwrap_or(scene.height);
    for (flag, v) in [("--width", width), ("--height", height)] {
        if !(1..=16384).contains(&v) {
            return Err(input(anyhow::anyhow!("{flag}: must be in 1..=16384, got {v}")));
        }
    }

    let mut rec = Recorder::default();
    let frame = Frame::new(&scene, width, height, &mut rec);
    let visibility = method.run(&frame, &mut rec).map_err(input)?;
    let record = RunRecord {
        scene: scene.name.clone(),
        method: method.name().to_owned(),
        params: method.params(),
        width,
        height,
        effects: frame.effects.names().into_iter().map(String::from).collect(),
        counters: rec.counters,
        total_ms: rec.stages.total_ms(),
        stages: rec.stages.stages,
        skipped_stages: rec.stages.skipped,
        notes: rec.notes,
    };

    let out = a.out.unwrap_or_else(|| {
        PathBuf::from(format!("shadowbench-out/{}-{}", scene.name, method.name()))
    });
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    reports::write_visibility_exr(&out.join("visibility.exr"), &visibility)?;
    reports::write_shadow_png(&out.join("shadow.png"), &frame, &visibility)?;
    reports::write_run_json(&out.join("run.json"), &record)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&record)?);
    }
    eprintln!(
        "{} on {} at {}x{}: {:.1} ms; wrote {}",
        record.method,
        record.scene,
        width,
        height,
        record.total_ms,
        out.display()
    );
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Scenes { json, toml } => scenes(json, toml),
        Command::Render(a) => render(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(e)) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
        Err(Failure::Internal(e)) => {
            eprintln!("internal error: {e:#}");
            ExitCode::from(1)
        }
    }
}
