//! Triangles to pixels: a z-buffer with perspective-correct depth, colour and normals, shaded
//! with Lambert and ambient light as the mannequin is.

use image::{Rgb, RgbImage};
use nalgebra::{Point3, Vector3};
use videomocap_core::camera::PinholeCamera;

/// Nearest depth drawn, metres (triangles nearer are left out).
const NEAR_M: f64 = 0.05;

/// Draws the triangles of `vertices` (camera space) over `image`, each pixel coloured by
/// `colour(triangle, rest point)` (the point of the rest mesh `rest` it shows, so patterns stay
/// on the body), and returns the depth per pixel (infinite where nothing was drawn).
pub(super) fn draw(
    camera: &PinholeCamera,
    vertices: &[Vector3<f64>],
    rest: &[Vector3<f64>],
    triangles: &[[u32; 3]],
    colour: &dyn Fn(usize, &Vector3<f64>) -> [f64; 3],
    image: &mut RgbImage,
) -> Vec<f64> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let normals = vertex_normals(vertices, triangles);
    let screen: Vec<Option<(f64, f64)>> = vertices
        .iter()
        .map(|v| {
            if v.z < NEAR_M {
                return None;
            }
            camera.project(&Point3::from(*v)).map(|p| (p.x, p.y))
        })
        .collect();
    // From upper left, behind the camera (as the mannequin's light).
    let light = Vector3::new(0.3, 0.8, 0.5).normalize();
    let mut depth = vec![f64::INFINITY; w * h];
    let mut shade = vec![[0.0f64; 3]; w * h];
    for (ti, t) in triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| i as usize);
        let (Some(pa), Some(pb), Some(pc)) = (screen[a], screen[b], screen[c]) else {
            continue;
        };
        let area = (pb.0 - pa.0) * (pc.1 - pa.1) - (pb.1 - pa.1) * (pc.0 - pa.0);
        if area.abs() < 1e-12 {
            continue;
        }
        let x0 = pa.0.min(pb.0).min(pc.0).floor().max(0.0) as usize;
        let x1 = (pa.0.max(pb.0).max(pc.0).ceil() as i64).min(w as i64 - 1);
        let y0 = pa.1.min(pb.1).min(pc.1).floor().max(0.0) as usize;
        let y1 = (pa.1.max(pb.1).max(pc.1).ceil() as i64).min(h as i64 - 1);
        if x1 < 0 || y1 < 0 {
            continue;
        }
        let inv_z = [
            1.0 / vertices[a].z,
            1.0 / vertices[b].z,
            1.0 / vertices[c].z,
        ];
        for y in y0..=y1 as usize {
            for x in x0..=x1 as usize {
                let (px, py) = (x as f64, y as f64);
                // Barycentric weights of the pixel centre (pixel centres at integers).
                let wa = ((pb.0 - px) * (pc.1 - py) - (pb.1 - py) * (pc.0 - px)) / area;
                let wb = ((pc.0 - px) * (pa.1 - py) - (pc.1 - py) * (pa.0 - px)) / area;
                let wc = 1.0 - wa - wb;
                if wa < -1e-9 || wb < -1e-9 || wc < -1e-9 {
                    continue;
                }
                // Perspective-correct: 1/z is linear on the screen.
                let iz = wa * inv_z[0] + wb * inv_z[1] + wc * inv_z[2];
                let z = 1.0 / iz;
                let k = y * w + x;
                if z >= depth[k] {
                    continue;
                }
                depth[k] = z;
                let (ka, kb, kc) = (wa * inv_z[0] * z, wb * inv_z[1] * z, wc * inv_z[2] * z);
                let n = normals[a] * ka + normals[b] * kb + normals[c] * kc;
                let n = n.try_normalize(1e-12).unwrap_or(-Vector3::z());
                let lambert = n.dot(&-light).max(0.0);
                let s = 0.35 + 0.65 * lambert;
                let p = rest[a] * ka + rest[b] * kb + rest[c] * kc;
                shade[k] = colour(ti, &p).map(|v| v * s);
            }
        }
    }
    for (k, z) in depth.iter().enumerate() {
        if z.is_finite() {
            let c = shade[k].map(|v| v.clamp(0.0, 255.0) as u8);
            image.put_pixel((k % w) as u32, (k / w) as u32, Rgb(c));
        }
    }
    depth
}

/// Area-weighted vertex normals, pointing out of the body.
fn vertex_normals(vertices: &[Vector3<f64>], triangles: &[[u32; 3]]) -> Vec<Vector3<f64>> {
    let mut normals = vec![Vector3::zeros(); vertices.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        let n = (vertices[b] - vertices[a]).cross(&(vertices[c] - vertices[a]));
        for i in [a, b, c] {
            normals[i] += n;
        }
    }
    // The OBJ winds its faces one way; make the normals point away from the body's centre
    // on the whole (the sign is the same for every vertex).
    let centre = vertices.iter().sum::<Vector3<f64>>() / vertices.len().max(1) as f64;
    let outward: f64 = normals
        .iter()
        .zip(vertices)
        .map(|(n, v)| n.dot(&(v - centre)))
        .sum();
    let sign = if outward < 0.0 { -1.0 } else { 1.0 };
    normals
        .into_iter()
        .map(|n| (n * sign).try_normalize(1e-15).unwrap_or(Vector3::zeros()))
        .collect()
}
