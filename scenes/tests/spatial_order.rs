//! Mesh files are kept in a spatial triangle order wherever a scene reads them: a scene
//! file's mesh (the built-in bunny's) and a glTF scene's.

use glam::DVec3;
use scenes::{io::load_mesh, models::models_dir, registry, spatial_order::is_local, Mesh};

/// Every triangle as its corners' positions, in a canonical order of the triangles.
fn surface(mesh: &Mesh) -> Vec<[[u64; 3]; 3]> {
    let mut all: Vec<_> = (0..mesh.triangle_count())
        .map(|t| mesh.corners(t).map(|p| p.to_array().map(f64::to_bits)))
        .collect();
    all.sort_unstable();
    all
}

#[test]
fn the_bunny_file_is_read_into_a_local_order() {
    let path = models_dir().join("bunny00.off");
    if !path.exists() {
        eprintln!("skipped: {} is missing; run `scripts/fetch-models` to fetch it", path.display());
        return;
    }
    let raw = load_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(!is_local(&raw), "the file's own order scatters its triangles");
    let scene = registry::load("bunny-plane").unwrap_or_else(|e| panic!("{e}"));
    let bunny = scene.objects.iter().find(|o| o.name == "bunny").expect("the bunny");
    assert!(is_local(&bunny.mesh));
    assert_eq!(bunny.mesh.triangle_count(), raw.triangle_count());
    assert_eq!(bunny.mesh.positions.len(), raw.positions.len());
}

/// A `k x k` grid of unit quads in the plane `y = 0`, two triangles each, its triangles
/// taken with a stride that scatters them.
fn scattered_grid(k: u32) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=k {
        for i in 0..=k {
            positions.push(DVec3::new(f64::from(i), 0.0, f64::from(j)));
        }
    }
    let at = |i: u32, j: u32| j * (k + 1) + i;
    let mut triangles = Vec::new();
    for j in 0..k {
        for i in 0..k {
            triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
        }
    }
    let n = triangles.len();
    // A prime above the count: coprime with it, so every triangle is taken once.
    let stride = 7919;
    assert!(n < stride);
    let scattered = (0..n).map(|t| triangles[(t * stride) % n]).collect();
    Mesh::new(positions, scattered).expect("valid grid")
}

#[test]
fn a_scattered_mesh_in_a_gltf_scene_is_read_into_a_local_order() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut scene = registry::load("plane-square").unwrap_or_else(|e| panic!("{e}"));
    let grid = scattered_grid(40);
    assert!(!is_local(&grid));
    scene.objects[0].mesh = grid.clone();
    let path = dir.path().join("grid.glb");
    scenes::write_glb(&scene, &path).unwrap_or_else(|e| panic!("{e}"));
    let back = registry::describe(path.to_str().expect("utf-8"))
        .and_then(|d| d.resolve())
        .unwrap_or_else(|e| panic!("{e}"));
    let mesh = &back.objects[0].mesh;
    assert!(is_local(mesh));
    // The same surface: the grid's coordinates are whole numbers, exact in `f32`.
    assert_eq!(surface(mesh), surface(&grid));
    // Written and read again, it keeps its order.
    scene.objects[0].mesh = mesh.clone();
    scenes::write_glb(&scene, &path).unwrap_or_else(|e| panic!("{e}"));
    let again = registry::describe(path.to_str().expect("utf-8"))
        .and_then(|d| d.resolve())
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(again.objects[0].mesh.triangles, mesh.triangles);
}
