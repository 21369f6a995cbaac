//! A suite's work as a list of items, and its deterministic split into shards
//! (`report --plan`, `report --shard K/N`).
//!
//! The items, in the order an unsharded report runs them: for each scene of the suite, one
//! item per `[[run]]` (every combination of its parameters on that scene), then one per image
//! grid of that scene, then, for each further frame size the runs give (`width`, `height`),
//! one item per `[[run]]` that asks for it; then the papers' tables, one item per scene and
//! frame of a table (its runs there, [`crate::tables::table_items`]). After a scene's `[[run]]`
//! items on its own frame come its outside results, one item per `[[external]]` entry with a
//! file for the scene (its cost: the frame's pixels, one comparison). A table's item whose
//! scene and frame are a
//! suite scene's follows that scene's items, so that its runs share the scene's frame and are
//! measured with its runs; the others come last. Each item names its scene, frame and
//! reference (none for a table's own frame: a table measures times and counters), lists its
//! runs and carries an estimate of its cost ([`WorkItem::cost`]), so that a user sees the size
//! of a sweep before starting it, shards can be balanced and progress can be estimated.
//!
//! The cost estimate, in arbitrary units, is what dominates a run at these sizes: per timed or
//! warm-up run, the frame's pixels times the samples per pixel, plus the shadow map's texels,
//! plus the scene's triangles; a grid counts one run per panel. It orders items and weighs the
//! progress of a sweep ([`run_cost`]); it does not predict seconds.
//!
//! A scene whose animation is not still ([`animation_of`]) runs its `[[run]]` items in motion,
//! every run once per frame (`crate::motion`): such an item's [`WorkItem::frames`] is the
//! animation's frame count (the suite's `frames` when it sets one) and its cost is that many
//! times a still item's. Its grids, outside results and tables' runs are of frame 0 only, one
//! frame each.
//!
//! Shards take items by longest processing time first ([`assign`]): items sorted by falling
//! cost (ties by their index), each given to the shard with the least cost so far (ties to the
//! lowest shard). The same plan and shard count always give the same split. Within a shard,
//! items run in plan order, so a scene's frame and reference are prepared once per shard.

use crate::suite::{ReferenceChoice, Suite};
use serde::{Deserialize, Serialize};

/// What an item runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Work {
    /// Every combination of the suite's `[[run]]` number `spec` on the item's scene.
    Runs {
        /// Index into the suite's runs.
        spec: usize,
        /// The method.
        method: String,
        /// Its runs, as `map_res=512 rate=16 device=gpu` (empty for the defaults).
        runs: Vec<String>,
    },
    /// The suite's image grid number `grid`.
    Grid {
        /// Index into the suite's grids.
        grid: usize,
        /// Its title.
        title: String,
    },
    /// The suite's `[[external]]` entry number `external`: its result on the item's scene,
    /// scored against the scene's reference.
    External {
        /// Index into the suite's externals.
        external: usize,
        /// The outside renderer's name.
        name: String,
    },
    /// The runs the suite's table number `table` makes on the item's scene at the item's
    /// frame (a table's scenes and frames are its own, [`crate::tables::table_items`]).
    Table {
        /// Index into the suite's tables.
        table: usize,
        /// The paper's table.
        paper: String,
        /// Its runs, as `pcf-gems16 map_res=512` (method, then what it sets).
        runs: Vec<String>,
    },
}

/// One item of a suite's work.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorkItem {
    /// Its index in the plan.
    pub item: usize,
    /// The scene (`None` for a table, which has its own scenes).
    pub scene: Option<String>,
    /// Its index in the suite's scenes (a scene may be listed twice).
    pub scene_index: Option<usize>,
    /// Frame width (0 when the scene cannot be loaded).
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// The reference its runs are measured against (`exact`, `raytrace`; `None` for a table
    /// or a scene that cannot be loaded).
    pub reference: Option<String>,
    /// The `raytrace` reference's rate.
    pub ref_rate: Option<u32>,
    /// What it runs.
    #[serde(flatten)]
    pub work: Work,
    /// The frames each of its runs runs on: the animation's frame count for the `[[run]]`
    /// items of an animated scene, 1 otherwise (see the module documentation).
    #[serde(default = "one_frame")]
    pub frames: u32,
    /// The estimated cost (see the module documentation).
    pub cost: f64,
    /// The estimated peak memory of its heaviest run with its reference, bytes
    /// (`analysis::budget`; 0 for a grid, whose runs are the suite's, for an outside result,
    /// which runs nothing, and for a scene that cannot be loaded).
    #[serde(default)]
    pub memory: u64,
}

