//! A cache of references on disk, shared by the shards of a report (`report --cache DIR`).
//!
//! References are the dearest part of a sweep and every run of a scene shares its own, so a
//! shard takes a scene's reference from the cache when another shard (or an earlier report)
//! computed it. Entries are content-addressed: the file name is the SHA-256 ([`key`]) of
//! everything the reference depends on:
//!
//! - the workbench's version and its build ([`build_id`]: the commit of a clean checkout, or
//!   the SHA-256 of the running executable when the checkout has uncommitted changes, so that
//!   an edited, rebuilt workbench never reads a reference an earlier build computed);
//! - the frame's size;
//! - the reference's name and rate;
//! - the scene's camera, light and effect switches (their `Debug` text, which prints every
//!   field, `f64`s in their shortest exact form);
//! - every object's name, material, whether it casts shadows, and its mesh (vertex coordinates
//!   as `f64` bytes, triangle indices as `u32` bytes).
//!
//! An entry, `KEY.ref`, is a JSON header line ([`Header`]: the key, the frame, the reference,
//! its time, and the SHA-256 and length of the payload), then the payload: the lit fraction as
//! little-endian `f64`, the evaluated flags as bytes, the pixel classes' codes as bytes when
//! the reference has classes, and the transmittance as three little-endian `f64` per pixel
//! when it has one. Reading verifies the header's key, frame and reference, the payload's
//! length and its SHA-256; an entry that fails is counted as invalid, recomputed and replaced.
//! Writing goes to a temporary file in the same folder, then renames it over the entry, so two
//! shards writing the same entry at once leave one whole file, and a reader never sees half a
//! file. The format is our own because it is a flat dump of `f64`s that must come back bit for
//! bit; SHA-256 is the `sha2` crate's.

use analysis::pixel_class::PixelClass;
use analysis::ReferenceImage;
use methods::Frame;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// The format named in every entry's header.
pub const FORMAT: &str = "shadowbench reference cache 1";

/// What a cache entry's header line holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// [`FORMAT`].
    pub format: String,
    /// The entry's key (its file stem).
    pub key: String,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// The reference's name.
    pub reference: String,
    /// Its rate (`raytrace`).
    pub ref_rate: Option<u32>,
    /// The reference's time when it was computed, milliseconds.
    pub reference_ms: f64,
    /// Whether the payload holds pixel classes.
    pub classes: bool,
    /// Whether the payload holds a transmittance.
    pub transmittance: bool,
    /// The payload's length in bytes.
    pub payload_bytes: u64,
    /// The payload's SHA-256, in hex.
    pub payload_sha256: String,
}

/// What one cache did during a report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CacheStats {
    /// References read from the cache.
    pub hits: u64,
    /// References computed because the cache had none.
    pub misses: u64,
    /// Entries that failed verification, recomputed and replaced.
    pub invalid: u64,
    /// Entries that could not be written (the reference was used all the same).
    pub write_failures: u64,
}

/// The sum of two counts (the shards of a merged report).
impl std::ops::Add for CacheStats {
    type Output = Self;

    fn add(self, o: Self) -> Self {
        Self {
            hits: self.hits + o.hits,
            misses: self.misses + o.misses,
            invalid: self.invalid + o.invalid,
            write_failures: self.write_failures + o.write_failures,
        }
    }
}

/// A cache folder.
#[derive(Debug)]
pub struct ReferenceCache {
    dir: PathBuf,
    /// What it did so far.
    pub stats: CacheStats,
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// What identifies the code that computes references: `commit` when the checkout it was built
/// from is clean (`dirty` false and the commit known), else the SHA-256 of the running
/// executable (or, when that cannot be read, this process's id and start time, which no other
/// run shares).
pub fn build_id(commit: &str, dirty: bool) -> String {
    if !dirty && commit != "unknown" {
        return format!("commit {commit}");
    }
    let exe = std::env::current_exe().and_then(std::fs::read);
    match exe {
        Ok(bytes) => format!("executable {}", hex(&Sha256::digest(&bytes))),
        Err(_) => {
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos());
            format!("process {} {nanos}", std::process::id())
        }
    }
}

/// The key of the reference `name` at `rate` on `frame` of `scene`, computed by the code
/// `build` ([`build_id`]; see the module documentation for what goes into it).
pub fn key(
    scene: &scenes::Scene,
    width: u32,
    height: u32,
    name: &str,
    rate: Option<u32>,
    build: &str,
) -> String {
    let mut h = Sha256::new();
    // Each text with its length first, so that no two sequences of texts hash alike.
    let text = |h: &mut Sha256, s: &str| {
        h.update((s.len() as u64).to_le_bytes());
        h.update(s.as_bytes());
    };
    text(&mut h, FORMAT);
    text(&mut h, env!("CARGO_PKG_VERSION"));
    text(&mut h, build);
    text(&mut h, &format!("{width}x{height} {name} {rate:?}"));
    text(&mut h, &format!("{:?}", scene.camera));
    text(&mut h, &format!("{:?}", scene.light));
    text(&mut h, &format!("{:?}", scene.switches));
    for o in &scene.objects {
        text(&mut h, &format!("{:?} {:?} {}", o.name, o.material, o.casts_shadows));
        h.update((o.mesh.positions.len() as u64).to_le_bytes());
        for p in &o.mesh.positions {
            for c in p.to_array() {
                h.update(c.to_le_bytes());
            }
        }
        h.update((o.mesh.triangles.len() as u64).to_le_bytes());
        for t in &o.mesh.triangles {
            for i in t {
                h.update(i.to_le_bytes());
            }
        }
    }
    hex(&h.finalize())
}

