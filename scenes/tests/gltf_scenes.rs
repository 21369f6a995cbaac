//! glTF scenes: written here by hand (JSON text and buffer bytes, no exporter involved), read
//! as `.glb`, as `.gltf` with an external `.bin` and with a `data:` URI, and compared with the
//! same scene written as a TOML scene file and OBJ files; bad files refused naming the cause;
//! a glTF file as a scene file's object; the export read back.

use scenes::{registry, Camera, GltfError, Light, Scene, SceneError};
use std::path::{Path, PathBuf};

/// The buffer: the quad's 4 positions (48 bytes), its 6 `u16` indices (12 bytes), the
/// triangle's 3 positions (36 bytes).
fn buffer() -> Vec<u8> {
    let quad: [[f32; 3]; 4] =
        [[-4.0, 0.0, -4.0], [4.0, 0.0, -4.0], [4.0, 0.0, 4.0], [-4.0, 0.0, 4.0]];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let tri: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let mut bytes = Vec::new();
    bytes.extend(quad.iter().flatten().flat_map(|c| c.to_le_bytes()));
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    bytes.extend(tri.iter().flatten().flat_map(|c| c.to_le_bytes()));
    assert_eq!(bytes.len(), 96);
    bytes
}

/// The scene's lights: a directional light shining along (-0.5, -1, -0.25), or a spot at
/// (3, 9, 2) aimed at the origin with an outer cone angle of 0.5 radians.
#[derive(Clone, Copy)]
enum Lamp {
    Sun,
    Spot,
}

/// The glTF JSON of the scene. The ground (a quad, indexed, scaled by (2, 1, 2)) is a root;
/// the caster (a triangle, not indexed, translucent) is the child of a node translated by
/// (1, 2, 0) and scaled by 2, turned 90 degrees about y by its own matrix and raised by 0.5;
/// the camera sits on a node translated by (0, 0, 10) under one translated by (0, 2, 0).
/// `buffer` is the buffer's `uri` member (or nothing, for a GLB's BIN chunk).
fn json(lamp: Lamp, buffer: &str) -> String {
    let (light, light_node) = match lamp {
        Lamp::Sun => (
            r#"{"name":"sun-light","type":"directional"}"#,
            r#"{"name":"sun","extensions":{"KHR_lights_punctual":{"light":0}},
                "matrix":[1,0,0,0, 0,1,0,0, 0.5,1,0.25,0, 0,0,0,1]}"#,
        ),
        Lamp::Spot => (
            r#"{"name":"lamp-light","type":"spot","spot":{"outerConeAngle":0.5}}"#,
            r#"{"name":"lamp","extensions":{"KHR_lights_punctual":{"light":0}},
                "matrix":[1,0,0,0, 0,1,0,0, 3,9,2,0, 3,9,2,1]}"#,
        ),
    };
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{light}]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1, 3, 5]}}],
  "nodes": [
    {{"name": "ground", "mesh": 0, "scale": [2, 1, 2]}},
    {{"name": "parent", "translation": [1, 2, 0], "scale": [2, 2, 2], "children": [2]}},
    {{"name": "caster", "mesh": 1, "matrix": [0,0,-1,0, 0,1,0,0, 1,0,0,0, 0,0.5,0,1]}},
    {{"name": "rig", "translation": [0, 2, 0], "children": [4]}},
    {{"name": "cam", "camera": 0, "translation": [0, 0, 10]}},
    {light_node}
  ],
  "cameras": [{{"type": "perspective",
               "perspective": {{"yfov": 0.75, "znear": 0.125, "aspectRatio": 1.5}}}}],
  "meshes": [
    {{"name": "quad", "primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}},
    {{"name": "tri", "primitives": [{{"attributes": {{"POSITION": 2}}, "material": 1}}]}}
  ],
  "materials": [
    {{"name": "grey", "pbrMetallicRoughness": {{"baseColorFactor": [0.5, 0.5, 0.25, 1]}}}},
    {{"name": "glass", "alphaMode": "BLEND",
      "pbrMetallicRoughness": {{"baseColorFactor": [0.25, 0.5, 0.75, 0.5]}}}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
      "min": [-4, 0, -4], "max": [4, 0, 4]}},
    {{"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}},
    {{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 1, 0]}}
  ],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 12}},
    {{"buffer": 0, "byteOffset": 60, "byteLength": 36}}
  ],
  "buffers": [{{"byteLength": 96{buffer}}}]
}}"#
    )
}