fn one_frame() -> u32 {
    1
}

/// The animation a suite runs `scene` in: `None` for a still scene (no track: it runs as a
/// still frame), else the scene's animation sampled at the suite's `frames` when it sets one
/// (a count outside `1..=scenes::MAX_FRAMES`, which reading the suite refuses, leaves the
/// scene's own).
pub fn animation_of(scene: &scenes::Scene, frames: Option<u32>) -> Option<scenes::Animation> {
    let a = &scene.animation;
    if a.is_still() {
        return None;
    }
    Some(frames.and_then(|n| a.with_frames(n).ok()).unwrap_or_else(|| a.clone()))
}

/// The estimated peak memory of the runs `runs` (method and options) on `triangles` at
/// `width x height`, against `reference` at `ref_rate`: the heaviest's.
fn peak_memory<'m>(
    runs: impl Iterator<Item = (&'m str, &'m methods::MethodOptions)>,
    triangles: f64,
    (width, height): (u32, u32),
    reference: Option<(&str, u32)>,
) -> u64 {
    runs.map(|(method, o)| {
        analysis::budget::estimate(&analysis::budget::Work {
            triangles: triangles as u64,
            width,
            height,
            method,
            rate: o.rate.unwrap_or(1),
            map_res: o.map_res.unwrap_or(1024),
            reference,
        })
        .bytes
    })
    .max()
    .unwrap_or(0)
}

/// What the plan knows of a scene without running anything.
struct SceneFacts {
    width: u32,
    height: u32,
    triangles: f64,
    transparency: bool,
    /// Frames its runs run on (1 for a still scene).
    frames: u32,
}

fn facts(suite: &Suite, name: &str) -> Option<SceneFacts> {
    let scene = scenes::load(name).ok()?;
    let (width, height) =
        if suite.width == 0 { (scene.width, scene.height) } else { (suite.width, suite.height) };
    Some(SceneFacts {
        width,
        height,
        triangles: scene.triangle_count() as f64,
        transparency: scene.effects().transparency,
        frames: animation_of(&scene, suite.frames).map_or(1, |a| a.frames()),
    })
}

/// The frame sizes of a scene's runs, the scene's own (`default`) first, then those the runs
/// give (`width`, `height`) in the order they first appear.
fn frame_sizes(suite: &Suite, default: (u32, u32)) -> Vec<(u32, u32)> {
    let mut sizes = vec![default];
    for size in suite.runs.iter().flat_map(|r| r.sizes()).flatten() {
        if !sizes.contains(&size) {
            sizes.push(size);
        }
    }
    sizes
}

/// The cost of one method run with `rate` samples and a `map_res` map on `pixels` pixels.
pub fn run_cost(pixels: f64, triangles: f64, rate: Option<u32>, map_res: Option<u32>) -> f64 {
    let texels = map_res.map_or(1024.0 * 1024.0, |m| f64::from(m) * f64::from(m));
    pixels * f64::from(rate.unwrap_or(1).max(1)) + texels + triangles
}

