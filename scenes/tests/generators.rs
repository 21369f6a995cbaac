//! The procedural generators: documented counts, determinism, constant area, watertight and
//! outward closed parts, validation naming the key, serde defaults, and no panics on random
//! parameters.

use proptest::prelude::*;
use scenes::generators::{
    CageParams, CityParams, Generator, HairballParams, HeightfieldParams, PlaneParams, PlantParams,
    RandomTrianglesParams, SpheresParams,
};
use scenes::Mesh;
use std::collections::BTreeMap;

/// Every generator at its defaults, with its name.
fn defaults() -> Vec<(&'static str, Box<dyn Generator>)> {
    vec![
        ("plane", Box::new(PlaneParams::default())),
        ("random_triangles", Box::new(RandomTrianglesParams::default())),
        ("cage", Box::new(CageParams::default())),
        ("spheres", Box::new(SpheresParams::default())),
        ("city", Box::new(CityParams::default())),
        ("plant", Box::new(PlantParams::default())),
        ("heightfield", Box::new(HeightfieldParams::default())),
        ("hairball", Box::new(HairballParams::default())),
    ]
}

fn bit_identical(a: &Mesh, b: &Mesh) -> bool {
    a.triangles == b.triangles
        && a.positions.len() == b.positions.len()
        && a.positions
            .iter()
            .zip(&b.positions)
            .all(|(p, q)| p.to_array().map(f64::to_bits) == q.to_array().map(f64::to_bits))
}

/// Connected components of the triangles (through shared vertex indices), as triangle lists in
/// order of first appearance.
fn components(mesh: &Mesh) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..mesh.positions.len()).collect();
    fn find(parent: &mut [usize], mut v: usize) -> usize {
        while parent[v] != v {
            parent[v] = parent[parent[v]];
            v = parent[v];
        }
        v
    }
    for t in &mesh.triangles {
        let root = find(&mut parent, t[0] as usize);
        for &v in &t[1..] {
            let other = find(&mut parent, v as usize);
            parent[other] = root;
        }
    }
    let mut groups: BTreeMap<usize, usize> = BTreeMap::new();
    let mut out: Vec<Vec<usize>> = Vec::new();
    for (i, t) in mesh.triangles.iter().enumerate() {
        let root = find(&mut parent, t[0] as usize);
        let g = *groups.entry(root).or_insert_with(|| {
            out.push(Vec::new());
            out.len() - 1
        });
        out[g].push(i);
    }
    out
}

/// Every undirected edge of `triangles` is used by exactly two of them, in opposite directions.
fn is_watertight(mesh: &Mesh, triangles: &[usize]) -> bool {
    let mut edges: BTreeMap<(u32, u32), (u32, u32)> = BTreeMap::new();
    for &t in triangles {
        let tri = mesh.triangles[t];
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if a == b {
                return false;
            }
            let e = edges.entry((a.min(b), a.max(b))).or_default();
            if a < b {
                e.0 += 1;
            } else {
                e.1 += 1;
            }
        }
    }
    edges.values().all(|&uses| uses == (1, 1))
}

