//! `--scene` with a glTF file: the same frame, pixel for pixel, as the same scene written as a
//! TOML scene file and OBJ files; a bad glTF file refused with exit code 2 naming the cause.

mod common;

use common::{shadowbench, stderr, write};
use std::path::Path;

/// The light of the scene: `directional` (along (-0.5, -1, -0.25)), `spot` (at (3, 9, 2),
/// aimed at the origin, outer cone angle 0.5 radians), or another type (`point`, refused).
fn light(light_type: &str) -> (String, &'static str) {
    match light_type {
        "spot" => (
            r#"{"type": "spot", "spot": {"outerConeAngle": 0.5}}"#.to_owned(),
            "[1,0,0,0, 0,1,0,0, 3,9,2,0, 3,9,2,1]",
        ),
        t => (format!(r#"{{"type": "{t}"}}"#), "[1,0,0,0, 0,1,0,0, 0.5,1,0.25,0, 0,0,0,1]"),
    }
}

/// A GLB (glTF 2.0 §4.4) of a ground quad (indexed, scaled by (2, 1, 2)) and a translucent
/// triangle under a transformed parent, a camera under a transformed rig and a light (see
/// [`light`]); `light_type` is the light's `type`.
fn glb(light_type: &str) -> Vec<u8> {
    glb_edited(light_type, |json| json)
}

/// [`glb`] with its JSON chunk passed through `edit`.
fn glb_edited(light_type: &str, edit: impl Fn(String) -> String) -> Vec<u8> {
    let (light, light_matrix) = light(light_type);
    let mut bin: Vec<u8> = Vec::new();
    for v in [[-4.0f32, 0.0, -4.0], [4.0, 0.0, -4.0], [4.0, 0.0, 4.0], [-4.0, 0.0, 4.0]] {
        bin.extend(v.iter().flat_map(|c| c.to_le_bytes()));
    }
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        bin.extend(v.iter().flat_map(|c| c.to_le_bytes()));
    }
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{light}]}}}},
  "scene": 0, "scenes": [{{"nodes": [0, 1, 3, 5]}}],
  "nodes": [
    {{"name": "ground", "mesh": 0, "scale": [2, 1, 2]}},
    {{"name": "parent", "translation": [1, 2, 0], "scale": [2, 2, 2], "children": [2]}},
    {{"name": "caster", "mesh": 1, "matrix": [0,0,-1,0, 0,1,0,0, 1,0,0,0, 0,0.5,0,1]}},
    {{"name": "rig", "translation": [0, 2, 0], "children": [4]}},
    {{"name": "cam", "camera": 0, "translation": [0, 0, 10]}},
    {{"name": "sun", "extensions": {{"KHR_lights_punctual": {{"light": 0}}}},
      "matrix": {light_matrix}}}],
  "cameras": [{{"type": "perspective",
               "perspective": {{"yfov": 0.75, "znear": 0.125, "aspectRatio": 1.5}}}}],
  "meshes": [
    {{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}},
    {{"primitives": [{{"attributes": {{"POSITION": 2}}, "material": 1}}]}}],
  "materials": [
    {{"pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.5, 0.25, 1]}}}},
    {{"alphaMode": "BLEND", "pbrMetallicRoughness": {{"baseColorFactor": [0.25, 0.5, 0.75, 0.5]}}}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
      "min": [-4, 0, -4], "max": [4, 0, 4]}},
    {{"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}},
    {{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 1, 0]}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
                  {{"buffer": 0, "byteOffset": 48, "byteLength": 12}},
                  {{"buffer": 0, "byteOffset": 60, "byteLength": 36}}],
  "buffers": [{{"byteLength": 96}}]}}"#
    );
    let mut json = edit(json).into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = (12 + 8 + json.len() + 8 + bin.len()) as u32;
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(total.to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// The same scene as a TOML scene file and OBJ files, in world space, with the light of
/// `light_type` (see [`light`]).
fn toml_scene(dir: &Path, light_type: &str) -> String {
    let light = match light_type {
        "spot" => format!(
            "[light.spot]\nposition = [3.0, 9.0, 2.0]\ntarget = [0.0, 0.0, 0.0]\nfov_deg = {:?}\n",
            1.0f64.to_degrees()
        ),
        _ => "[light.directional]\ndirection = [-0.5, -1.0, -0.25]\n".to_owned(),
    };
    write(dir, "ground.obj", "v -8 0 -8\nv 8 0 -8\nv 8 0 8\nv -8 0 8\nf 1 2 3\nf 1 3 4\n");
    write(dir, "caster.obj", "v 1 3 0\nv 1 3 -2\nv 1 5 0\nf 1 2 3\n");
    let text = format!(
        "resolution = [900, 600]\n[camera.perspective]\neye = [0.0, 2.0, 10.0]\n\
         target = [0.0, 2.0, 9.0]\nfov_y_deg = {:?}\nnear = 0.125\n{light}\
         [[object]]\nshape.file = {{ path = \"ground.obj\" }}\n\
         material = {{ color = [0.5, 0.5, 0.25] }}\n\
         [[object]]\nshape.file = {{ path = \"caster.obj\" }}\n\
         material = {{ color = [0.25, 0.5, 0.75], opacity = 0.5 }}\n",
        0.75f64.to_degrees()
    );
    write(dir, "scene.toml", &text)
}

/// Every method of the registry's table and the ray-traced reference (`exact` refuses the
/// translucent caster in both forms), under a directional and a spot light.
#[test]
fn a_gltf_scene_renders_as_its_toml_and_obj_files_pixel_for_pixel() {
    let dir = tempfile::tempdir().expect("tempdir");
    let every = methods::registry::METHODS.iter().map(|m| m.name).chain(["raytrace"]);
    let methods: Vec<&str> = every.collect();
    for light_type in ["directional", "spot"] {
        let glb_path = dir.path().join(format!("{light_type}.glb"));
        std::fs::write(&glb_path, glb(light_type)).expect("writes");
        let toml_path = toml_scene(dir.path(), light_type);
        for method in &methods {
            let mut images = Vec::new();
            for (form, scene) in [("glb", glb_path.to_str().expect("utf-8")), ("toml", &toml_path)]
            {
                let out = dir.path().join(format!("{light_type}-{method}-{form}"));
                let o = shadowbench(&[
                    "render",
                    "--scene",
                    scene,
                    "--method",
                    method,
                    "--width",
                    "48",
                    "--height",
                    "32",
                    "--out",
                    out.to_str().expect("utf-8"),
                ]);
                assert_eq!(o.status.code(), Some(0), "{method} {form}: {}", stderr(&o));
                images.push(std::fs::read(out.join("visibility.exr")).expect("an image"));
            }
            assert!(images[0] == images[1], "{light_type} {method}: the glTF scene differs");
        }
    }
}

#[test]
fn a_gltf_scene_with_a_point_light_is_bad_input_naming_the_node() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("point.glb");
    std::fs::write(&path, glb("point")).expect("writes");
    let o = shadowbench(&["render", "--scene", path.to_str().expect("utf-8"), "--method", "sm"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("point.glb: node `sun` (5): light 0 is a point light"),
        "{}",
        stderr(&o)
    );
}

/// Bad glTF files exit 2 naming the file and the cause: a buffer whose file is missing, an
/// accessor of the wrong type, before anything is computed or written.
#[test]
fn bad_gltf_files_are_bad_input_naming_the_cause() {
    let dir = tempfile::tempdir().expect("tempdir");
    let wrong = dir.path().join("wrong.glb");
    // The indices' accessor as 32-bit floats: not an index type.
    let glb = glb_edited("directional", |j| {
        j.replacen(r#""componentType": 5123"#, r#""componentType": 5126"#, 1)
    });
    std::fs::write(&wrong, glb).expect("writes");
    let missing = dir.path().join("missing.gltf");
    // The same scene as a .gltf whose buffer is a file that is not there.
    let bytes = glb_edited("directional", |j| {
        let with_uri = r#""buffers": [{"byteLength": 96, "uri": "nowhere.bin"}]"#;
        j.replace(r#""buffers": [{"byteLength": 96}]"#, with_uri)
    });
    let len = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes")) as usize;
    let json = String::from_utf8(bytes[20..20 + len].to_vec()).expect("utf-8");
    assert!(json.contains("nowhere.bin"));
    std::fs::write(&missing, json.trim_end()).expect("writes");
    for (path, needles) in [
        (&wrong, &["wrong.glb", "accessor 1", "indices"][..]),
        (&missing, &["missing.gltf", "buffer 0", "nowhere.bin", "missing"][..]),
    ] {
        let out = dir.path().join("out");
        let o = shadowbench(&[
            "render",
            "--scene",
            path.to_str().expect("utf-8"),
            "--method",
            "sm",
            "--out",
            out.to_str().expect("utf-8"),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        for n in needles {
            assert!(stderr(&o).contains(n), "`{n}` not in {}", stderr(&o));
        }
        assert!(!out.exists(), "a refused scene writes nothing");
    }
}