/// The suite's work, in the order an unsharded report runs it (see the module documentation).
/// Scenes are loaded to learn their frame and effects; one that cannot be loaded still has
/// its items, with a zero frame, and running them records why.
pub fn plan(suite: &Suite) -> Vec<WorkItem> {
    let runs_per = f64::from(suite.warmup + suite.repeats.max(1));
    let mut items = Vec::new();
    for (scene_index, name) in suite.scenes.iter().enumerate() {
        let f = facts(suite, name);
        let scene_size = f.as_ref().map_or((0, 0), |f| (f.width, f.height));
        let triangles = f.as_ref().map_or(0.0, |f| f.triangles);
        let (reference, ref_rate) = match &f {
            None => (None, None),
            Some(f) => {
                let exact = match suite.reference {
                    ReferenceChoice::Auto => !f.transparency,
                    ReferenceChoice::Exact => true,
                    ReferenceChoice::Raytrace => false,
                };
                if exact {
                    (Some("exact".to_owned()), None)
                } else {
                    (Some("raytrace".to_owned()), Some(suite.ref_rate))
                }
            }
        };
        let budget_reference =
            reference.as_deref().map(|r| (r, ref_rate.unwrap_or(suite.ref_rate)));
        let frames = f.as_ref().map_or(1, |f| f.frames);
        let item = |work: Work,
                    (width, height),
                    frames: u32,
                    cost: f64,
                    memory: u64,
                    items: &Vec<WorkItem>| WorkItem {
            item: items.len(),
            scene: Some(name.clone()),
            scene_index: Some(scene_index),
            width,
            height,
            reference: reference.clone(),
            ref_rate,
            work,
            frames,
            cost,
            memory,
        };
        // One frame after another: the scene's own with its runs and grids, then each frame
        // size the runs add, with the runs that ask for it.
        for (n, size) in frame_sizes(suite, scene_size).into_iter().enumerate() {
            let pixels = f64::from(size.0) * f64::from(size.1);
            for (k, spec) in suite.runs.iter().enumerate() {
                let on_frame = spec.sizes().iter().any(|s| match s {
                    Some(s) if f.is_some() => *s == size,
                    _ => n == 0,
                });
                if !on_frame {
                    continue;
                }
                let combos = spec.expand();
                let cost = f64::from(frames)
                    * combos
                        .iter()
                        .map(|o| runs_per * run_cost(pixels, triangles, o.rate, o.map_res))
                        .sum::<f64>();
                let memory = if f.is_some() {
                    let runs = combos.iter().map(|o| (spec.method.as_str(), o));
                    peak_memory(runs, triangles, size, budget_reference)
                } else {
                    0
                };
                let runs = combos.iter().map(combo_label).collect();
                let work = Work::Runs { spec: k, method: spec.method.clone(), runs };
                let it = item(work, size, frames, cost, memory, &items);
                items.push(it);
            }
            if n > 0 {
                continue;
            }
            for (k, e) in suite.externals.iter().enumerate() {
                if e.files.contains_key(name) {
                    let work = Work::External { external: k, name: e.name.clone() };
                    let it = item(work, size, 1, pixels, 0, &items);
                    items.push(it);
                }
            }
            for (k, grid) in suite.grids.iter().enumerate().filter(|(_, g)| g.scene == *name) {
                let cost = grid
                    .panels
                    .iter()
                    .map(|p| p.options())
                    .map(|o| run_cost(pixels, triangles, o.rate, o.map_res))
                    .sum();
                let work = Work::Grid { grid: k, title: grid.title.clone() };
                let it = item(work, size, 1, cost, 0, &items);
                items.push(it);
            }
        }
    }
    // A table's items: one per scene and frame. One whose scene and frame are a suite
    // scene's joins that scene's items, so that they share its frame (and its reference);
    // the others follow, in the order of the tables.
    let mut tail = Vec::new();
    for (k, spec) in suite.tables.iter().enumerate() {
        for (name, (w, h), runs) in crate::tables::table_items(spec) {
            let triangles = scenes::load(&name).map_or(0.0, |s| s.triangle_count() as f64);
            let pixels = f64::from(w) * f64::from(h);
            let cost = runs
                .iter()
                .map(|(_, o)| runs_per * run_cost(pixels, triangles, o.rate, o.map_res))
                .sum();
            let labels = runs
                .iter()
                .map(|(m, o)| [*m, &combo_label(o)].join(" ").trim().to_owned())
                .collect();
            let memory = peak_memory(runs.iter().map(|(m, o)| (*m, o)), triangles, (w, h), None);
            let work = Work::Table { table: k, paper: spec.paper.name().to_owned(), runs: labels };
            let shared = items.iter().rposition(|i: &WorkItem| {
                i.scene.as_deref() == Some(name.as_str()) && (i.width, i.height) == (w, h)
            });
            let (scene_index, reference, ref_rate) = match shared {
                Some(at) => {
                    (items[at].scene_index, items[at].reference.clone(), items[at].ref_rate)
                }
                None => (None, None, None),
            };
            let item = WorkItem {
                item: 0,
                scene: Some(name),
                scene_index,
                width: w,
                height: h,
                reference,
                ref_rate,
                work,
                frames: 1,
                cost,
                memory,
            };
            match shared {
                Some(at) => items.insert(at + 1, item),
                None => tail.push(item),
            }
        }
    }
    items.extend(tail);
    for (k, item) in items.iter_mut().enumerate() {
        item.item = k;
    }
    items
}