/// A GLB container (glTF 2.0 §4.4) of `json` and `bin`, each chunk padded to 4 bytes.
fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    out
}

/// Standard base64 with padding, for `data:` URIs.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(char::from(ALPHABET[(n >> (18 - 6 * k)) as usize & 63]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The same scene as a TOML scene file and two OBJ files, in world space: the quad scaled by
/// (2, 1, 2); the triangle's corners (0,0,0), (1,0,0), (0,1,0) turned about y ((x, y, z) ->
/// (z, y, -x)), raised by 0.5, scaled by 2 and moved by (1, 2, 0).
fn toml_scene(dir: &Path, lamp: Lamp) -> PathBuf {
    std::fs::write(
        dir.join("ground.obj"),
        "v -8 0 -8\nv 8 0 -8\nv 8 0 8\nv -8 0 8\nf 1 2 3\nf 1 3 4\n",
    )
    .expect("writes");
    std::fs::write(dir.join("caster.obj"), "v 1 3 0\nv 1 3 -2\nv 1 5 0\nf 1 2 3\n")
        .expect("writes");
    // The camera's yfov (0.75 rad) and the spot's cone (twice 0.5 rad) in degrees, as the
    // reader converts them.
    let light = match lamp {
        Lamp::Sun => "[light.directional]\ndirection = [-0.5, -1.0, -0.25]\n".to_owned(),
        Lamp::Spot => format!(
            "[light.spot]\nposition = [3.0, 9.0, 2.0]\ntarget = [0.0, 0.0, 0.0]\nfov_deg = {:?}\n",
            1.0f64.to_degrees()
        ),
    };
    let text = format!(
        "name = \"scene\"\nresolution = [900, 600]\n\
         [camera.perspective]\neye = [0.0, 2.0, 10.0]\ntarget = [0.0, 2.0, 9.0]\n\
         up = [0.0, 1.0, 0.0]\nfov_y_deg = {:?}\nnear = 0.125\n{light}\
         [[object]]\nname = \"ground\"\nshape.file = {{ path = \"ground.obj\" }}\n\
         material = {{ color = [0.5, 0.5, 0.25], opacity = 1.0 }}\n\
         [[object]]\nname = \"caster\"\nshape.file = {{ path = \"caster.obj\" }}\n\
         material = {{ color = [0.25, 0.5, 0.75], opacity = 0.5 }}\n",
        0.75f64.to_degrees()
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).expect("writes");
    path
}

fn load(path: &Path) -> Result<Scene, SceneError> {
    registry::load(path.to_str().expect("utf-8"))
}