fn payload(r: &ReferenceImage) -> Vec<u8> {
    let n = r.lit.len();
    let mut out = Vec::with_capacity(n * 10);
    for v in &r.lit {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend(r.evaluated.iter().map(|&e| u8::from(e)));
    if let Some(c) = &r.classes {
        out.extend(c.iter().map(|c| c.code()));
    }
    if let Some(t) = &r.transmittance {
        for px in t {
            for v in px {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    out
}

/// Reads an `f64` at `at` (the caller has checked the length).
fn f64_at(bytes: &[u8], at: usize) -> f64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&bytes[at..at + 8]);
    f64::from_le_bytes(b)
}

impl ReferenceCache {
    /// The cache in `dir`, created when missing.
    pub fn open(dir: &Path) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        Ok(Self { dir: dir.to_owned(), stats: CacheStats::default() })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn path(&self, key: &str) -> PathBuf {
        self.dir.join(format!("{key}.ref"))
    }

    /// The entry `key`, verified against the expected frame and reference, with the time it
    /// took to compute; `None` when there is none or it fails verification (counted).
    fn read(
        &mut self,
        key: &str,
        expect: (&str, Option<u32>, u32, u32),
    ) -> Option<(ReferenceImage, f64)> {
        let bytes = std::fs::read(self.path(key)).ok()?;
        match decode(&bytes, key, expect) {
            Some(r) => Some(r),
            None => {
                self.stats.invalid += 1;
                None
            }
        }
    }

    /// Writes the entry `key` (to a temporary file, then renamed over the entry).
    fn write(&self, key: &str, header: &Header, payload: &[u8]) -> std::io::Result<()> {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let tmp = self.dir.join(format!(".{key}.{}.{nanos}.tmp", std::process::id()));
        let mut line = serde_json::to_string(header).map_err(std::io::Error::other)?;
        line.push('\n');
        let result = (|| {
            let mut f = std::fs::File::create(&tmp)?;
            f.write_all(line.as_bytes())?;
            f.write_all(payload)?;
            f.sync_all()?;
            std::fs::rename(&tmp, self.path(key))
        })();
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result
    }

    /// The reference `name` at `rate` on `frame` of `scene` computed by the code `build`
    /// ([`build_id`]), from the cache or from `compute` (which returns it with its time in
    /// milliseconds), stored when computed.
    pub fn get_or_compute<E>(
        &mut self,
        scene: &scenes::Scene,
        frame: &Frame<'_>,
        name: &str,
        rate: Option<u32>,
        build: &str,
        compute: impl FnOnce() -> Result<(ReferenceImage, f64), E>,
    ) -> Result<(ReferenceImage, f64), E> {
        let (w, h) = (frame.width(), frame.height());
        let key = key(scene, w, h, name, rate, build);
        if let Some(hit) = self.read(&key, (name, rate, w, h)) {
            self.stats.hits += 1;
            return Ok(hit);
        }
        self.stats.misses += 1;
        let (image, ms) = compute()?;
        let payload = payload(&image);
        let header = Header {
            format: FORMAT.to_owned(),
            key: key.clone(),
            width: w,
            height: h,
            reference: name.to_owned(),
            ref_rate: rate,
            reference_ms: ms,
            classes: image.classes.is_some(),
            transmittance: image.transmittance.is_some(),
            payload_bytes: payload.len() as u64,
            payload_sha256: hex(&Sha256::digest(&payload)),
        };
        if self.write(&key, &header, &payload).is_err() {
            self.stats.write_failures += 1;
        }
        Ok((image, ms))
    }
}

/// The reference in an entry's bytes, when they verify (see the module documentation).
fn decode(
    bytes: &[u8],
    key: &str,
    (name, rate, w, h): (&str, Option<u32>, u32, u32),
) -> Option<(ReferenceImage, f64)> {
    let newline = bytes.iter().position(|&b| b == b'\n')?;
    let header: Header = serde_json::from_slice(&bytes[..newline]).ok()?;
    let body = &bytes[newline + 1..];
    let fits = header.format == FORMAT
        && header.key == key
        && (header.width, header.height) == (w, h)
        && header.reference == name
        && header.ref_rate == rate
        && header.payload_bytes == body.len() as u64
        && header.payload_sha256 == hex(&Sha256::digest(body));
    let n = w as usize * h as usize;
    let expected =
        n * 9 + if header.classes { n } else { 0 } + if header.transmittance { n * 24 } else { 0 };
    if !fits || body.len() != expected {
        return None;
    }
    let lit = (0..n).map(|k| f64_at(body, 8 * k)).collect();
    let evaluated = body[8 * n..9 * n].iter().map(|&b| b != 0).collect();
    let mut at = 9 * n;
    let classes = if header.classes {
        let c: Option<Vec<PixelClass>> =
            body[at..at + n].iter().map(|&b| PixelClass::ALL.get(b as usize).copied()).collect();
        at += n;
        Some(c?)
    } else {
        None
    };
    let transmittance = header
        .transmittance
        .then(|| (0..n).map(|k| [0, 1, 2].map(|c| f64_at(body, at + 24 * k + 8 * c))).collect());
    let image = ReferenceImage { width: w, height: h, lit, evaluated, transmittance, classes };
    Some((image, header.reference_ms))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference(n: usize, classes: bool, transmittance: bool) -> ReferenceImage {
        ReferenceImage {
            width: n as u32,
            height: 1,
            lit: (0..n).map(|k| k as f64 / 3.0).collect(),
            evaluated: (0..n).map(|k| k % 2 == 0).collect(),
            transmittance: transmittance.then(|| (0..n).map(|k| [k as f64, 0.5, 1e-300]).collect()),
            classes: classes.then(|| (0..n).map(|k| PixelClass::ALL[k % 4]).collect()),
        }
    }

    #[test]
    fn an_entry_comes_back_bit_for_bit_and_a_damaged_one_is_refused() {
        let dir = tempfile::tempdir().expect("tempdir");
        let cache = ReferenceCache::open(dir.path()).expect("cache");
        for (classes, transmittance) in [(false, false), (true, false), (false, true), (true, true)]
        {
            let r = reference(7, classes, transmittance);
            let key = format!("k{}{}", u8::from(classes), u8::from(transmittance));
            let p = payload(&r);
            let header = Header {
                format: FORMAT.into(),
                key: key.clone(),
                width: 7,
                height: 1,
                reference: "exact".into(),
                ref_rate: None,
                reference_ms: 12.5,
                classes,
                transmittance,
                payload_bytes: p.len() as u64,
                payload_sha256: hex(&Sha256::digest(&p)),
            };
            cache.write(&key, &header, &p).expect("writes");
            let bytes = std::fs::read(cache.path(&key)).expect("entry");
            let (back, ms) = decode(&bytes, &key, ("exact", None, 7, 1)).expect("verifies");
            assert_eq!((back, ms), (r, 12.5));
            // Another frame, reference or key, a flipped payload bit, a cut file: refused.
            assert!(decode(&bytes, &key, ("exact", None, 7, 2)).is_none());
            assert!(decode(&bytes, &key, ("raytrace", Some(64), 7, 1)).is_none());
            assert!(decode(&bytes, "other", ("exact", None, 7, 1)).is_none());
            let mut flipped = bytes.clone();
            let last = flipped.len() - 1;
            flipped[last] ^= 1;
            assert!(decode(&flipped, &key, ("exact", None, 7, 1)).is_none());
            assert!(decode(&bytes[..bytes.len() - 3], &key, ("exact", None, 7, 1)).is_none());
        }
        // No temporary file is left behind.
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .expect("dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }

    #[test]
    fn the_key_changes_with_what_the_reference_depends_on() {
        let scene = scenes::load("plane-square").expect("scene");
        let k = key(&scene, 64, 48, "exact", None, "abc");
        assert_eq!(k.len(), 64);
        assert_eq!(k, key(&scene, 64, 48, "exact", None, "abc"), "deterministic");
        assert_ne!(k, key(&scene, 64, 49, "exact", None, "abc"));
        assert_ne!(k, key(&scene, 64, 48, "raytrace", Some(64), "abc"));
        assert_ne!(k, key(&scene, 64, 48, "exact", None, "abd"));
        // A clean checkout is named by its commit; an edited one by the executable itself.
        assert_eq!(build_id("abc", false), "commit abc");
        let edited = build_id("abc", true);
        assert!(edited.starts_with("executable ") && edited.len() == 11 + 64, "{edited}");
        assert_eq!(edited, build_id("unknown", false));
        let mut moved = scene.clone();
        let x = &mut moved.objects[0].mesh.positions[0].x;
        *x = x.next_up();
        assert_ne!(k, key(&moved, 64, 48, "exact", None, "abc"));
        let mut lit = scene.clone();
        if let scenes::Light::Directional { direction } = &mut lit.light {
            direction.y = direction.y.next_up();
        }
        assert_ne!(k, key(&lit, 64, 48, "exact", None, "abc"), "{:?}", lit.light);
    }
}
