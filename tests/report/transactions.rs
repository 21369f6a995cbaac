//! Outputs as transactions (`reports::publish`): two writers of one folder give one output
//! and one clear refusal, never a mixed folder; a report killed at any moment (SIGKILL or
//! SIGINT) and run again finishes equal to one that was never interrupted; a merge refuses a
//! shard with a file, a row or a build missing or changed, naming it; a full disk leaves no
//! truncated file under its final name; `render` refuses a folder of someone else's files, and
//! `report --baseline` a report changed since it was written.

use crate::common::{assert_same_report, shadowbench, stderr, write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// One scene, one method: a report of two runs that takes about a second.
const SUITE: &str = r#"
name = "txn"
width = 64
height = 48
warmup = 0
repeats = 1
scenes = ["plane-square", "cage"]

[[run]]
method = "sm"
map_res = [64]
"#;

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Starts `shadowbench args` with `slow` (a `SHADOWBENCH_SLOWDOWN` value, so that it runs long
/// enough to be caught in the middle), its output discarded. It is started through `env
/// --default-signal=INT` (GNU coreutils), since a test run from a background job inherits
/// SIGINT ignored, and `kill -INT` is to stop it as it stops a command at a terminal.
fn spawn(args: &[&str], slow: Option<&str>) -> Child {
    let mut c = Command::new("env");
    c.arg("--default-signal=INT").arg(env!("CARGO_BIN_EXE_shadowbench"));
    c.args(args).stdout(Stdio::null()).stderr(Stdio::piped());
    match slow {
        Some(s) => c.env("SHADOWBENCH_SLOWDOWN", s),
        None => c.env_remove("SHADOWBENCH_SLOWDOWN"),
    };
    c.spawn().expect("the shadowbench binary starts")
}

/// Waits until the lock file `lock` names `child` as its holder, at most 20 s. The holder
/// writes its name only once it holds the lock: the file's mere presence is not enough, for
/// the first writer creates it before it takes the lock, and a second writer started in
/// between may take the lock first.
fn wait_for_holder(lock: &Path, child: &std::process::Child) {
    let me = format!("process {}\n", child.id());
    let start = Instant::now();
    while !std::fs::read_to_string(lock).is_ok_and(|t| t.starts_with(&me)) {
        assert!(start.elapsed() < Duration::from_secs(20), "{} never named {me}", lock.display());
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// The folder's manifest, checked against its files with `sha256sum`-free means: every listed
/// file present with its size; and no staging folder or lock file left.
fn assert_whole(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join(".shadowbench-manifest"))
        .unwrap_or_else(|e| panic!("{}: no manifest: {e}", dir.display()));
    let m: serde_json::Value = serde_json::from_str(&text).expect("the manifest parses");
    for e in m["files"].as_array().expect("files") {
        let p = dir.join(e["path"].as_str().expect("path"));
        let size =
            std::fs::metadata(&p).unwrap_or_else(|_| panic!("{} missing", p.display())).len();
        assert_eq!(Some(size), e["size"].as_u64(), "{}", p.display());
    }
    assert!(!dir.join(".shadowbench-staging").exists(), "{}: staging left", dir.display());
    assert!(!dir.join(".shadowbench-lock").exists(), "{}: lock left", dir.display());
    m
}

/// `render --scene cage --method sm` at `size x size` into `out`.
fn render_cage(size: &str, out: &Path) -> std::process::Output {
    let args = ["render", "--scene", "cage", "--method", "sm", "--width", size, "--height", size];
    shadowbench(&[&args[..], &["--out", path(out)]].concat())
}

#[test]
fn two_renders_into_one_folder_give_one_output_and_one_refusal() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out");
    let args = |map: &'static str| {
        vec!["render", "--scene", "cage", "--method", "sm", "--width", "64", "--height", "48"]
            .into_iter()
            .chain(["--map-res", map, "--out", path(&out)])
            .map(str::to_owned)
            .collect::<Vec<String>>()
    };
    for k in 0..10 {
        let (a, b) = (args("64"), args("128"));
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        let b: Vec<&str> = b.iter().map(String::as_str).collect();
        let first = spawn(&a, Some("sm=200"));
        wait_for_holder(&out.join(".shadowbench-lock"), &first);
        let second = shadowbench(&b);
        let first = first.wait_with_output().expect("the first ends");
        assert_eq!(first.status.code(), Some(0), "try {k}: {}", stderr(&first));
        assert_eq!(second.status.code(), Some(2), "try {k}: {}", stderr(&second));
        let err = stderr(&second);
        assert!(err.contains("another shadowbench is writing this folder"), "{err}");
        assert!(err.contains("process ") && err.contains("render"), "names the holder: {err}");
        assert_whole(&out);
        let run: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).expect("run.json"))
                .expect("parses");
        assert_eq!(run["params"]["map_res"], 64, "try {k}: the first writer's run");
    }
}