fn signed_volume(mesh: &Mesh, triangles: &[usize]) -> f64 {
    triangles
        .iter()
        .map(|&t| {
            let [a, b, c] = mesh.corners(t);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Every component of `mesh` (or of its first `closed` triangles) is watertight and encloses a
/// positive volume.
fn assert_closed_outward(name: &str, mesh: &Mesh, closed: usize) {
    let part =
        Mesh { positions: mesh.positions.clone(), triangles: mesh.triangles[..closed].to_vec() };
    let parts = components(&part);
    assert!(!parts.is_empty(), "{name}");
    for (i, c) in parts.iter().enumerate() {
        assert!(is_watertight(&part, c), "{name}: component {i} is not watertight");
        assert!(signed_volume(&part, c) > 0.0, "{name}: component {i} faces in");
    }
}

#[test]
fn defaults_build_the_documented_triangle_counts() {
    let expected = [
        ("plane", 2),
        ("random_triangles", 1_000),
        ("cage", 1_584),
        ("spheres", 10_240),
        ("city", 768),
        ("plant", 1_960),
        ("heightfield", 131_072),
        ("hairball", 72_000),
    ];
    for ((name, g), (expected_name, count)) in defaults().into_iter().zip(expected) {
        assert_eq!(name, expected_name);
        g.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        let mesh = g.generate();
        mesh.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.triangle_count(), count, "{name}");
    }
}

#[test]
fn counts_follow_the_parameters() {
    for s in [1, 2, 5, 13] {
        let plane = PlaneParams { subdivisions: s, ..Default::default() }.generate();
        assert_eq!(plane.triangle_count(), 2 * (s * s) as usize);
        let city = CityParams { blocks: s, ..Default::default() }.generate();
        assert_eq!(city.triangle_count(), 12 * (s * s) as usize);
        let field = HeightfieldParams { resolution: s, ..Default::default() }.generate();
        assert_eq!(field.triangle_count(), 2 * (s * s) as usize);
    }
    for count in [1, 7, 1234] {
        let tris = RandomTrianglesParams { count, ..Default::default() }.generate();
        assert_eq!(tris.triangle_count(), count as usize);
    }
    let cage = CageParams { bars_per_side: 5, ..Default::default() };
    assert_eq!(cage.generate().triangle_count(), 12 * 12 * 4);
    let spheres = SpheresParams { count: 3, subdivisions: 2, ..Default::default() };
    assert_eq!(spheres.generate().triangle_count(), 3 * 320);
    let plant = PlantParams { leaves: 10, stems: 2, ..Default::default() };
    assert_eq!(plant.generate().triangle_count(), 2 * 72 + 10 * 4);
    let hair = HairballParams { strands: 7, segments: 96, sides: 3, ..Default::default() };
    assert_eq!(hair.generate().triangle_count(), 7 * 576, "Aila & Laine's 576 triangles a hair");
}

#[test]
fn random_triangles_keep_their_total_area() {
    for count in [1_000, 10_000, 100_000, 1_000_000] {
        let mesh = RandomTrianglesParams { count, ..Default::default() }.generate();
        assert_eq!(mesh.triangle_count(), count as usize);
        let area = mesh.area();
        assert!((area - 40.0).abs() <= 1e-9 * 40.0, "{count}: {area}");
    }
    let mesh =
        RandomTrianglesParams { count: 500, total_area: 3.5, ..Default::default() }.generate();
    assert!((mesh.area() - 3.5).abs() <= 1e-9 * 3.5);
}

#[test]
fn same_seed_same_mesh_other_seed_other_mesh() {
    type Pair = (&'static str, Box<dyn Generator>, Box<dyn Generator>);
    let pairs: Vec<Pair> = vec![
        (
            "random_triangles",
            Box::new(RandomTrianglesParams { count: 200, seed: 11, ..Default::default() }),
            Box::new(RandomTrianglesParams { count: 200, seed: 12, ..Default::default() }),
        ),
        (
            "spheres",
            Box::new(SpheresParams { subdivisions: 1, seed: 11, ..Default::default() }),
            Box::new(SpheresParams { subdivisions: 1, seed: 12, ..Default::default() }),
        ),
        (
            "city",
            Box::new(CityParams { seed: 11, ..Default::default() }),
            Box::new(CityParams { seed: 12, ..Default::default() }),
        ),
        (
            "plant",
            Box::new(PlantParams { leaves: 50, seed: 11, ..Default::default() }),
            Box::new(PlantParams { leaves: 50, seed: 12, ..Default::default() }),
        ),
        (
            "heightfield",
            Box::new(HeightfieldParams { resolution: 20, seed: 11, ..Default::default() }),
            Box::new(HeightfieldParams { resolution: 20, seed: 12, ..Default::default() }),
        ),
        (
            "hairball",
            Box::new(HairballParams { strands: 20, seed: 11, ..Default::default() }),
            Box::new(HairballParams { strands: 20, seed: 12, ..Default::default() }),
        ),
    ];
    for (name, a, b) in pairs {
        let first = a.generate();
        assert!(bit_identical(&first, &a.generate()), "{name}: not deterministic");
        let other = b.generate();
        assert_eq!(first.triangles.len(), other.triangles.len(), "{name}");
        assert_ne!(first.positions, other.positions, "{name}: the seed changes nothing");
    }
    // The deterministic generators also repeat themselves.
    for (name, g) in defaults() {
        assert!(bit_identical(&g.generate(), &g.generate()), "{name}");
    }
}

#[test]
fn meshes_are_pinned_across_platforms() {
    // An FNV-1a hash over the bits of every coordinate and index at the defaults. SplitMix64,
    // the portable sin_cos and plain IEEE arithmetic make these the same on every platform and
    // at every optimisation level; a change here changes every scene built from a seed, so
    // update the values only on purpose.
    fn checksum(mesh: &Mesh) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |word: u64| h = (h ^ word).wrapping_mul(0x0000_0100_0000_01b3);
        for p in &mesh.positions {
            for c in p.to_array() {
                eat(c.to_bits());
            }
        }
        for t in &mesh.triangles {
            for &v in t {
                eat(u64::from(v));
            }
        }
        h
    }
    let pinned = [
        ("plane", 0x1fe4_dc43_ca7f_407c),
        ("random_triangles", 0xec9d_66ae_3291_d7a8),
        ("cage", 0x4a00_217a_cf5c_6e5d),
        ("spheres", 0x1d36_3f88_e8be_4f7a),
        ("city", 0x8c2e_763b_4fac_c0d5),
        ("plant", 0x4293_0e8c_7d41_642a),
        ("heightfield", 0x101d_8a23_4b16_6833),
        ("hairball", 0xfb23_92d8_894c_1ad0),
    ];
    for ((name, g), (pinned_name, sum)) in defaults().into_iter().zip(pinned) {
        assert_eq!(name, pinned_name);
        let got = checksum(&g.generate());
        assert_eq!(got, sum, "{name}: {got:#018x}");
    }
}

#[test]
fn closed_parts_are_watertight_and_face_out() {
    let cage = CageParams { bars_per_side: 4, ..Default::default() }.generate();
    assert_closed_outward("cage", &cage, cage.triangle_count());
    assert_eq!(components(&cage).len(), 36, "one component per bar");
    let spheres = SpheresParams { subdivisions: 2, ..Default::default() }.generate();
    assert_closed_outward("spheres", &spheres, spheres.triangle_count());
    assert_eq!(components(&spheres).len(), 8);
    let city = CityParams::default().generate();
    assert_closed_outward("city", &city, city.triangle_count());
    assert_eq!(components(&city).len(), 64);
    let plant = PlantParams::default().generate();
    assert_closed_outward("plant stems", &plant, 5 * 72);
    let ico = SpheresParams { count: 1, subdivisions: 0, ..Default::default() }.generate();
    assert_closed_outward("icosahedron", &ico, 20);
}

#[test]
fn casters_stand_on_or_above_the_ground_within_the_footprint() {
    for (name, g) in defaults() {
        let mesh = g.generate();
        assert!(mesh.positions.iter().all(|p| p.is_finite()), "{name}");
        let (lo, hi) = mesh.bounds().expect("vertices");
        match name {
            "plane" | "heightfield" => {
                assert!(lo.y.abs() <= 0.15 && hi.y.abs() <= 0.15, "{name}");
                assert_eq!((lo.x, lo.z, hi.x, hi.z), (-10.0, -10.0, 10.0, 10.0), "{name}");
            }
            _ => {
                assert!(lo.y >= 0.0, "{name} goes below the ground: {lo}");
                assert!(
                    lo.x >= -5.0 && lo.z >= -5.0 && hi.x <= 5.0 && hi.z <= 5.0,
                    "{name}: {lo} {hi}"
                );
                let middle = 0.5 * (lo + hi);
                assert!(
                    middle.x.abs() < 2.0 && middle.z.abs() < 2.0,
                    "{name} is off-centre: {middle}"
                );
            }
        }
    }
}

#[test]
fn receivers_face_up() {
    let plane = PlaneParams { subdivisions: 3, ..Default::default() }.generate();
    let field =
        HeightfieldParams { resolution: 30, amplitude: 0.5, wavelength: 0.5, ..Default::default() }
            .generate();
    for mesh in [plane, field] {
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.corners(t);
            assert!((b - a).cross(c - a).y > 0.0);
        }
    }
}

#[test]
fn validation_errors_name_the_field() {
    let cases: Vec<(Box<dyn Generator>, &str)> = vec![
        (Box::new(PlaneParams { size: -1.0, ..Default::default() }), "size"),
        (Box::new(PlaneParams { subdivisions: 0, ..Default::default() }), "subdivisions"),
        (Box::new(RandomTrianglesParams { count: 0, ..Default::default() }), "count"),
        (Box::new(RandomTrianglesParams { count: 30_000_000, ..Default::default() }), "count"),
        (
            Box::new(RandomTrianglesParams { total_area: f64::NAN, ..Default::default() }),
            "total_area",
        ),
        (
            Box::new(RandomTrianglesParams { extent: [0.0, 1.0, 1.0], ..Default::default() }),
            "extent",
        ),
        (Box::new(CageParams { bar_width: 1.0, ..Default::default() }), "bar_width"),
        (Box::new(CageParams { bars_per_side: 0, ..Default::default() }), "bars_per_side"),
        (Box::new(SpheresParams { count: 0, ..Default::default() }), "count"),
        (Box::new(SpheresParams { max_radius: 0.1, ..Default::default() }), "max_radius"),
        (Box::new(SpheresParams { subdivisions: 40, ..Default::default() }), "subdivisions"),
        (Box::new(CityParams { blocks: 0, ..Default::default() }), "blocks"),
        (Box::new(CityParams { max_height: f64::INFINITY, ..Default::default() }), "max_height"),
        (Box::new(PlantParams { leaves: 0, ..Default::default() }), "leaves"),
        (Box::new(PlantParams { leaf_width: 0.0, ..Default::default() }), "leaf_width"),
        (Box::new(HeightfieldParams { resolution: 0, ..Default::default() }), "resolution"),
        (Box::new(HeightfieldParams { wavelength: -1.0, ..Default::default() }), "wavelength"),
        (Box::new(HairballParams { strands: 0, ..Default::default() }), "strands"),
        (Box::new(HairballParams { thickness: f64::NAN, ..Default::default() }), "thickness"),
        (Box::new(HairballParams { center_height: 0.5, ..Default::default() }), "center_height"),
    ];
    for (g, key) in cases {
        let err = g.validate().expect_err(key);
        assert_eq!(err.key, key, "{err}");
        assert!(err.to_string().contains(key), "{err}");
        assert!(g.generate().triangles.is_empty(), "{key}: invalid params build nothing");
    }
}

#[test]
fn parameters_default_every_missing_key_and_reject_unknown_ones() {
    let plane: PlaneParams = toml::from_str("size = 3.0").expect("valid");
    assert_eq!(plane, PlaneParams { size: 3.0, ..Default::default() });
    let hair: HairballParams = toml::from_str("").expect("valid");
    assert_eq!(hair, HairballParams::default());
    let tris: RandomTrianglesParams =
        toml::from_str("extent = [1.0, 2.0, 3.0]\nseed = 5").expect("valid");
    assert_eq!(tris.extent, [1.0, 2.0, 3.0]);
    assert_eq!(tris.seed, 5);
    let err = toml::from_str::<CageParams>("bars = 3").expect_err("unknown key").to_string();
    assert!(err.contains("bars"), "{err}");
    let err = toml::from_str::<SpheresParams>("radius = 3.0").expect_err("unknown key").to_string();
    assert!(err.contains("radius"), "{err}");
    // Round trip.
    let city = CityParams { blocks: 3, street_width: 0.25, ..Default::default() };
    let text = toml::to_string(&city).expect("serialisable");
    assert_eq!(toml::from_str::<CityParams>(&text).expect("round trip"), city);
}

/// Builds `g` and checks what every mesh must satisfy.
fn check_valid_build(g: &dyn Generator) -> Result<(), TestCaseError> {
    prop_assert!(g.validate().is_ok(), "{:?}", g.validate());
    let mesh = g.generate();
    prop_assert!(!mesh.triangles.is_empty());
    prop_assert!(mesh.positions.iter().all(|p| p.is_finite()));
    let n = mesh.positions.len() as u32;
    prop_assert!(mesh.triangles.iter().flatten().all(|&v| v < n));
    prop_assert!(mesh.validate().is_ok());
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn valid_small_params_build_sound_meshes(
        seed in any::<u64>(),
        n in 1u32..6,
        a in 0.1f64..10.0,
        b in 0.1f64..5.0,
        c in 0.01f64..3.0,
        f in 0.0f64..1.0,
    ) {
        check_valid_build(&PlaneParams { size: a, subdivisions: n })?;
        check_valid_build(&RandomTrianglesParams {
            count: n * 7, total_area: a, extent: [b, c, a], min_height: c, seed,
        })?;
        let cage = CageParams {
            size: [a, b, c],
            bars_per_side: n + 1,
            bar_width: (0.05 + 0.9 * f) * a.min(b).min(c) / f64::from(n + 1),
            height_above_ground: c,
        };
        check_valid_build(&cage)?;
        let mesh = cage.generate();
        let all: Vec<usize> = (0..mesh.triangle_count()).collect();
        prop_assert!(is_watertight(&mesh, &all));
        check_valid_build(&SpheresParams {
            count: n,
            min_radius: 0.05 + 0.5 * f,
            max_radius: 0.6 + b / 5.0,
            subdivisions: n % 3,
            min_height: c,
            max_height: c + a,
            seed,
        })?;
        check_valid_build(&CityParams {
            blocks: n,
            min_height: c,
            max_height: c + b,
            street_width: f * 10.0 / f64::from(n) * 0.99,
            seed,
        })?;
        check_valid_build(&PlantParams {
            leaves: n * 3,
            leaf_length: b,
            leaf_width: c,
            height: a,
            stems: n,
            stem_width: a * (0.01 + 0.5 * f),
            seed,
        })?;
        check_valid_build(&HeightfieldParams {
            size: a, resolution: n * 3, amplitude: c * f, wavelength: b, waves: n, seed,
        })?;
        check_valid_build(&HairballParams {
            strands: n * 2,
            segments: n + 1,
            sides: 2 + n % 4,
            radius: b,
            center_height: b + c + a * f,
            length: c,
            thickness: c * 0.1,
            seed,
        })?;
    }

    #[test]
    fn arbitrary_params_never_panic(
        x in prop_oneof![any::<f64>(), -5.0f64..20.0, Just(f64::NAN), Just(0.0)],
        y in prop_oneof![any::<f64>(), 0.0f64..5.0, Just(f64::INFINITY)],
        // Small counts, or counts that fail validation (more than 20 M triangles).
        n in prop_oneof![0u32..8, 20_000_001u32..=u32::MAX],
        seed in any::<u64>(),
    ) {
        let gens: Vec<Box<dyn Generator>> = vec![
            Box::new(PlaneParams { size: x, subdivisions: n }),
            Box::new(RandomTrianglesParams { count: n, total_area: x, extent: [y, x, y], min_height: y, seed }),
            Box::new(CageParams { size: [x, y, x], bars_per_side: n, bar_width: y, height_above_ground: x }),
            Box::new(SpheresParams { count: n, min_radius: y, max_radius: x, subdivisions: if n < 8 { n % 3 } else { n }, min_height: y, max_height: x, seed }),
            Box::new(CityParams { blocks: n, min_height: y, max_height: x, street_width: y, seed }),
            Box::new(PlantParams { leaves: n, leaf_length: x, leaf_width: y, height: x, stems: n, stem_width: y, seed }),
            Box::new(HeightfieldParams { size: x, resolution: n, amplitude: y, wavelength: x, waves: n, seed }),
            Box::new(HairballParams { strands: n, segments: n, sides: n, radius: y, center_height: x, length: y, thickness: y, seed }),
        ];
        for g in gens {
            let valid = g.validate().is_ok();
            let mesh = g.generate();
            prop_assert!(mesh.positions.iter().all(|p| p.is_finite()));
            let count = mesh.positions.len() as u32;
            prop_assert!(mesh.triangles.iter().flatten().all(|&v| v < count));
            prop_assert_eq!(valid, !mesh.triangles.is_empty());
        }
    }
}
