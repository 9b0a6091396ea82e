//! A small software rasteriser: perspective camera, z-buffer, per-vertex normals interpolated
//! across each triangle (Gouraud normals, Lambert shading per pixel), two-sided lighting.
//!
//! Shade of a pixel with unit normal `n` (flipped to face the camera), light direction `l` and
//! base colour `c`: `c * (ambient + diffuse * max(0, n . l)) + specular * max(0, n . h)^32`, with
//! `h` the half vector of `l` and the view direction.

use crate::Vec3;

/// An RGB image, row-major, 3 bytes per pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

impl Image {
    /// A vertical light-grey gradient (so white cloth still stands out).
    pub fn background(width: usize, height: usize) -> Image {
        let mut rgb = Vec::with_capacity(width * height * 3);
        for y in 0..height {
            let t = y as f64 / height.max(1) as f64;
            let g = (238.0 - 40.0 * t) as u8;
            for _ in 0..width {
                rgb.extend_from_slice(&[g, g, g.saturating_add(6)]);
            }
        }
        Image { width, height, rgb }
    }

    /// Copies `tile` with its top left corner at `(x0, y0)`.
    pub fn blit(&mut self, tile: &Image, x0: usize, y0: usize) {
        for y in 0..tile.height {
            let ty = y0 + y;
            if ty >= self.height {
                break;
            }
            let w = tile.width.min(self.width.saturating_sub(x0));
            let src = &tile.rgb[y * tile.width * 3..(y * tile.width + w) * 3];
            let at = (ty * self.width + x0) * 3;
            self.rgb[at..at + w * 3].copy_from_slice(src);
        }
    }
}

/// A pinhole camera looking at `target` from `eye`, `up` roughly up.
#[derive(Debug, Clone, Copy)]
pub struct Camera {
    pub eye: Vec3,
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    /// Focal length in pixels.
    focal: f64,
    cx: f64,
    cy: f64,
}

impl Camera {
    /// Frames the sphere `(center, radius)` from the direction given by azimuth and elevation
    /// (radians; azimuth from +x towards +y, elevation above the x-y plane), z up.
    pub fn framing(
        center: Vec3,
        radius: f64,
        azimuth: f64,
        elevation: f64,
        width: usize,
        height: usize,
    ) -> Camera {
        let fov_y: f64 = 35f64.to_radians();
        let dir = Vec3::new(
            elevation.cos() * azimuth.cos(),
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
        );
        let aspect_fov = if width < height {
            // The narrower side decides.
            2.0 * ((fov_y / 2.0).tan() * width as f64 / height as f64).atan()
        } else {
            fov_y
        };
        let dist = radius.max(1e-6) / (aspect_fov / 2.0).sin() * 1.02;
        let eye = center + dir * dist;
        let forward = (center - eye).normalize();
        let right = forward.cross(Vec3::Z).normalize_or(Vec3::X);
        let up = right.cross(forward);
        Camera {
            eye,
            right,
            up,
            forward,
            focal: height as f64 / 2.0 / (fov_y / 2.0).tan(),
            cx: width as f64 / 2.0,
            cy: height as f64 / 2.0,
        }
    }

    /// Pixel coordinates and depth of a world point (`None` behind the camera).
    pub fn project(&self, p: Vec3) -> Option<(f64, f64, f64)> {
        let d = p - self.eye;
        let z = d.dot(self.forward);
        if z <= 1e-6 {
            return None;
        }
        Some((
            self.cx + self.focal * d.dot(self.right) / z,
            self.cy - self.focal * d.dot(self.up) / z,
            z,
        ))
    }
}

/// Triangles with per-vertex normals and one colour, to draw.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub color: [f64; 3],
}

impl Mesh {
    /// Area-weighted vertex normals of the triangles.
    pub fn smooth_normals(&mut self) {
        let mut n = vec![Vec3::ZERO; self.positions.len()];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.positions[i as usize]);
            let f = (b - a).cross(c - a);
            for &i in t {
                n[i as usize] += f;
            }
        }
        for v in &mut n {
            *v = v.normalize_or_zero();
        }
        self.normals = n;
    }
}

/// Draws meshes into an image with a shared z-buffer, and keeps which draw call each pixel
/// shows (what the camera's choice of view counts).
pub struct Raster {
    pub image: Image,
    depth: Vec<f64>,
    /// Per pixel: 0 for background, else `k` for the `k`-th [`Raster::draw`] call.
    owner: Vec<u32>,
    draws: u32,
    light: Vec3,
}

impl Raster {
    pub fn new(width: usize, height: usize, camera: &Camera) -> Raster {
        // Light from above, over the camera's left shoulder.
        let light = (camera.up * 1.0 - camera.right * 0.5 - camera.forward * 0.8).normalize();
        Raster {
            image: Image::background(width, height),
            depth: vec![f64::INFINITY; width * height],
            owner: vec![0; width * height],
            draws: 0,
            light,
        }
    }