/// Writes the scene's three glTF forms into `dir`: `scene.glb`, `scene.gltf` with `scene.bin`
/// and `inline/scene.gltf` with a `data:` URI.
fn gltf_forms(dir: &Path, lamp: Lamp) -> [PathBuf; 3] {
    let bin = buffer();
    let glb_path = dir.join("scene.glb");
    std::fs::write(&glb_path, glb(&json(lamp, ""), &bin)).expect("writes");
    let gltf_path = dir.join("scene.gltf");
    std::fs::write(dir.join("scene.bin"), &bin).expect("writes");
    std::fs::write(&gltf_path, json(lamp, r#", "uri": "scene.bin""#)).expect("writes");
    std::fs::create_dir_all(dir.join("inline")).expect("mkdir");
    let inline = dir.join("inline/scene.gltf");
    let uri = format!(r#", "uri": "data:application/octet-stream;base64,{}""#, base64(&bin));
    std::fs::write(&inline, json(lamp, &uri)).expect("writes");
    [glb_path, gltf_path, inline]
}

#[test]
fn a_gltf_scene_is_the_same_scene_as_its_toml_and_obj_files() {
    for lamp in [Lamp::Sun, Lamp::Spot] {
        let dir = tempfile::tempdir().expect("tempdir");
        let want = load(&toml_scene(dir.path(), lamp)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(want.objects.len(), 2);
        assert!(want.effects().transparency);
        for path in gltf_forms(dir.path(), lamp) {
            let described =
                registry::describe(path.to_str().expect("utf-8")).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(described.name(), "scene");
            assert_eq!(described.resolution(), [900, 600]);
            assert!(described.triangles_exact());
            assert_eq!(described.triangles().ok(), Some(3));
            assert_eq!(described.notes(), &[] as &[String]);
            let got = described.resolve().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert_eq!(got, want, "{}", path.display());
        }
    }
}

#[test]
fn strips_and_fans_are_triangulated_as_the_spec_says_and_lines_are_ignored_with_a_note() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Four vertices of a square in z = 0, as a strip, a fan and lines.
    let square: [[f32; 3]; 4] =
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let bin: Vec<u8> = square.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    let text = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"name": "shapes", "mesh": 0}}],
  "meshes": [{{"name": "m", "primitives": [
    {{"attributes": {{"POSITION": 0}}, "mode": 5}},
    {{"attributes": {{"POSITION": 0}}, "mode": 6}},
    {{"attributes": {{"POSITION": 0}}, "mode": 1}}]}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 0]}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 48}}],
  "buffers": [{{"byteLength": 48, "uri": "data:application/octet-stream;base64,{}"}}]}}"#,
        base64(&bin)
    );
    let path = dir.path().join("shapes.gltf");
    std::fs::write(&path, text).expect("writes");
    let described = registry::describe(path.to_str().expect("utf-8")).expect("described");
    assert_eq!(described.triangles().ok(), Some(4));
    assert_eq!(
        described.notes(),
        ["mesh `m` (0), primitive 2: mode Lines casts no shadow, ignored"]
    );
    let scene = described.resolve().unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["shapes#0", "shapes#1"]);
    // Strip: (0 1 2), (1 3 2); fan: (1 2 0), (2 3 0); vertices in order of first use.
    assert_eq!(scene.objects[0].mesh.triangles, [[0, 1, 2], [1, 3, 2]]);
    assert_eq!(scene.objects[1].mesh.triangles, [[0, 1, 2], [1, 3, 2]]);
    let fan_first = scene.objects[1].mesh.positions[0];
    assert_eq!(fan_first.to_array(), [1.0, 0.0, 0.0]);
    // Without a camera or a light: the defaults of a mesh file given as the scene.
    let mesh_default = registry::mesh_scene(Path::new("m.obj"));
    assert_eq!(scene.camera, mesh_default.camera);
    assert_eq!(scene.light, mesh_default.light.normalized());
    assert_eq!([scene.width, scene.height], [800, 600]);
}

