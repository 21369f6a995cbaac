//! A report run in shards and merged (`report --plan`, `report --shard K/N`, `report merge`)
//! equals the unsharded report on every field but times, machine and provenance; shards
//! share references through the cache; a merge with a shard missing or unfinished refuses,
//! naming it; a damaged cache entry is recomputed; a refused merge or report changes no file.

use crate::common::{assert_same_report, shadowbench, stderr, write};
use std::path::Path;

/// Two scenes, two methods, a grid: five items, so that three shards split scenes.
const SUITE: &str = r#"
name = "tiny"
width = 96
height = 72
warmup = 0
repeats = 1
scenes = ["plane-square", "cage"]

[[run]]
method = "sm"
map_res = [64, 128]

[[run]]
method = "pcf-gems4"
map_res = [64]

[[grid]]
title = "the cage's shadow"
scene = "cage"
inset = [0.4, 0.4, 0.2, 0.2]
reference = true

[[grid.panels]]
method = "sm"
map_res = 64
"#;

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Runs shard `k` of `n` of `suite` into `dir/shards/k` with the cache `dir/cache`.
fn shard(suite: &str, dir: &Path, k: u32, n: u32) -> std::process::Output {
    let out = dir.join("shards").join(k.to_string());
    let cache = dir.join("cache");
    let o = shadowbench(&[
        "report",
        "--suite",
        suite,
        "--shard",
        &format!("{k}/{n}"),
        "--out",
        path(&out),
        "--cache",
        path(&cache),
    ]);
    assert_eq!(o.status.code(), Some(0), "shard {k}/{n}: {}", stderr(&o));
    o
}

fn merge(dirs: &[&Path], out: &Path) -> std::process::Output {
    let mut args = vec!["report", "merge"];
    args.extend(dirs.iter().map(|d| path(d)));
    args.extend(["--out", path(out)]);
    shadowbench(&args)
}

#[test]
fn shards_merged_equal_the_unsharded_report_and_share_the_cache() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "tiny.toml", SUITE);

    // The plan: a JSON line per item, in the order the report runs them.
    let o = shadowbench(&["report", "--suite", &suite, "--plan"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let items: Vec<serde_json::Value> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("a JSON line"))
        .collect();
    assert_eq!(items.len(), 5, "2 scenes x 2 runs, and the grid");
    assert_eq!(items[0]["scene"], "plane-square");
    assert_eq!(items[0]["runs"], serde_json::json!(["map_res=64", "map_res=128"]));
    assert_eq!(items[4]["kind"], "grid");
    assert!(items.iter().all(|i| i["cost"].as_f64().is_some_and(|c| c > 0.0)));
    assert!(stderr(&o).contains("5 items, 6 runs"), "{}", stderr(&o));

    let whole = dir.path().join("whole");
    let o = shadowbench(&["report", "--suite", &suite, "--out", path(&whole)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));

    let outs: Vec<String> = (0..3)
        .map(|k| String::from_utf8_lossy(&shard(&suite, dir.path(), k, 3).stdout).into_owned())
        .collect();
    // Every scene's reference is computed once over the three shards; the other shards that
    // need it read it.
    let hits: u64 = outs
        .iter()
        .map(|o| {
            let n = o.split(" hits").next().and_then(|s| s.rsplit(' ').next());
            n.and_then(|n| n.parse::<u64>().ok()).unwrap_or_else(|| panic!("no hit count: {o}"))
        })
        .sum();
    assert!(hits >= 1, "{outs:?}");
    let entries = std::fs::read_dir(dir.path().join("cache")).expect("cache").count();
    assert_eq!(entries, 2, "one entry per scene");

    let merged = dir.path().join("merged");
    let shards: Vec<std::path::PathBuf> =
        (0..3).map(|k| dir.path().join("shards").join(k.to_string())).collect();
    let refs: Vec<&Path> = shards.iter().map(|p| p.as_path()).collect();
    let o = merge(&refs, &merged);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("merged 3 shards"));
    assert_same_report(&whole, &merged);

    // The merged folder is a whole report: the same files as the unsharded one, each run
    // marked with its shard, every shard's provenance kept.
    let files = |d: &Path| {
        let manifest: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(d.join(".shadowbench-manifest")).expect("manifest"),
        )
        .expect("parses");
        let mut f: Vec<String> = manifest["files"]
            .as_array()
            .expect("files")
            .iter()
            .map(|e| e["path"].as_str().expect("path").to_owned())
            .collect();
        f.sort();
        f
    };
    assert_eq!(files(&whole), files(&merged));
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(merged.join("runs.json")).expect("runs.json"),
    )
    .expect("parses");
    assert_eq!(json["shards"].as_array().map(Vec::len), Some(3));
    assert!(json["rows"].as_array().expect("rows").iter().all(|r| r["shard"].is_u64()));
    for f in ["index.html", "runs/cage-sm-map_res-64.html", "scenes/cage.reference.exr"] {
        assert!(merged.join(f).is_file(), "{f}");
    }
    let page = std::fs::read_to_string(merged.join("runs/cage-sm-map_res-64.html")).expect("page");
    assert!(page.contains("cage-pcf-gems4-map_res-64.png"), "the page flips to the scene's runs");

    // A second unsharded report into the same folder takes both references from its cache.
    let o = shadowbench(&["report", "--suite", &suite, "--out", path(&whole)]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("2 hits, 0 misses"), "{o:?}");
    assert_same_report(&whole, &merged);
}