/// A combination's parameters as `map_res=512 rate=16 device=gpu` (what it sets).
fn combo_label(o: &methods::MethodOptions) -> String {
    let mut parts: Vec<String> =
        o.given().into_iter().map(|(k, v)| format!("{k}={}", v.text())).collect();
    if o.device == methods::registry::Device::Gpu {
        parts.push("device=gpu".to_owned());
    }
    parts.join(" ")
}

/// The shard of each item (`0..shards`), by longest processing time first (see the module
/// documentation). `shards` must be at least 1.
pub fn assign(items: &[WorkItem], shards: u32) -> Vec<u32> {
    let shards = shards.max(1);
    let mut order: Vec<usize> = (0..items.len()).collect();
    order.sort_by(|&a, &b| items[b].cost.total_cmp(&items[a].cost).then(a.cmp(&b)));
    let mut load = vec![0.0f64; shards as usize];
    let mut of = vec![0u32; items.len()];
    for k in order {
        let (least, _) = load
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1).then(a.0.cmp(&b.0)))
            .unwrap_or((0, &0.0));
        load[least] += items[k].cost;
        of[k] = least as u32;
    }
    of
}

/// A share of a plan: shard `index` of `count` (`report --shard K/N`, `K` from 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This shard, from 0.
    pub index: u32,
    /// How many shards the plan is split into.
    pub count: u32,
}

/// A `--shard` value that is not `K/N` with `0 <= K < N`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "`{0}` is not a shard: give K/N with 0 <= K < N (e.g. 0/4, as Slurm's array task id and count)"
)]
pub struct ShardError(pub String);