#[test]
fn two_reports_into_one_folder_give_one_report_and_one_refusal() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "txn.toml", SUITE);
    let other =
        write(dir.path(), "other.toml", &SUITE.replace("name = \"txn\"", "name = \"other\""));
    let out = dir.path().join("out");
    for k in 0..10 {
        let first = spawn(&["report", "--suite", &suite, "--out", path(&out)], Some("sm=30"));
        wait_for_holder(&out.join(".shadowbench-lock"), &first);
        let second = shadowbench(&["report", "--suite", &other, "--out", path(&out)]);
        let first = first.wait_with_output().expect("the first ends");
        assert_eq!(first.status.code(), Some(0), "try {k}: {}", stderr(&first));
        assert_eq!(second.status.code(), Some(2), "try {k}: {}", stderr(&second));
        assert!(stderr(&second).contains("another shadowbench is writing"), "{}", stderr(&second));
        assert_whole(&out);
        let runs: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join("runs.json")).expect("runs.json"),
        )
        .expect("parses");
        assert_eq!(runs["suite"]["name"], "txn", "try {k}: the first writer's report");
    }
}

#[test]
fn a_report_killed_at_any_moment_and_run_again_equals_an_uninterrupted_one() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "txn.toml", SUITE);
    let whole = dir.path().join("whole");
    let o = shadowbench(&["report", "--suite", &suite, "--out", path(&whole)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = dir.path().join("out");
    let shard_out = dir.path().join("shard");
    // An earlier report in the folder, so that a kill can also fall while it is replaced.
    let o = shadowbench(&["report", "--suite", &suite, "--out", path(&out)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // How long a slowed run takes, so that the kills fall from its start to its end.
    let slow = Some("sm=40");
    let start = Instant::now();
    let status = spawn(&["report", "--suite", &suite, "--out", path(&out)], slow).wait();
    assert!(status.expect("runs").success());
    let length = start.elapsed().as_secs_f64();
    let mut killed = 0;
    for (k, share) in [0.0, 0.03, 0.1, 0.25, 0.45, 0.65, 0.85, 0.97].into_iter().enumerate() {
        let signal = if k % 2 == 0 { "-KILL" } else { "-INT" };
        let ms = (share * length * 1000.0) as u64;
        for (folder, shard) in [(&out, None), (&shard_out, Some("0/1"))] {
            let mut args = vec!["report", "--suite", &suite, "--out", path(folder)];
            if let Some(s) = shard {
                args.extend(["--shard", s]);
            }
            let mut child = spawn(&args, slow);
            std::thread::sleep(Duration::from_millis(ms));
            let pid = child.id().to_string();
            let _ = Command::new("kill").args([signal, &pid]).status();
            let status = child.wait().expect("ends");
            killed += usize::from(!status.success());
            let o = shadowbench(&args);
            assert_eq!(o.status.code(), Some(0), "after {signal} at {ms} ms: {}", stderr(&o));
            assert_whole(folder);
        }
        assert_same_report(&whole, &out);
    }
    assert!(killed >= 10, "most runs were caught while running ({killed} of 16)");
    // The shard, rerun after its kills, merges into the same report.
    let merged = dir.path().join("merged");
    let o = shadowbench(&["report", "merge", path(&shard_out), "--out", path(&merged)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_same_report(&whole, &merged);
}

/// Runs the two shards of the suite into `dir/s0` and `dir/s1`.
fn shards(suite: &str, dir: &Path) -> [PathBuf; 2] {
    let s = [dir.join("s0"), dir.join("s1")];
    for (k, d) in s.iter().enumerate() {
        let o = shadowbench(&[
            "report",
            "--suite",
            suite,
            "--shard",
            &format!("{k}/2"),
            "--out",
            path(d),
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    s
}

/// Rewrites `runs.json` of the shard `dir` through `change` and puts its new size and hash in
/// the manifest, as a shard of another build or an edited one would have them.
fn rewrite_runs(dir: &Path, change: impl FnOnce(&mut serde_json::Value)) {
    use sha2::Digest;
    let file = dir.join("runs.json");
    let mut runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&file).expect("runs.json")).expect("parses");
    change(&mut runs);
    let text = serde_json::to_string_pretty(&runs).expect("json");
    std::fs::write(&file, &text).expect("writes");
    let mpath = dir.join(".shadowbench-manifest");
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&mpath).expect("manifest")).expect("parses");
    for e in m["files"].as_array_mut().expect("files") {
        if e["path"] == "runs.json" {
            e["size"] = text.len().into();
            let hash = sha2::Sha256::digest(text.as_bytes());
            e["sha256"] = hash.iter().map(|b| format!("{b:02x}")).collect::<String>().into();
        }
    }
    std::fs::write(&mpath, serde_json::to_string(&m).expect("json")).expect("writes");
}

/// Copies the folder `from` to `to` (files only, one level of folders deep is enough here).
fn copy_dir(from: &Path, to: &Path) {
    for e in walk(from) {
        let dst = to.join(e.strip_prefix(from).expect("under"));
        std::fs::create_dir_all(dst.parent().expect("parent")).expect("mkdir");
        std::fs::copy(&e, dst).expect("copies");
    }
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).expect("a folder") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                todo.push(p);
            } else {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

#[test]
fn a_merge_refuses_a_shard_with_a_file_a_row_or_a_build_missing_or_changed() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let suite = write(dir.path(), "txn.toml", SUITE);
    let [s0, s1] = shards(&suite, dir.path());
    let out = dir.path().join("merged");
    let merge = |a: &Path, extra: &[&str]| {
        let mut args = vec!["report", "merge", path(a), path(&s1), "--out", path(&out)];
        args.extend(extra);
        shadowbench(&args)
    };
    let o = merge(&s0, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    std::fs::remove_dir_all(&out).expect("removes");

    // Each damage of a copy of shard 0, and the words the refusal must hold.
    type Damage = Box<dyn Fn(&Path)>;
    let exr =
        |d: &Path| walk(&d.join("visibility")).into_iter().next().expect("an EXR of the shard");
    let cases: Vec<(&str, Damage, Vec<&str>)> = vec![
        (
            "a visibility EXR removed",
            Box::new(move |d: &Path| std::fs::remove_file(exr(d)).expect("rm")),
            vec![".exr", "missing"],
        ),
        (
            "a truncated EXR",
            Box::new(move |d: &Path| {
                let f = exr(d);
                let bytes = std::fs::read(&f).expect("reads");
                std::fs::write(&f, &bytes[..bytes.len() / 2]).expect("writes");
            }),
            vec![".exr", "bytes"],
        ),
        (
            "the runs folder removed",
            Box::new(|d: &Path| std::fs::remove_dir_all(d.join("runs")).expect("rm")),
            vec!["runs/", "missing"],
        ),
        (
            "a row deleted from runs.json",
            Box::new(|d: &Path| {
                let f = d.join("runs.json");
                let mut v: serde_json::Value =
                    serde_json::from_str(&std::fs::read_to_string(&f).expect("r")).expect("p");
                v["rows"].as_array_mut().expect("rows").pop();
                std::fs::write(&f, serde_json::to_string_pretty(&v).expect("j")).expect("w");
            }),
            vec!["runs.json"],
        ),
        (
            "a row duplicated, manifest updated",
            Box::new(|d: &Path| {
                rewrite_runs(d, |v| {
                    let rows = v["rows"].as_array_mut().expect("rows");
                    let first = rows[0].clone();
                    rows.push(first);
                })
            }),
            vec!["twice"],
        ),
        (
            "another version, manifest updated",
            Box::new(|d: &Path| {
                rewrite_runs(d, |v| {
                    v["shards"][0]["provenance"]["version"] = "0.0.9".into();
                })
            }),
            vec!["0.0.9", "--allow-mixed"],
        ),
        (
            "another commit, manifest updated",
            Box::new(|d: &Path| {
                rewrite_runs(d, |v| {
                    v["shards"][0]["provenance"]["commit"] = "0123456789abcdef".into();
                })
            }),
            vec!["0123456789abcdef", "--allow-mixed"],
        ),
    ];
    for (k, (what, damage, words)) in cases.iter().enumerate() {
        let copy = dir.path().join(format!("damaged-{k}"));
        copy_dir(&s0, &copy);
        damage(&copy);
        let o = merge(&copy, &[]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{what}: {err}");
        for w in words {
            assert!(err.contains(w), "{what}: `{w}` not in: {err}");
        }
        assert!(err.contains(path(&copy)), "{what}: names the shard: {err}");
        assert!(!out.exists(), "{what}: nothing written");
    }
    // Shards of two builds merge with --allow-mixed, which the provenance records.
    let copy = dir.path().join("damaged-5");
    let o = merge(&copy, &["--allow-mixed"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("runs.json")).expect("r"))
            .expect("parses");
    let mixed = runs["provenance"]["mixed"].as_array().expect("mixed recorded");
    assert_eq!(mixed.len(), 2);
    assert!(mixed[0].as_str().expect("text").contains("0.0.9"), "{mixed:?}");
}

#[test]
fn render_refuses_a_folder_of_foreign_files_and_a_report_folder() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let foreign = dir.path().join("foreign");
    std::fs::create_dir_all(&foreign).expect("mkdir");
    std::fs::write(foreign.join("run.json"), "mine").expect("writes");
    let render = |out: &Path| render_cage("32", out);
    let o = render(&foreign);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("run.json, which shadowbench did not write"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(foreign.join("run.json")).expect("kept"), "mine");
    assert_eq!(walk(&foreign).len(), 1, "nothing added");

    let suite = write(dir.path(), "txn.toml", SUITE);
    let report = dir.path().join("report");
    let o = shadowbench(&["report", "--suite", &suite, "--out", path(&report)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let before = walk(&report);
    let o = render(&report);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("holds a report"), "{}", stderr(&o));
    assert_eq!(walk(&report), before);

    // A report changed after it was written is refused as a baseline, naming the file.
    let runs = report.join("runs.json");
    let text = std::fs::read_to_string(&runs).expect("runs.json");
    std::fs::write(&runs, text.replacen("\"sm\"", "\"xx\"", 1)).expect("writes");
    let later = dir.path().join("later");
    let o = shadowbench(&[
        "report",
        "--suite",
        &suite,
        "--out",
        path(&later),
        "--baseline",
        path(&report),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("runs.json") && stderr(&o).contains("changed"), "{}", stderr(&o));
    assert!(!later.exists(), "refused before anything is written");

    // A render replaces its own earlier run.
    let mine = dir.path().join("mine");
    for _ in 0..2 {
        let o = render(&mine);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    assert_whole(&mine);
}

/// A small tmpfs where the machine lets the test mount one (root, a mount namespace that
/// allows it), unmounted when dropped.
struct SmallDisk(PathBuf);

impl SmallDisk {
    fn mount(at: &Path, size: &str) -> Option<Self> {
        std::fs::create_dir_all(at).ok()?;
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs", path(at)])
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        ok.then(|| SmallDisk(at.to_owned()))
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

#[test]
fn a_full_disk_leaves_no_truncated_file_under_its_final_name() {
    let _machine = crate::common::machine_shared();
    let dir = tempfile::tempdir().expect("tempdir");
    let Some(disk) = SmallDisk::mount(&dir.path().join("disk"), "96k") else {
        eprintln!("skipped: this machine does not let the test mount a tmpfs");
        return;
    };
    let out = disk.0.join("out");
    let render = |size: &str| render_cage(size, &out);
    let o = render("16");
    assert_eq!(o.status.code(), Some(0), "a small run fits: {}", stderr(&o));
    let before: Vec<(PathBuf, Vec<u8>)> =
        walk(&out).into_iter().map(|p| (p.clone(), std::fs::read(&p).expect("r"))).collect();
    let o = render("400");
    assert_eq!(o.status.code(), Some(1), "the disk is full: {}", stderr(&o));
    assert!(stderr(&o).contains("No space left"), "{}", stderr(&o));
    let after: Vec<(PathBuf, Vec<u8>)> =
        walk(&out).into_iter().map(|p| (p.clone(), std::fs::read(&p).expect("r"))).collect();
    assert_eq!(after, before, "the earlier run is whole and nothing else is left");
    assert_whole(&out);
    drop(disk);
}