#[test]
fn a_missing_or_unfinished_shard_is_named_and_nothing_is_merged() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "tiny.toml", SUITE);
    for k in [0, 2] {
        shard(&suite, dir.path(), k, 3);
    }
    let s = |k: u32| dir.path().join("shards").join(k.to_string());
    let out = dir.path().join("merged");
    let o = merge(&[&s(0), &s(2)], &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("shard 1 of 3 is missing") && err.contains("--only 1"), "{err}");
    assert!(!out.join("runs.json").exists());

    // A shard that started and did not finish (its folder has only shard.json).
    std::fs::create_dir_all(s(1)).expect("folder");
    let start = r#"{"suite": "tiny", "shard": {"index": 1, "count": 3}, "started": "now"}"#;
    std::fs::write(s(1).join("shard.json"), start).expect("writes");
    let o = merge(&[&s(0), &s(1), &s(2)], &out);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("did not finish"), "{}", stderr(&o));

    // The same shard twice, and shards of different counts, are refused.
    let o = merge(&[&s(0), &s(0), &s(2)], &out);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("also in"), "{}", stderr(&o));
    let other = dir.path().join("other");
    std::fs::create_dir_all(&other).expect("folder");
    let o = shadowbench(&[
        "report",
        "--suite",
        &suite,
        "--shard",
        "1/2",
        "--out",
        path(&other.join("1")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = merge(&[&s(0), &other.join("1"), &s(2)], &out);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("of 3 shards"), "{}", stderr(&o));

    // Finishing the missing shard completes the merge.
    std::fs::remove_dir_all(s(1)).expect("removes");
    shard(&suite, dir.path(), 1, 3);
    let o = merge(&[&s(0), &s(1), &s(2)], &out);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));

    // Bad shard values are bad input.
    for bad in ["3/3", "x", "1/0"] {
        let o = shadowbench(&["report", "--suite", &suite, "--shard", bad, "--plan"]);
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(stderr(&o).contains("--shard"), "{}", stderr(&o));
    }
}

#[test]
fn a_damaged_cache_entry_is_recomputed_and_replaced() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let one = SUITE.replace(r#", "cage""#, "");
    let one = one.split("[[grid]]").next().expect("the suite before its grid");
    let suite = write(dir.path(), "one.toml", one);
    let cache = dir.path().join("cache");
    let run = |out: &str| {
        let o = shadowbench(&[
            "report",
            "--suite",
            &suite,
            "--out",
            path(&dir.path().join(out)),
            "--cache",
            path(&cache),
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    assert!(run("a").contains("0 hits, 1 misses"));
    let entry = std::fs::read_dir(&cache).expect("cache").next().expect("an entry").expect("entry");
    let mut bytes = std::fs::read(entry.path()).expect("reads");
    let last = bytes.len() - 1;
    bytes[last] ^= 0x40;
    std::fs::write(entry.path(), &bytes).expect("writes");
    let second = run("b");
    assert!(second.contains("1 entries failed verification"), "{second}");
    assert!(run("c").contains("1 hits, 0 misses"), "the entry was replaced");
    assert_same_report(&dir.path().join("a"), &dir.path().join("c"));
    assert_same_report(&dir.path().join("a"), &dir.path().join("b"));
}

/// Every file under `dir` with its size, sorted: what a refused command must leave as it was.
fn snapshot(dir: &Path) -> Vec<(std::path::PathBuf, u64)> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).expect("a folder") {
            let e = e.expect("an entry");
            let meta = e.metadata().expect("metadata");
            if meta.is_dir() {
                todo.push(e.path());
            } else {
                out.push((e.path(), meta.len()));
            }
        }
    }
    out.sort();
    out
}

/// A refused merge or report changes no file: a merge into one of its own shards, a merge of
/// a folder that is no shard into an earlier report, and a report whose `--cache` is a file
/// are refused (exit 2) before the output folder's earlier report is removed.
#[test]
fn refused_merges_and_reports_change_no_file() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "tiny.toml", SUITE);
    for k in 0..3 {
        shard(&suite, dir.path(), k, 3);
    }
    let s = |k: u32| dir.path().join("shards").join(k.to_string());
    let kept = snapshot(&s(0));
    let o = merge(&[&s(0), &s(1), &s(2)], &s(0));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("would write over the shard"), "{}", stderr(&o));
    assert_eq!(snapshot(&s(0)), kept, "the shard is untouched");
    // A folder inside one of the shards is refused too.
    let o = merge(&[&s(0), &s(1), &s(2)], &s(1).join("merged"));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));

    let earlier = dir.path().join("earlier");
    let o = shadowbench(&["report", "--suite", &suite, "--out", path(&earlier)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let kept = snapshot(&earlier);
    assert!(kept.len() > 10, "a whole report: {kept:?}");
    let not_a_shard = dir.path().join("empty");
    std::fs::create_dir_all(&not_a_shard).expect("folder");
    let o = merge(&[&not_a_shard], &earlier);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a shard's folder"), "{}", stderr(&o));
    assert_eq!(snapshot(&earlier), kept, "the earlier report is untouched");

    let file = dir.path().join("cache.txt");
    std::fs::write(&file, "not a folder").expect("writes");
    for cache in [file.clone(), file.join("inside")] {
        let o = shadowbench(&[
            "report",
            "--suite",
            &suite,
            "--out",
            path(&earlier),
            "--cache",
            path(&cache),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("--cache") && stderr(&o).contains("is a file"),
            "{}",
            stderr(&o)
        );
        assert_eq!(snapshot(&earlier), kept, "the earlier report is untouched");
    }
}