/// The scene's `.gltf` with `edit` applied to its JSON text, beside its `.bin`.
fn edited(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    std::fs::write(dir.join("scene.bin"), buffer()).expect("writes");
    let path = dir.join("bad.gltf");
    std::fs::write(&path, edit(json(Lamp::Sun, r#", "uri": "scene.bin""#))).expect("writes");
    path
}

/// The error `describe` then `resolve` give.
fn error_of(path: &Path) -> SceneError {
    match registry::describe(path.to_str().expect("utf-8")) {
        Err(e) => e,
        Ok(d) => d.resolve().expect_err("a bad file"),
    }
}

#[test]
fn bad_gltf_files_are_refused_naming_the_cause() {
    let dir = tempfile::tempdir().expect("tempdir");
    let d = dir.path();

    let path = edited(d, |j| j.replace("scene.bin", "missing.bin"));
    let err = error_of(&path);
    let looked = d.join("missing.bin");
    assert!(
        matches!(&err, SceneError::Gltf(e) if matches!(**e, GltfError::MissingBuffer { buffer: 0, looked: ref l, .. } if *l == looked)),
        "{err}"
    );
    assert_eq!(
        err.to_string(),
        format!(
            "{}: buffer 0 needs the file {}, which is missing",
            path.display(),
            looked.display()
        )
    );

    // The indices as floats.
    let path = edited(d, |j| {
        j.replace(
            r#""componentType": 5123, "count": 6, "type": "SCALAR""#,
            r#""componentType": 5126, "count": 3, "type": "SCALAR""#,
        )
    });
    let err = error_of(&path);
    assert_eq!(
        err.to_string(),
        format!(
            "{}: mesh `quad` (0), primitive 0, accessor 1: indices is Scalar of F32, expected \
             Scalar of U8, U16 or U32",
            path.display()
        )
    );

    // POSITION as unsigned shorts.
    let path = edited(d, |j| {
        j.replacen(
            r#""componentType": 5126, "count": 4"#,
            r#""componentType": 5123, "count": 4"#,
            1,
        )
    });
    let err = error_of(&path);
    assert!(
        err.to_string().ends_with("mesh `quad` (0), primitive 0, accessor 0: POSITION is Vec3 of U16, expected Vec3 of F32"),
        "{err}"
    );

    let path = edited(d, |j| j.replace(r#""type":"directional""#, r#""type":"point""#));
    let err = error_of(&path);
    assert_eq!(
        err.to_string(),
        format!(
            "{}: node `sun` (5): light `sun-light` (0) is a point light; only directional and \
             spot lights cast shadows here",
            path.display()
        )
    );

    let path = edited(d, |j| {
        j.replace(
            r#""extensionsUsed": ["KHR_lights_punctual"],"#,
            r#""extensionsUsed": ["KHR_lights_punctual", "KHR_draco_mesh_compression"],
               "extensionsRequired": ["KHR_lights_punctual", "KHR_draco_mesh_compression"],"#,
        )
    });
    let err = error_of(&path);
    assert!(
        matches!(&err, SceneError::Gltf(e) if matches!(&**e, GltfError::RequiredExtension { extension, .. } if extension == "KHR_draco_mesh_compression")),
        "{err}"
    );
    assert!(err.to_string().contains("requires the extension KHR_draco_mesh_compression"), "{err}");

    // An accessor beyond its buffer view, and a buffer shorter than declared.
    let path =
        edited(d, |j| j.replace(r#""count": 3, "type": "VEC3""#, r#""count": 4, "type": "VEC3""#));
    assert!(
        error_of(&path).to_string().contains("accessor 2: POSITION 4 elements end at byte 108"),
        "{}",
        error_of(&path)
    );
    std::fs::write(d.join("short.bin"), &buffer()[..90]).expect("writes");
    let path = edited(d, |j| j.replace("scene.bin", "short.bin"));
    assert!(
        error_of(&path)
            .to_string()
            .ends_with("buffer 0: holds 90 bytes, fewer than its byteLength 96"),
        "{}",
        error_of(&path)
    );

    // A node that is its own ancestor.
    let path = edited(d, |j| j.replace(r#""children": [4]}"#, r#""children": [4, 3]}"#));
    assert!(
        error_of(&path).to_string().contains("node `rig` (3): is reached twice"),
        "{}",
        error_of(&path)
    );

    // GLB headers that lie, and files that are not glTF: refused, never a panic.
    for (name, bytes) in [
        ("tiny.glb", b"glTF\x02\0\0\0\x04\0\0\0".to_vec()),
        ("long.glb", b"glTF\x02\0\0\0\xff\xff\0\0\x10\0\0\0JSON{}".to_vec()),
        ("text.glb", b"not json".to_vec()),
    ] {
        let path = d.join(name);
        std::fs::write(&path, bytes).expect("writes");
        let err = error_of(&path);
        assert!(
            matches!(&err, SceneError::Gltf(e) if matches!(**e, GltfError::Format { .. })),
            "{name}: {err}"
        );
    }
    // A camera whose type names a projection it lacks.
    let path = edited(d, |j| {
        j.replace(
            r#""perspective": {"yfov": 0.75, "znear": 0.125, "aspectRatio": 1.5}"#,
            r#""orthographic": {"xmag": 1, "ymag": 1, "zfar": 10, "znear": 0}"#,
        )
    });
    assert!(
        error_of(&path).to_string().contains("camera 0 is of type perspective but has no"),
        "{}",
        error_of(&path)
    );
    // An attribute naming an accessor that does not exist.
    let path = edited(d, |j| j.replace(r#""POSITION": 2"#, r#""POSITION": 7"#));
    assert!(
        error_of(&path).to_string().contains("refers to accessor 7, which does not exist"),
        "{}",
        error_of(&path)
    );
}

#[test]
fn a_scene_file_takes_a_gltf_file_as_an_object() {
    let dir = tempfile::tempdir().expect("tempdir");
    let [glb_path, ..] = gltf_forms(dir.path(), Lamp::Sun);
    let text = "[camera.perspective]\neye = [0.0, 6.0, 8.0]\ntarget = [0.0, 0.0, 0.0]\n\
                fov_y_deg = 45.0\n[light.directional]\ndirection = [0.0, -1.0, 0.0]\n\
                [[object]]\nname = \"both\"\nshape.file = { path = \"scene.glb\" }\n\
                transform = { translate = [0.0, 1.0, 0.0] }\n\
                material = { color = [0.1, 0.2, 0.3], opacity = 0.25 }\n";
    let path = dir.path().join("holder.toml");
    std::fs::write(&path, text).expect("writes");
    let described = registry::describe(path.to_str().expect("utf-8")).expect("described");
    assert!(described.triangles_exact());
    assert_eq!(described.triangles().ok(), Some(3));
    let scene = described.resolve().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.objects.len(), 1);
    let object = &scene.objects[0];
    assert_eq!(object.material.opacity, 0.25);
    // Both meshes, in world space, then the object's translation; the file's light and
    // camera are not the scene's.
    let whole = load(&glb_path).expect("loads");
    let mut expected = whole.objects[0].mesh.clone();
    expected.append(&whole.objects[1].mesh);
    expected.transform(&glam::DMat4::from_translation(glam::DVec3::Y));
    assert_eq!(object.mesh, expected);
    assert_eq!(scene.light, Light::Directional { direction: glam::DVec3::NEG_Y });
    // Its errors name the scene file, the object and the glTF file's cause.
    std::fs::remove_file(dir.path().join("scene.bin")).expect("removes");
    let text = text.replace("scene.glb", "scene.gltf");
    std::fs::write(&path, text).expect("writes");
    let err = load(&path).expect_err("no buffer");
    assert!(
        err.to_string()
            .starts_with(&format!("{}: line 9: `object[0].shape.file.path`: ", path.display())),
        "{err}"
    );
    assert!(err.to_string().contains(": buffer 0 needs the file "), "{err}");
}

#[test]
fn a_built_in_scene_file_works_from_any_folder_and_names_every_place_looked() {
    let dir = tempfile::tempdir().expect("tempdir");
    let desc = registry::builtin("bunny-plane").expect("built-in");
    let path = dir.path().join("elsewhere/bp.toml");
    std::fs::create_dir_all(path.parent().expect("parent")).expect("mkdir");
    std::fs::write(&path, desc.to_toml()).expect("writes");
    match registry::describe(path.to_str().expect("utf-8")).expect("parses").triangles() {
        // The models folder holds the bunny: found there from any folder.
        Ok(triangles) => assert!(triangles > 0),
        Err(err) => {
            let SceneError::ModelMissing { looked, fetch, .. } = &err else { panic!("{err}") };
            let want = [
                dir.path().join("elsewhere/bunny00.off"),
                scenes::models::models_dir().join("bunny00.off"),
            ];
            assert_eq!(looked.to_vec(), want.to_vec());
            assert!(*fetch);
            assert!(
                err.to_string().contains(&format!(
                    "needs bunny00.off, which is missing (looked for {} and {})",
                    want[0].display(),
                    want[1].display()
                )),
                "{err}"
            );
        }
    }
}

/// Whether `a` and `b` agree to the rounding of `f32`.
fn near(a: glam::DVec3, b: glam::DVec3) -> bool {
    (a - b).abs().max_element() <= 1e-6 * a.abs().max_element().max(1.0)
}

#[test]
fn an_exported_scene_reads_back_the_same() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (i, scene) in [
        load(&toml_scene(dir.path(), Lamp::Sun)).expect("loads"),
        load(&toml_scene(dir.path(), Lamp::Spot)).expect("loads"),
        registry::load("spot-spheres").expect("built-in"),
        registry::load("plane-square").expect("built-in"),
    ]
    .into_iter()
    .enumerate()
    {
        let path = dir.path().join(format!("out{i}.glb"));
        scenes::write_glb(&scene, &path).unwrap_or_else(|e| panic!("{e}"));
        let back = load(&path).unwrap_or_else(|e| panic!("{}: {e}", scene.name));
        let name = &scene.name;
        assert_eq!(back.objects.len(), scene.objects.len(), "{name}");
        for (a, b) in scene.objects.iter().zip(&back.objects) {
            assert_eq!(a.name, b.name, "{name}");
            // The same triangles, corner by corner (the reader keeps the vertices in their
            // order of first use, so their indices may differ).
            assert_eq!(a.mesh.triangle_count(), b.mesh.triangle_count(), "{name}");
            for t in 0..a.mesh.triangle_count() {
                let rounded = a.mesh.corners(t).map(|p| p.to_array().map(|c| f64::from(c as f32)));
                assert_eq!(b.mesh.corners(t).map(|p| p.to_array()), rounded, "{name}");
            }
            for k in 0..3 {
                assert_eq!(b.material.color[k], f64::from(a.material.color[k] as f32), "{name}");
            }
            assert_eq!(b.material.opacity, f64::from(a.material.opacity as f32), "{name}");
        }
        assert_eq!([back.width, back.height], [scene.width * 600 / scene.height, 600], "{name}");
        let (pa, pb) = (scene.camera.projector(64, 48), back.camera.projector(64, 48));
        for (u, v) in
            [(pa.origin, pb.origin), (pa.forward, pb.forward), (pa.up, pb.up), (pa.right, pb.right)]
        {
            assert!(near(u, v), "{name}: camera {u} vs {v}");
        }
        match (&scene.camera, &back.camera) {
            (
                Camera::Perspective { fov_y_deg: a, near: n, .. },
                Camera::Perspective { fov_y_deg: b, near: m, .. },
            ) => {
                assert!((a - b).abs() < 1e-5 && (n - m).abs() < 1e-6, "{name}");
            }
            _ => panic!("{name}: the camera's kind changed"),
        }
        let bounds = scene.bounds();
        let (la, lb) = (scene.light.projector(bounds, 64), back.light.projector(bounds, 64));
        assert!(near(la.forward, lb.forward), "{name}: light {} vs {}", la.forward, lb.forward);
        match (&scene.light, &back.light) {
            (Light::Directional { .. }, Light::Directional { .. }) => {}
            (
                Light::Spot { position: a, fov_deg: f, .. },
                Light::Spot { position: b, fov_deg: g, .. },
            ) => {
                assert!(near(*a, *b) && (f - g).abs() < 1e-4, "{name}");
            }
            _ => panic!("{name}: the light's kind changed"),
        }
    }
}

#[test]
fn what_a_scene_leaves_out_is_noted_and_the_first_camera_and_light_are_taken() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = edited(dir.path(), |j| {
        j.replace(r#""alphaMode": "BLEND""#, r#""alphaMode": "MASK", "alphaCutoff": 0.75"#)
            .replace(
                r#""baseColorFactor": [0.5, 0.5, 0.25, 1]"#,
                r#""baseColorFactor": [0.5, 0.5, 0.25, 1], "baseColorTexture": {"index": 0}"#,
            )
            .replace(
                r#""accessors""#,
                r#""textures": [{"source": 0}], "images": [{"uri": "tex.png"}], "accessors""#,
            )
            .replace(
                r#""extensionsUsed": ["KHR_lights_punctual"]"#,
                r#""extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"]"#,
            )
            .replace(
                r#""lights": [{"name":"sun-light","type":"directional"}]"#,
                r#""lights": [{"name":"sun-light","type":"directional"},
                             {"type":"spot","spot":{"outerConeAngle":0.25}}]"#,
            )
            .replace(
                r#""camera": 0, "translation": [0, 0, 10]"#,
                r#""camera": 0, "translation": [0, 0, 10],
                   "extensions": {"KHR_lights_punctual": {"light": 1}}"#,
            )
            .replace(r#"{"name":"sun","#, r#"{"name":"sun", "camera": 0,"#)
    });
    let described = registry::describe(path.to_str().expect("utf-8")).expect("described");
    assert_eq!(
        described.notes(),
        [
            "the extension KHR_materials_emissive_strength is not read",
            "material `grey` (0): its base colour texture is ignored; its factor is used",
            "node `sun` (5): its camera is ignored; the scene's is node `cam` (4)'s",
            "node `sun` (5): light `sun-light` (0) is ignored; the scene's is node `cam` (4)'s",
        ]
    );
    let scene = described.resolve().unwrap_or_else(|e| panic!("{e}"));
    // The camera's node holds the first light: a spot at the eye, aimed down its -Z.
    let eye = glam::DVec3::new(0.0, 2.0, 10.0);
    let spot =
        Light::Spot { position: eye, target: eye - glam::DVec3::Z, fov_deg: 0.5f64.to_degrees() };
    assert_eq!(scene.light, spot);
    // MASK: the constant alpha 0.5 is below the cutoff 0.75, so the triangle lets all light by.
    assert_eq!(scene.objects[1].material.opacity, 0.0);
    assert_eq!(scene.objects[0].material.color, [0.5, 0.5, 0.25]);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]

    /// A valid GLB with a few of its bytes changed is read or refused, never a panic.
    #[test]
    fn a_damaged_glb_is_read_or_refused_without_panic(
        flips in proptest::collection::vec((0usize..4096, proptest::prelude::any::<u8>()), 1..6)
    ) {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut bytes = glb(&json(Lamp::Spot, ""), &buffer());
        for (at, value) in flips {
            let n = bytes.len();
            bytes[at % n] = value;
        }
        let path = dir.path().join("damaged.glb");
        std::fs::write(&path, &bytes).expect("writes");
        if let Ok(described) = registry::describe(path.to_str().expect("utf-8")) {
            let _ = described.triangles();
            let _ = described.resolve();
        }
        let _ = scenes::io::load_mesh(&path);
    }

    /// The same with digits of the JSON changed into other digits: the JSON still parses, and
    /// counts, offsets, lengths, indices and transforms take other values.
    #[test]
    fn a_glb_with_other_numbers_is_read_or_refused_without_panic(
        flips in proptest::collection::vec((0usize..4096, b'0'..=b'9'), 1..4)
    ) {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut text = json(Lamp::Sun, "").into_bytes();
        let digits: Vec<usize> = (0..text.len()).filter(|&i| text[i].is_ascii_digit()).collect();
        for (at, digit) in flips {
            text[digits[at % digits.len()]] = digit;
        }
        let path = dir.path().join("numbers.glb");
        std::fs::write(&path, glb(&String::from_utf8_lossy(&text), &buffer())).expect("writes");
        if let Ok(described) = registry::describe(path.to_str().expect("utf-8")) {
            let _ = described.triangles();
            let _ = described.resolve();
        }
        let _ = scenes::io::load_mesh(&path);
    }
}
