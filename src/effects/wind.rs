//! Wind: aerodynamic drag per triangle from the air velocity relative to the triangle,
//! projected on its normal: `f = 1/2 rho Cd A (vr . n) |vr . n| n`, shared equally by its vertices.
//!
//! The wind velocity is a constant plus a scripted variation: keyframes (linear interpolation)
//! and sinusoidal gusts, so a flag flaps. `df/dv` is analytic; the dependence of `n` and `A` on
//! positions is treated explicitly (lagged one step), as usual for aerodynamic loads.

use super::effect::{Effect, State};
use crate::linalg::outer;
use crate::linalg::{BlockCsr, PatternBuilder};
use crate::Vec3;
use serde::{Deserialize, Serialize};

/// A sinusoidal gust: `amplitude * sin(2 pi frequency t + phase)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gust {
    pub amplitude: Vec3,
    pub frequency: f64,
    #[serde(default)]
    pub phase: f64,
}

/// Wind velocity offset at a time (keyframes are interpolated linearly, held at the ends).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindKey {
    pub t: f64,
    pub velocity: Vec3,
}

pub struct Wind {
    pub velocity: Vec3,
    pub keys: Vec<WindKey>,
    pub gusts: Vec<Gust>,
    /// `1/2 rho Cd`.
    half_rho_cd: f64,
    triangles: Vec<[u32; 3]>,
}

impl Wind {
    pub fn new(
        velocity: Vec3,
        keys: Vec<WindKey>,
        gusts: Vec<Gust>,
        air_density: f64,
        drag_coefficient: f64,
        triangles: Vec<[u32; 3]>,
    ) -> Self {
        Self {
            velocity,
            keys,
            gusts,
            half_rho_cd: 0.5 * air_density * drag_coefficient,
            triangles,
        }
    }

    /// Air velocity at time `t`.
    pub fn velocity_at(&self, t: f64) -> Vec3 {
        let mut w = self.velocity;
        if let (Some(first), Some(last)) = (self.keys.first(), self.keys.last()) {
            w += if t <= first.t {
                first.velocity
            } else if t >= last.t {
                last.velocity
            } else {
                let k = self.keys.partition_point(|k| k.t <= t);
                let (a, b) = (self.keys[k - 1], self.keys[k]);
                let s = (t - a.t) / (b.t - a.t).max(1e-12);
                a.velocity.lerp(b.velocity, s)
            };
        }
        for g in &self.gusts {
            w += g.amplitude * (std::f64::consts::TAU * g.frequency * t + g.phase).sin();
        }
        w
    }

    /// (unit normal, area, normal relative speed) of a triangle.
    fn triangle(&self, s: &State, w: Vec3, t: &[u32; 3]) -> (Vec3, f64, f64) {
        let [a, b, c] = t.map(|i| i as usize);
        let cr = (s.x[b] - s.x[a]).cross(s.x[c] - s.x[a]);
        let len = cr.length();
        if len <= 0.0 {
            return (Vec3::ZERO, 0.0, 0.0);
        }
        let n = cr / len;
        let vr = w - (s.v[a] + s.v[b] + s.v[c]) / 3.0;
        (n, 0.5 * len, vr.dot(n))
    }
}

impl Effect for Wind {
    fn name(&self) -> &'static str {
        "wind"
    }

    fn set_wind_velocity(&mut self, velocity: Vec3) -> bool {
        self.velocity = velocity;
        true
    }

    fn declare(&self, p: &mut PatternBuilder) {
        for t in &self.triangles {
            p.couple_all(t);
        }
    }

    fn add_forces(&self, s: &State, f: &mut [Vec3]) {
        let w = self.velocity_at(s.t);
        for t in &self.triangles {
            let (n, area, vn) = self.triangle(s, w, t);
            let fv = n * (self.half_rho_cd * area * vn * vn.abs() / 3.0);
            for &i in t {
                f[i as usize] += fv;
            }
        }
    }

    fn add_jacobians(&self, s: &State, _dfdx: &mut BlockCsr, dfdv: &mut BlockCsr) {
        let w = self.velocity_at(s.t);
        for t in &self.triangles {
            let (n, area, vn) = self.triangle(s, w, t);
            let m = outer(n, n) * (-2.0 * self.half_rho_cd * area * vn.abs() / 9.0);
            for &a in t {
                for &b in t {
                    dfdv.add(a, b, m);
                }
            }
        }
    }

    fn injects_energy(&self) -> bool {
        true
    }
}
