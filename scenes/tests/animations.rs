//! Animated scene files: every bad input of `[animation]` refused with the file, the line and
//! the key as written; keys reached exactly at their frames through a scene file.

use glam::{DQuat, DVec3, EulerRot};
use scenes::{registry, Camera, Light, SceneError};
use std::path::Path;

/// A still scene with a directional light: a ground plane and a square named `square`.
const DIRECTIONAL: &str = r#"resolution = [64, 48]
[camera.perspective]
eye = [0.0, 6.0, 8.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 45.0
[light.directional]
direction = [-0.3, -1.0, -0.2]
[[object]]
name = "ground"
shape.plane = { size = 10.0 }
[[object]]
name = "square"
shape.plane = { size = 2.0 }
transform = { translate = [0.0, 1.5, 0.0] }
"#;

/// The same scene under a spot light and seen by an orthographic camera.
const SPOT: &str = r#"resolution = [64, 48]
[camera.orthographic]
eye = [0.0, 6.0, 8.0]
target = [0.0, 0.0, 0.0]
height = 12.0
[light.spot]
position = [3.0, 9.0, 2.0]
target = [0.0, 0.0, 0.0]
fov_deg = 75.0
[[object]]
name = "ground"
shape.plane = { size = 10.0 }
"#;

/// Resolves `text` as the scene file `dir/anim.toml`.
fn resolve(dir: &Path, text: &str) -> Result<scenes::Scene, SceneError> {
    let path = dir.join("anim.toml");
    std::fs::write(&path, text).expect("writes");
    registry::describe(path.to_str().expect("utf-8"))?.resolve()
}

#[test]
fn bad_animations_are_refused_naming_the_line_and_key() {
    let dir = tempfile::tempdir().expect("tempdir");
    // (base scene, `[animation]` text with the line at fault marked `# <-`, key, what the
    // message says).
    let cases: &[(&str, &str, &str, &str)] = &[
        (DIRECTIONAL, "[animation]\nframes = 0 # <-\n", "animation.frames", "got 0"),
        (DIRECTIONAL, "[animation]\nframes = 1001 # <-\n", "animation.frames", "1..=1000"),
        (
            DIRECTIONAL,
            "[[animation.light]]\ntime = 0.0\n[[animation.light]]\ntime = 1.0\n\
             [[animation.light]]\ntime = 1.0 # <-\n",
            "animation.light[2].time",
            "strictly increase",
        ),
        (
            DIRECTIONAL,
            "[[animation.light]]\ntime = nan # <-\n",
            "animation.light[0].time",
            "finite",
        ),
        (
            DIRECTIONAL,
            "[[animation.light]]\ntime = 0.0\n[[animation.light]]\ntime = 1.0\n\
             direction = [0.0, 0.0, 0.0] # <-\n",
            "animation.light[1].direction",
            "non-zero",
        ),
        (
            DIRECTIONAL,
            "[[animation.light]]\ntime = 0.0\ndirection = [inf, -1.0, 0.0] # <-\n",
            "animation.light[0].direction",
            "finite",
        ),
        (
            DIRECTIONAL,
            "[[animation.light]]\ntime = 0.0\ndirection = [0.0, -2.0, 0.0]\n\
             [[animation.light]]\ntime = 1.0\ndirection = [0.0, 1.0, 0.0] # <-\n",
            "animation.light[1].direction",
            "opposite",
        ),
        (
            DIRECTIONAL,
            "[[animation.light]]\ntime = 0.0\nposition = [0.0, 5.0, 0.0] # <-\n",
            "animation.light[0].position",
            "directional",
        ),
        (
            SPOT,
            "[[animation.light]]\ntime = 0.0\ndirection = [0.0, -1.0, 0.0] # <-\n",
            "animation.light[0].direction",
            "spot",
        ),
        (
            SPOT,
            "[[animation.light]]\ntime = 0.0\nfov_deg = 171.0 # <-\n",
            "animation.light[0].fov_deg",
            "(0, 170]",
        ),
        (
            SPOT,
            "[[animation.light]]\ntime = 0.0\n[[animation.light]]\ntime = 1.0\n\
             position = [0.0, 0.0, 0.0]\ntarget = [3.0, 9.0, 2.0] # <-\n",
            "animation.light[1].target",
            "opposite",
        ),
        (
            SPOT,
            "[[animation.light]]\ntime = 0.0\nposition = [0.0, 0.0, 0.0] # <-\n",
            "animation.light[0].position",
            "must differ from the target",
        ),
        (
            SPOT,
            "[[animation.light]]\ntime = 0.0\nposition = [2e15, 9.0, 2.0] # <-\n",
            "animation.light[0].position",
            "beyond the supported range",
        ),
        (
            DIRECTIONAL,
            "[[animation.camera]]\ntime = 0.0\nfov_y_deg = 180.0 # <-\n",
            "animation.camera[0].fov_y_deg",
            "(0, 180)",
        ),
        (
            DIRECTIONAL,
            "[[animation.camera]]\ntime = 0.0\neye = [0.0, 0.0, 0.0] # <-\n",
            "animation.camera[0].eye",
            "must differ from the target",
        ),
        (
            DIRECTIONAL,
            "[[animation.camera]]\ntime = 0.0\nheight = 3.0 # <-\n",
            "animation.camera[0].height",
            "perspective",
        ),
        (
            SPOT,
            "[[animation.camera]]\ntime = 0.0\nfov_y_deg = 30.0 # <-\n",
            "animation.camera[0].fov_y_deg",
            "orthographic",
        ),
        (
            SPOT,
            "[[animation.camera]]\ntime = 0.0\nheight = -1.0 # <-\n",
            "animation.camera[0].height",
            "positive",
        ),
        (
            DIRECTIONAL,
            "[[animation.camera]]\ntime = 0.0\n[[animation.camera]]\ntime = 1.0\n\
             eye = [0.0, -6.0, -8.0] # <-\n",
            "animation.camera[1].eye",
            "opposite",
        ),
        (
            DIRECTIONAL,
            "[[animation.camera]]\ntime = 0.0\nup = [0.0, 1.0, 0.0]\n[[animation.camera]]\n\
             time = 1.0\nup = [0.0, -1.0, 0.0] # <-\n",
            "animation.camera[1].up",
            "opposite",
        ),
        (
            DIRECTIONAL,
            "[[animation.camera]]\ntime = 0.0\neye = [0.0, 6.0, 1.1e15] # <-\n",
            "animation.camera[0].eye",
            "beyond the supported range",
        ),
        (
            DIRECTIONAL,
            "[[animation.object]]\nname = \"squares\" # <-\n[[animation.object.key]]\ntime = 0.0\n",
            "animation.object[0].name",
            "`ground`, `square`",
        ),
        (
            DIRECTIONAL,
            "[[animation.object]]\nname = \"square\"\n[[animation.object.key]]\ntime = 0.0\n\
             [[animation.object]]\nname = \"square\" # <-\n[[animation.object.key]]\ntime = 0.0\n",
            "animation.object[1].name",
            "one track per object",
        ),
        (
            DIRECTIONAL,
            "[[animation.object]]\nname = \"square\"\nkey = [] # <-\n",
            "animation.object[0].key",
            "at least one key",
        ),
        (
            DIRECTIONAL,
            "[[animation.object]]\nname = \"square\"\n[[animation.object.key]]\ntime = 2.0\n\
             [[animation.object.key]]\ntime = -1.0 # <-\n",
            "animation.object[0].key[1].time",
            "strictly increase",
        ),
        (
            DIRECTIONAL,
            "[[animation.object]]\nname = \"square\"\nkey = [{ time = 1.0 },\n\
             { time = 0.5 }] # <-\n",
            "animation.object[0].key[1].time",
            "strictly increase",
        ),
        (
            DIRECTIONAL,
            "[[animation.object]]\nname = \"square\"\n[[animation.object.key]]\ntime = 0.0\n\
             rotate_deg = [0.0, nan, 0.0] # <-\n",
            "animation.object[0].key[0].rotate_deg",
            "finite",
        ),
        (
            DIRECTIONAL,
            "[[animation.object]]\nname = \"square\"\n[[animation.object.key]]\ntime = 0.0\n\
             [[animation.object.key]]\ntime = 1.0\ntranslate = [1e15, 0.0, 0.0] # <-\n",
            "animation.object[0].key[1].translate",
            "beyond the supported range",
        ),
        (
            DIRECTIONAL,
            "[[animation.map_scale]]\ntime = 0.0\nvalue = 1.0\n[[animation.map_scale]]\n\
             time = 1.0\nvalue = 0.0 # <-\n",
            "animation.map_scale[1].value",
            "positive and finite",
        ),
        (
            DIRECTIONAL,
            "[[animation.map_scale]]\ntime = 0.0\nvalue = inf # <-\n",
            "animation.map_scale[0].value",
            "positive and finite",
        ),
    ];
    for (base, animation, key, says) in cases {
        let text = format!("{base}{animation}");
        let line = 1 + text.lines().position(|l| l.ends_with("# <-")).expect("a marked line");
        let err = resolve(dir.path(), &text).expect_err(animation);
        let path = dir.path().join("anim.toml");
        let want = format!("{}: line {line}: `{key}`: ", path.display());
        let message = err.to_string();
        assert!(message.starts_with(&want) && message.contains(says), "{animation}:\n{message}");
    }
}

#[test]
fn malformed_animation_tables_are_parse_errors_naming_the_line() {
    for (animation, names) in [
        ("[animation]\nframe = 3 # <-\n", "frame"),
        ("[[animation.light]]\ntime = 0.0\ncolour = 1.0 # <-\n", "colour"),
        (
            "[[animation.object]]\nname = \"square\"\n[[animation.object.key]]\ntime = 0.0\n\
             translate = [1.0, 2.0] # <-\n",
            "invalid length 2",
        ),
        ("[[animation.map_scale]] # <-\nvalue = 1.0\n", "time"),
        ("[animation]\nframes = -1 # <-\n", "frames"),
    ] {
        let text = format!("{DIRECTIONAL}{animation}");
        let line = 1 + text.lines().position(|l| l.ends_with("# <-")).expect("a marked line");
        let err = scenes::SceneDesc::from_toml(&text, Path::new("anim.toml")).expect_err(animation);
        let message = err.to_string();
        assert!(
            message.contains(&format!("line {line},")) && message.contains(names),
            "{animation}:\n{message}"
        );
    }
}

#[test]
fn a_scene_file_reaches_each_key_exactly_at_its_frame() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Keys at times 0, 1 and 2 of every track, three frames: frame i is at time i.
    let animation = r#"[animation]
frames = 3
[[animation.light]]
time = 0.0
direction = [-0.3, -1.0, 0.2]
[[animation.light]]
time = 2.0
direction = [0.7, -0.9, -0.1]
[[animation.camera]]
time = 1.0
eye = [0.1, 5.3, 7.7]
fov_y_deg = 41.3
[[animation.camera]]
time = 2.0
target = [0.3, 0.1, -0.7]
up = [0.1, 1.0, 0.0]
[[animation.object]]
name = "square"
  [[animation.object.key]]
  time = 0.0
  translate = [0.1, 0.0, 0.0]
  [[animation.object.key]]
  time = 1.0
  translate = [0.3, 0.1, -0.7]
  rotate_deg = [10.0, 33.3, -71.0]
[[animation.map_scale]]
time = 1.0
value = 0.3
[[animation.map_scale]]
time = 2.0
value = 0.7
"#;
    let scene = resolve(dir.path(), &format!("{DIRECTIONAL}{animation}")).expect("valid");
    let a = &scene.animation;
    assert_eq!((a.frames(), a.time(0), a.time(1), a.time(2)), (3, 0.0, 1.0, 2.0));
    assert!(a.moves_camera() && !a.is_still());
    let unit = |d: DVec3| scenes::direction::unit(d).expect("a direction");
    let directional = |d: DVec3| Light::Directional { direction: unit(d) };
    let camera =
        |eye: [f64; 3], target: [f64; 3], up: [f64; 3], fov_y_deg: f64| Camera::Perspective {
            eye: DVec3::from(eye),
            target: DVec3::from(target),
            up: DVec3::from(up),
            fov_y_deg,
            near: 0.01,
        };
    let poses: Vec<_> = (0..3).map(|i| a.pose(&scene, i)).collect();
    assert_eq!(poses[0].light, directional(DVec3::new(-0.3, -1.0, 0.2)));
    assert_eq!(poses[2].light, directional(DVec3::new(0.7, -0.9, -0.1)));
    // The first camera key is held before its time; fields a key leaves out are the scene's.
    let first = camera([0.1, 5.3, 7.7], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 41.3);
    assert_eq!((&poses[0].camera, &poses[1].camera), (&first, &first));
    assert_eq!(poses[2].camera, camera([0.0, 6.0, 8.0], [0.3, 0.1, -0.7], [0.1, 1.0, 0.0], 45.0));
    assert_eq!([0, 1, 2].map(|i| a.map_scale(i)), [0.3, 0.3, 0.7]);
    // The square: translated alone at time 0, turned about its rest centre at time 1, and
    // held there after.
    let rest = &scene.objects[1].mesh;
    let (lo, hi) = rest.bounds().expect("vertices");
    let centre = 0.5 * (lo + hi);
    let r = DVec3::new(10.0, 33.3, -71.0);
    let q = DQuat::from_euler(EulerRot::ZYX, r.z.to_radians(), r.y.to_radians(), r.x.to_radians());
    let t = DVec3::new(0.3, 0.1, -0.7);
    for (i, want) in [
        (0, rest.positions.iter().map(|&p| p + DVec3::new(0.1, 0.0, 0.0)).collect::<Vec<_>>()),
        (1, rest.positions.iter().map(|&p| q * (p - centre) + centre + t).collect()),
        (2, rest.positions.iter().map(|&p| q * (p - centre) + centre + t).collect()),
    ] {
        assert_eq!(poses[i].objects[1].mesh.positions, want, "frame {i}");
        assert_eq!(poses[i].objects[0], scene.objects[0], "frame {i}");
    }
    // Resampled over the same span.
    let five = a.with_frames(5).expect("5 frames");
    assert_eq!([0, 1, 2, 3, 4].map(|i| five.time(i)), [0.0, 0.5, 1.0, 1.5, 2.0]);
    assert_eq!(five.pose(&scene, 2), poses[1]);
}

#[test]
fn a_motion_that_may_shrink_the_scene_below_the_smallest_extent_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let tiny = r#"[camera.perspective]
eye = [0.0, 6.0, 8.0]
target = [0.0, 0.0, 0.0]
fov_y_deg = 45.0
[light.directional]
direction = [-0.3, -1.0, -0.2]
[[object]]
name = "speck"
shape.plane = { size = 1e-9 }
transform = { scale = [0.8, 0.8, 0.8] }
"#;
    resolve(dir.path(), tiny).expect("a still speck is within the limits");
    let moving =
        "[[animation.object]] # <-\nname = \"speck\"\n[[animation.object.key]]\ntime = 0.0\n";
    let text = format!("{tiny}{moving}");
    let err = resolve(dir.path(), &text).expect_err("may shrink");
    assert!(matches!(err, SceneError::OutOfRange { .. }), "{err}");
    let line = 1 + text.lines().position(|l| l.ends_with("# <-")).expect("marked");
    assert!(err.to_string().contains(&format!("line {line}: `animation.object`: ")), "{err}");
}
