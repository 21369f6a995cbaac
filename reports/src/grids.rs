//! Image grids with zoomed insets, as the papers show their results side by side (Brabec &
//! Seidel Fig. 7, GPU Gems Figs. 11-6..8, Pan et al. Figs. 8 and 11): one column per panel,
//! the whole frame on top with the inset's region outlined in red, the region magnified below
//! (nearest neighbour, so single pixels stay visible), and the panel's label above.

use crate::model::{Panel, Region};
use crate::output::OutputError;
use image::{Rgb, RgbImage};
use plotters::prelude::*;
use std::path::Path;

/// Height of the label band, in pixels.
const LABEL: u32 = 28;
/// Gap between panels.
const GAP: u32 = 8;

/// The pixel rectangle `(x0, y0, w, h)` of `region` in a `width x height` frame, at least one
/// pixel, inside the frame.
pub fn region_pixels(region: Region, width: u32, height: u32) -> (u32, u32, u32, u32) {
    let clamp = |v: f64, size: u32| ((v.clamp(0.0, 1.0) * f64::from(size)) as u32).min(size - 1);
    let (x0, y0) = (clamp(region[0], width), clamp(region[1], height));
    let w = ((region[2].clamp(0.0, 1.0) * f64::from(width)) as u32).clamp(1, width - x0);
    let h = ((region[3].clamp(0.0, 1.0) * f64::from(height)) as u32).clamp(1, height - y0);
    (x0, y0, w, h)
}

/// Composes the grid: panels side by side, each with its frame (region outlined) above its
/// inset scaled to the panel's width.
pub fn compose(panels: &[Panel], region: Region) -> Option<RgbImage> {
    let first = panels.first()?;
    let (fw, fh) = first.image.dimensions();
    if fw == 0 || fh == 0 || panels.iter().any(|p| p.image.dimensions() != (fw, fh)) {
        return None;
    }
    let (rx, ry, rw, rh) = region_pixels(region, fw, fh);
    let zoom = (fw / rw).max(1);
    let (iw, ih) = (rw * zoom, rh * zoom);
    let n = panels.len() as u32;
    let width = n * fw.max(iw) + (n + 1) * GAP;
    let height = LABEL + fh + GAP + ih + 2 * GAP;
    let mut out = RgbImage::from_pixel(width, height, Rgb([255, 255, 255]));
    for (k, p) in panels.iter().enumerate() {
        let left = GAP + k as u32 * (fw.max(iw) + GAP);
        for (x, y, px) in p.image.enumerate_pixels() {
            out.put_pixel(left + x, LABEL + y, *px);
        }
        // Outline the region on the frame.
        let red = Rgb([230, 20, 20]);
        for x in rx..rx + rw {
            out.put_pixel(left + x, LABEL + ry, red);
            out.put_pixel(left + x, LABEL + ry + rh - 1, red);
        }
        for y in ry..ry + rh {
            out.put_pixel(left + rx, LABEL + y, red);
            out.put_pixel(left + rx + rw - 1, LABEL + y, red);
        }
        let top = LABEL + fh + GAP;
        for y in 0..ih {
            for x in 0..iw {
                out.put_pixel(left + x, top + y, *p.image.get_pixel(rx + x / zoom, ry + y / zoom));
            }
        }
    }
    Some(out)
}

/// Composes the grid, draws the labels and writes it as PNG.
pub fn write_grid(path: &Path, panels: &[Panel], region: Region) -> Result<(), OutputError> {
    let fail = |message: String| OutputError::Write { path: path.to_owned(), message };
    let grid = compose(panels, region)
        .ok_or_else(|| fail("a grid needs panels of one non-empty frame size".into()))?;
    let (w, h) = grid.dimensions();
    let mut buf = grid.into_raw();
    {
        crate::plots::register_font();
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let (fw, _) = panels[0].image.dimensions();
        let (_, _, rw, _) = region_pixels(region, fw, panels[0].image.height());
        let column = fw.max(rw * (fw / rw).max(1)) + GAP;
        for (k, p) in panels.iter().enumerate() {
            let x = (GAP + k as u32 * column) as i32;
            root.draw_text(&p.label, &("sans-serif", 15).into_font().color(&BLACK), (x, 5))
                .map_err(|e| fail(e.to_string()))?;
        }
        root.present().map_err(|e| fail(e.to_string()))?;
    }
    let img = RgbImage::from_raw(w, h, buf).ok_or_else(|| fail("grid buffer size".into()))?;
    img.save(path).map_err(|e| fail(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_places_frames_and_magnified_insets() {
        let mut a = RgbImage::from_pixel(40, 30, Rgb([0, 0, 0]));
        a.put_pixel(20, 15, Rgb([255, 255, 255]));
        let b = RgbImage::from_pixel(40, 30, Rgb([100, 100, 100]));
        let panels = [Panel { label: "a".into(), image: a }, Panel { label: "b".into(), image: b }];
        let region = [0.5, 0.5, 0.25, 0.25]; // pixels 20..30 x 15..22, magnified 4x
        assert_eq!(region_pixels(region, 40, 30), (20, 15, 10, 7));
        let g = compose(&panels, region).expect("composes");
        assert_eq!(g.dimensions(), (2 * 40 + 3 * GAP, LABEL + 30 + GAP + 28 + 2 * GAP));
        // The white pixel, top-left of the region, fills the inset's first 4x4 block.
        let top = LABEL + 30 + GAP;
        assert_eq!(*g.get_pixel(GAP + 3, top + 3), Rgb([255, 255, 255]));
        assert_eq!(*g.get_pixel(GAP + 4, top + 4), Rgb([0, 0, 0]));
        // The region is outlined in red on the frame.
        assert_eq!(*g.get_pixel(GAP + 25, LABEL + 15), Rgb([230, 20, 20]));
        assert!(compose(&[], region).is_none());
        let dir = tempfile::tempdir().expect("tempdir");
        write_grid(&dir.path().join("g.png"), &panels, region).expect("writes");
    }
}
