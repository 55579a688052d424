//! Pictures without external tools: orthographic views of coloured triangles and lines,
//! z-buffered, flat shaded (Lambert, light from the camera), written as PNG
//! ([`super::png`]). Used for the garment-on-body pictures of the movement protocol.

use nalgebra::Vector3;

/// A triangle with its colour.
pub type Triangle = ([Vector3<f64>; 3], [u8; 3]);
/// A line segment with its colour.
pub type Segment = ([Vector3<f64>; 2], [u8; 3]);

/// An RGB image, rows top to bottom.
#[derive(Clone, Debug)]
pub struct Picture {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

/// One view: the direction the camera looks along (from the camera into the scene); image
/// up is the projection of +z (of +y when looking along z).
fn basis(dir: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let d = dir.normalize();
    let up0 = if d.z.abs() > 0.9 { Vector3::y() } else { Vector3::z() };
    let right = d.cross(&up0).normalize();
    let up = right.cross(&d);
    (right, up, d)
}

/// Renders `views` side by side, each `size` × `size` pixels, framing the box `focus`
/// (min, max corners; enlarged by 15 %): every triangle and line is drawn (clipped to the
/// frame), nearer ones hiding farther ones; lines are drawn over surfaces within
/// `line_bias` (m) in front of them.
pub fn render(triangles: &[Triangle], lines: &[Segment], focus: (Vector3<f64>, Vector3<f64>), views: &[Vector3<f64>], size: u32, line_bias: f64) -> Picture {
    let size = size.clamp(16, 4096) as usize;
    let width = size * views.len().max(1);
    let mut rgb = vec![255u8; width * size * 3];
    let corners: Vec<Vector3<f64>> = (0..8).map(|k| Vector3::new(if k & 1 == 0 { focus.0.x } else { focus.1.x }, if k & 2 == 0 { focus.0.y } else { focus.1.y }, if k & 4 == 0 { focus.0.z } else { focus.1.z })).collect();
    for (vi, dir) in views.iter().enumerate() {
        let (right, up, d) = basis(dir);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for c in &corners {
            let p = [c.dot(&right), c.dot(&up)];
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let half = (0.5 * 1.15 * (hi[0] - lo[0]).max(hi[1] - lo[1])).max(1e-6);
        let scale = size as f64 / (2.0 * half);
        // Pixel coordinates (x right, y down) and depth of a point.
        let project = |x: &Vector3<f64>| ((x.dot(&right) - centre[0]) * scale + 0.5 * size as f64, (centre[1] - x.dot(&up)) * scale + 0.5 * size as f64, x.dot(&d));
        let mut depth = vec![f64::INFINITY; size * size];
        let mut put = |px: usize, py: usize, z: f64, c: [u8; 3], depth: &mut Vec<f64>| {
            let i = py * size + px;
            if z < depth[i] {
                depth[i] = z;
                let o = 3 * (py * width + vi * size + px);
                rgb[o..o + 3].copy_from_slice(&c);
            }
        };
        for (t, colour) in triangles {
            let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
            let shade = if n.norm() > 0.0 { 0.35 + 0.65 * n.normalize().dot(&d).abs() } else { 0.35 };
            let c = colour.map(|v| (f64::from(v) * shade).round().clamp(0.0, 255.0) as u8);
            let p = t.map(|x| project(&x));
            let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
            if area.abs() < 1e-12 {
                continue;
            }
            let x0 = p.iter().map(|q| q.0).fold(f64::INFINITY, f64::min).floor().max(0.0) as usize;
            let x1 = p.iter().map(|q| q.0).fold(f64::NEG_INFINITY, f64::max).ceil().min(size as f64 - 1.0);
            let y0 = p.iter().map(|q| q.1).fold(f64::INFINITY, f64::min).floor().max(0.0) as usize;
            let y1 = p.iter().map(|q| q.1).fold(f64::NEG_INFINITY, f64::max).ceil().min(size as f64 - 1.0);
            if x1 < 0.0 || y1 < 0.0 {
                continue;
            }
            for py in y0..=y1 as usize {
                for px in x0..=x1 as usize {
                    let (sx, sy) = (px as f64 + 0.5, py as f64 + 0.5);
                    let w0 = ((p[1].0 - sx) * (p[2].1 - sy) - (p[2].0 - sx) * (p[1].1 - sy)) / area;
                    let w1 = ((p[2].0 - sx) * (p[0].1 - sy) - (p[0].0 - sx) * (p[2].1 - sy)) / area;
                    let w2 = 1.0 - w0 - w1;
                    if w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 {
                        put(px, py, w0 * p[0].2 + w1 * p[1].2 + w2 * p[2].2, c, &mut depth);
                    }
                }
            }
        }
        for (s, colour) in lines {
            let (a, b) = (project(&s[0]), project(&s[1]));
            let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
            for k in 0..=steps {
                let f = k as f64 / steps as f64;
                let (x, y, z) = (a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1), a.2 + f * (b.2 - a.2) - line_bias);
                for (dx, dy) in [(0i64, 0i64), (1, 0), (0, 1), (1, 1)] {
                    let (px, py) = (x as i64 + dx, y as i64 + dy);
                    if px >= 0 && py >= 0 && (px as usize) < size && (py as usize) < size {
                        put(px as usize, py as usize, z, *colour, &mut depth);
                    }
                }
            }
        }
    }
    Picture { width: width as u32, height: size as u32, rgb }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Of two squares facing the camera, the nearer (blue) hides the farther (red) in the
    /// middle of the frame; the corners (outside the 15 % margin) stay white.
    #[test]
    fn nearer_triangles_hide_farther_ones() {
        let sq = |y: f64| -> Vec<[Vector3<f64>; 3]> {
            let (a, b, c, d) = (Vector3::new(-1.0, y, -1.0), Vector3::new(1.0, y, -1.0), Vector3::new(1.0, y, 1.0), Vector3::new(-1.0, y, 1.0));
            vec![[a, b, c], [a, c, d]]
        };
        let mut tris: Vec<Triangle> = sq(1.0).into_iter().map(|t| (t, [0, 0, 255])).collect();
        tris.extend(sq(0.0).into_iter().map(|t| (t, [255, 0, 0])));
        // Looking along −y from +y: the square at y = 1 is nearer.
        let pic = render(&tris, &[], (Vector3::new(-1.0, 0.0, -1.0), Vector3::new(1.0, 1.0, 1.0)), &[Vector3::new(0.0, -1.0, 0.0)], 64, 0.0);
        let px = |x: usize, y: usize| &pic.rgb[3 * (y * 64 + x)..3 * (y * 64 + x) + 3];
        assert_eq!(px(32, 32), &[0, 0, 255]);
        assert_eq!(px(0, 0), &[255, 255, 255]);
    }
}