    /// Per pixel, which draw call it shows: 0 for none, `k` for the `k`-th.
    pub fn owners(&self) -> &[u32] {
        &self.owner
    }

    pub fn draw(&mut self, camera: &Camera, mesh: &Mesh) {
        self.draws += 1;
        let projected: Vec<Option<(f64, f64, f64)>> =
            mesh.positions.iter().map(|&p| camera.project(p)).collect();
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        for t in &mesh.triangles {
            let Some(idx) = t
                .iter()
                .map(|&i| usize::try_from(i).ok().filter(|&i| i < projected.len()))
                .collect::<Option<Vec<usize>>>()
            else {
                continue;
            };
            let Some(p) = idx
                .iter()
                .map(|&i| projected[i])
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            let area =
                (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
            if area.abs() < 1e-12 || !area.is_finite() {
                continue;
            }
            let xmin = p
                .iter()
                .map(|q| q.0)
                .fold(f64::INFINITY, f64::min)
                .floor()
                .max(0.0) as i64;
            let xmax = (p
                .iter()
                .map(|q| q.0)
                .fold(f64::NEG_INFINITY, f64::max)
                .ceil() as i64)
                .min(w - 1);
            let ymin = p
                .iter()
                .map(|q| q.1)
                .fold(f64::INFINITY, f64::min)
                .floor()
                .max(0.0) as i64;
            let ymax = (p
                .iter()
                .map(|q| q.1)
                .fold(f64::NEG_INFINITY, f64::max)
                .ceil() as i64)
                .min(h - 1);
            let normals: Vec<Vec3> = idx
                .iter()
                .map(|&i| mesh.normals.get(i).copied().unwrap_or(Vec3::Z))
                .collect();
            let world: Vec<Vec3> = idx.iter().map(|&i| mesh.positions[i]).collect();
            for y in ymin..=ymax {
                for x in xmin..=xmax {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let e = |a: usize, b: usize| {
                        (p[b].0 - p[a].0) * (py - p[a].1) - (px - p[a].0) * (p[b].1 - p[a].1)
                    };
                    let (w0, w1, w2) = (e(1, 2) / area, e(2, 0) / area, e(0, 1) / area);
                    if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                        continue;
                    }
                    let z = w0 * p[0].2 + w1 * p[1].2 + w2 * p[2].2;
                    let k = (y * w + x) as usize;
                    if z >= self.depth[k] {
                        continue;
                    }
                    self.depth[k] = z;
                    self.owner[k] = self.draws;
                    let pos = world[0] * w0 + world[1] * w1 + world[2] * w2;
                    let mut n =
                        (normals[0] * w0 + normals[1] * w1 + normals[2] * w2).normalize_or(Vec3::Z);
                    let view = (camera.eye - pos).normalize_or(Vec3::Z);
                    if n.dot(view) < 0.0 {
                        n = -n;
                    }
                    let diffuse = n.dot(self.light).max(0.0);
                    let half = (self.light + view).normalize_or(Vec3::Z);
                    let spec = 0.25 * n.dot(half).max(0.0).powi(32);
                    let shade = 0.28 + 0.72 * diffuse;
                    let px = &mut self.image.rgb[k * 3..k * 3 + 3];
                    for c in 0..3 {
                        let v = (mesh.color[c] * shade + spec) * 255.0;
                        px[c] = v.round().clamp(0.0, 255.0) as u8;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearer_triangle_wins_and_shading_is_two_sided() {
        let cam = Camera::framing(
            Vec3::ZERO,
            1.0,
            0.0,
            std::f64::consts::FRAC_PI_2 - 1e-3,
            64,
            64,
        );
        let mut r = Raster::new(64, 64, &cam);
        let quad = |z: f64, color: [f64; 3], flip: bool| {
            let mut m = Mesh {
                positions: vec![
                    Vec3::new(-1.0, -1.0, z),
                    Vec3::new(1.0, -1.0, z),
                    Vec3::new(1.0, 1.0, z),
                    Vec3::new(-1.0, 1.0, z),
                ],
                triangles: if flip {
                    vec![[0, 2, 1], [0, 3, 2]]
                } else {
                    vec![[0, 1, 2], [0, 2, 3]]
                },
                color,
                ..Mesh::default()
            };
            m.smooth_normals();
            m
        };
        r.draw(&cam, &quad(0.0, [1.0, 0.0, 0.0], false));
        r.draw(&cam, &quad(0.2, [0.0, 0.0, 1.0], true));
        let mid = (32 * 64 + 32) * 3;
        let px = &r.image.rgb[mid..mid + 3];
        assert!(
            px[2] > 100 && px[0] < 80,
            "the nearer blue quad is drawn lit: {px:?}"
        );
    }
}