impl std::str::FromStr for Shard {
    type Err = ShardError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || ShardError(s.to_owned());
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = k.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if index < count {
            Ok(Self { index, count })
        } else {
            Err(bad())
        }
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// The items of `plan` in this shard, in plan order.
    pub fn items(self, plan: &[WorkItem]) -> Vec<usize> {
        let of = assign(plan, self.count);
        (0..plan.len()).filter(|&k| of[k] == self.index).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(k: usize, cost: f64) -> WorkItem {
        WorkItem {
            item: k,
            scene: None,
            scene_index: None,
            width: 0,
            height: 0,
            reference: None,
            ref_rate: None,
            work: Work::Table { table: k, paper: String::new(), runs: Vec::new() },
            frames: 1,
            cost,
            memory: 0,
        }
    }

    #[test]
    fn shards_take_the_costliest_items_first_and_balance_the_rest() {
        let items: Vec<WorkItem> =
            [5.0, 1.0, 4.0, 3.0, 3.0, 2.0].iter().enumerate().map(|(k, &c)| item(k, c)).collect();
        // By falling cost: 5 to shard 0, 4 to 1, 3 (item 3) to 1 (4 < 5), 3 (item 4) to 0
        // (5 < 7), 2 to 1 (7 < 8), 1 to 0 (8 < 9).
        assert_eq!(assign(&items, 2), [0, 0, 1, 1, 0, 1]);
        let loads = |n: u32| {
            let of = assign(&items, n);
            let mut l = vec![0.0; n as usize];
            for (k, s) in of.iter().enumerate() {
                l[*s as usize] += items[k].cost;
            }
            l
        };
        assert_eq!(loads(2), [9.0, 9.0]);
        assert_eq!(loads(1), [18.0]);
        // Every item in exactly one shard, whatever the count, and more shards than items
        // leave some empty.
        for n in 1..9 {
            let mut all: Vec<usize> =
                (0..n).flat_map(|k| Shard { index: k, count: n }.items(&items)).collect();
            all.sort_unstable();
            assert_eq!(all, (0..items.len()).collect::<Vec<_>>());
        }
    }

    #[test]
    fn shard_values_are_k_of_n() {
        assert_eq!("2/3".parse(), Ok(Shard { index: 2, count: 3 }));
        for bad in ["3/3", "1", "a/2", "-1/2", "0/0", "1/2/3"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        assert_eq!(Shard { index: 0, count: 4 }.to_string(), "0/4");
    }

    /// An animated scene's `[[run]]` items run every frame, the suite's `frames` when it sets
    /// one, and cost as many frames; its grid and a still scene's runs are one frame.
    #[test]
    fn an_animated_scene_s_runs_cost_every_frame() {
        let text = |frames: &str| {
            format!(
                "name = \"m\"\nwidth = 48\nheight = 36\n{frames}\n\
                 scenes = [\"square-slide\", \"plane-square\"]\n\
                 [[run]]\nmethod = \"sm\"\nmap_res = [64, 128]\n\
                 [[grid]]\ntitle = \"g\"\nscene = \"square-slide\"\n\
                 inset = [0.1, 0.1, 0.2, 0.2]\npanels = [{{ method = \"sm\" }}]\n"
            )
        };
        let parse = |t: &str| Suite::parse(t, std::path::Path::new("m.toml")).expect("parses");
        let p = plan(&parse(&text("frames = 4")));
        assert!(matches!(p[1].work, Work::Grid { .. }), "{p:?}");
        assert_eq!(p.iter().map(|i| i.frames).collect::<Vec<_>>(), [4, 1, 1]);
        // square-slide is plane-square with the square sliding: the same frame's runs.
        assert_eq!(p[0].cost, 4.0 * p[2].cost);
        let own = plan(&parse(&text("")));
        assert_eq!(own[0].frames, 24, "the scene's own count");
        let line = serde_json::to_string(&p[0]).expect("json");
        assert!(line.contains("\"frames\":4"), "{line}");
        let still = scenes::load("plane-square").expect("built in");
        assert!(animation_of(&still, Some(4)).is_none());
        let moving = scenes::load("cage-sweep").expect("built in");
        assert_eq!(animation_of(&moving, Some(4)).map(|a| a.frames()), Some(4));
        assert_eq!(animation_of(&moving, Some(0)).map(|a| a.frames()), Some(24));
    }

    #[test]
    fn the_plan_follows_the_unsharded_order() {
        let suite = Suite::load("quick").expect("quick");
        let p = plan(&suite);
        let runs = suite.scenes.len() * suite.runs.len();
        let grids = suite.grids.iter().filter(|g| suite.scenes.contains(&g.scene)).count();
        let tables: usize = suite.tables.iter().map(|t| crate::tables::table_items(t).len()).sum();
        assert_eq!(p.len(), runs + grids + tables);
        // The tables' own frames are not the suite's 320x240: their items come last, without
        // a reference, each naming its scene.
        let table_items = &p[runs + grids..];
        assert!(table_items.iter().all(|i| matches!(i.work, Work::Table { .. })));
        assert!(table_items.iter().all(|i| i.reference.is_none() && i.scene.is_some()));
        assert!(p.iter().enumerate().all(|(k, i)| i.item == k && i.cost > 0.0));
        assert_eq!(p[0].scene.as_deref(), Some(suite.scenes[0].as_str()));
        assert!(matches!(p[0].work, Work::Runs { spec: 0, .. }));
        assert!(matches!(p.last().map(|i| &i.work), Some(Work::Table { .. })));
        let line = serde_json::to_string(&p[0]).expect("json");
        assert!(line.contains("\"kind\":\"runs\"") && line.contains("\"reference\":\"exact\""));
    }
}
