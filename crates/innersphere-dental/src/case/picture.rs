//! The report's pictures, drawn without a window or a GPU: meshes projected orthographically
//! along a view direction, hidden surfaces removed by a depth buffer, each triangle lit by
//! its normal, written as PNG. Deterministic (one thread, fixed order), so that a report
//! is the same bytes run after run. Hand-written because no maintained crate rasterises
//! triangles headlessly without pulling in a GPU stack, and the job is ~100 lines.

use glam::DVec3;
use innersphere::error::{Error, Result};
use innersphere::mesh::Mesh;

/// A camera: the picture's right and up directions and the direction towards the viewer
/// (all unit, orthogonal).
#[derive(Debug, Clone, Copy)]
pub struct View {
    right: DVec3,
    up: DVec3,
    toward: DVec3,
}

impl View {
    /// Looking along `-toward` with `up_hint` as the picture's up (made orthogonal).
    pub fn new(toward: DVec3, up_hint: DVec3) -> View {
        let toward = toward.normalize_or(DVec3::Z);
        let right = up_hint
            .cross(toward)
            .normalize_or(toward.any_orthonormal_vector());
        View {
            right,
            up: toward.cross(right),
            toward,
        }
    }
}

/// One mesh to draw: its vertices (already placed), triangles and a colour per vertex or
/// one for all.
pub struct Layer<'a> {
    /// The vertices, placed in the common frame.
    pub vertices: &'a [DVec3],
    /// The mesh's triangles.
    pub mesh: &'a Mesh,
    /// Per-vertex colours (`None`: `colour` for all).
    pub colours: Option<&'a [[u8; 3]]>,
    /// The colour when there are no per-vertex ones.
    pub colour: [u8; 3],
}

/// Draws `layers` seen through `view` into a `width` × `height` PNG (the drawing fills it
/// with a margin; the background is white).
pub fn render(layers: &[Layer], view: &View, width: u32, height: u32) -> Result<Vec<u8>> {
    let (w, h) = (width as usize, height as usize);
    let project = |p: DVec3| (p.dot(view.right), p.dot(view.up), p.dot(view.toward));
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for l in layers {
        for &v in l.vertices {
            let (x, y, _) = project(v);
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
    }
    let mut rgb = vec![255u8; w * h * 3];
    if lo.0.is_finite() && hi.0 > lo.0 && hi.1 > lo.1 {
        let s = (0.92 * w as f64 / (hi.0 - lo.0)).min(0.92 * h as f64 / (hi.1 - lo.1));
        let (cx, cy) = ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0);
        let to_px = |x: f64, y: f64| ((x - cx) * s + w as f64 / 2.0, h as f64 / 2.0 - (y - cy) * s);
        let mut depth = vec![f64::NEG_INFINITY; w * h];
        let light = (view.toward * 0.8 + view.up * 0.45 + view.right * 0.2).normalize();
        for l in layers {
            for t in &l.mesh.triangles {
                let [a, b, c] = t.map(|i| l.vertices.get(i as usize).copied());
                let (Some(a), Some(b), Some(c)) = (a, b, c) else {
                    continue;
                };
                let n = (b - a).cross(c - a).normalize_or_zero();
                // Both faces lit (open scans show their insides too).
                let shade = 0.35 + 0.65 * n.dot(light).abs();
                let colour = match l.colours {
                    Some(cs) => {
                        let k = |i: u32| cs.get(i as usize).copied().unwrap_or(l.colour);
                        let (p, q, r) = (k(t[0]), k(t[1]), k(t[2]));
                        std::array::from_fn(|j| {
                            ((p[j] as u32 + q[j] as u32 + r[j] as u32) / 3) as u8
                        })
                    }
                    None => l.colour,
                };
                let lit: [u8; 3] = colour.map(|x| (x as f64 * shade).round().min(255.0) as u8);
                let p = [a, b, c].map(|v| {
                    let (x, y, z) = project(v);
                    let (px, py) = to_px(x, y);
                    (px, py, z)
                });
                fill(&p, lit, w, h, &mut depth, &mut rgb);
            }
        }
    }
    encode_png(&rgb, width, height)
}

/// Fills the projected triangle `p` (pixel x, y, depth towards the viewer) where it is
/// nearer than `depth`.
fn fill(
    p: &[(f64, f64, f64); 3],
    colour: [u8; 3],
    w: usize,
    h: usize,
    depth: &mut [f64],
    rgb: &mut [u8],
) {
    let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
    if !area.is_finite() || area.abs() < 1e-12 {
        return;
    }
    let x0 = p
        .iter()
        .map(|q| q.0)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as usize;
    let x1 = p
        .iter()
        .map(|q| q.0)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(w as f64 - 1.0);
    let y0 = p
        .iter()
        .map(|q| q.1)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as usize;
    let y1 = p
        .iter()
        .map(|q| q.1)
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .min(h as f64 - 1.0);
    if x1 < 0.0 || y1 < 0.0 {
        return;
    }
    let (x1, y1) = (x1 as usize, y1 as usize);
    let edge = |a: (f64, f64, f64), b: (f64, f64, f64), x: f64, y: f64| {
        (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0)
    };
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
            let w0 = edge(p[1], p[2], fx, fy) / area;
            let w1 = edge(p[2], p[0], fx, fy) / area;
            let w2 = edge(p[0], p[1], fx, fy) / area;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * p[0].2 + w1 * p[1].2 + w2 * p[2].2;
            let k = y * w + x;
            if z > depth[k] {
                depth[k] = z;
                rgb[3 * k..3 * k + 3].copy_from_slice(&colour);
            }
        }
    }
}

/// `rgb` (8-bit, row by row) as a PNG file's bytes.
pub fn encode_png(rgb: &[u8], width: u32, height: u32) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    let fail = |e: png::EncodingError| Error::InvalidOption(format!("drawing a picture: {e}"));
    {
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(fail)?;
        writer.write_image_data(rgb).map_err(fail)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square seen face on fills the middle of the picture in its colour, shaded;
    /// the corners stay white; the same drawing gives the same bytes.
    #[test]
    fn a_square_fills_the_middle() {
        let mesh = Mesh {
            vertices: vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let layer = Layer {
            vertices: &mesh.vertices,
            mesh: &mesh,
            colours: None,
            colour: [200, 100, 50],
        };
        let view = View::new(DVec3::Z, DVec3::Y);
        let png_bytes = render(&[layer], &view, 40, 40).unwrap();
        let again = render(
            &[Layer {
                vertices: &mesh.vertices,
                mesh: &mesh,
                colours: None,
                colour: [200, 100, 50],
            }],
            &view,
            40,
            40,
        )
        .unwrap();
        assert_eq!(png_bytes, again);
        let decoder = png::Decoder::new(std::io::Cursor::new(png_bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        reader.next_frame(&mut buf).unwrap();
        let at = |x: usize, y: usize| &buf[3 * (y * 40 + x)..3 * (y * 40 + x) + 3];
        assert_eq!(at(0, 0), [255, 255, 255]);
        let mid = at(20, 20);
        assert!(
            mid[0] > mid[1] && mid[1] > mid[2] && mid[0] < 255,
            "{mid:?}"
        );
    }
}
