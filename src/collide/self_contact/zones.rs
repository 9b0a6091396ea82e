//! Rigid impact zones (Provot 1997, Harmon et al. 2008): the fail-safe that moves each group of
//! still-colliding vertices rigidly, and stops them at their start positions as a last resort.

use super::collider::SelfCollider;
use super::stencil::Stencil;
use crate::{Mat3, Vec3};

fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[parent[i as usize] as usize];
        parent[i as usize] = p;
        i = p;
    }
    i
}

fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

/// The rigid motion `v = vc + omega x (x - xc)` that best fits weighted point velocities
/// `(x, v, m)`: centre-of-mass velocity and the angular velocity `I^-1 L` of the momentum about
/// the centre. Collinear sets have a singular inertia, regularised by a tiny fraction of its trace
/// (the rotation about their line is then zero).
fn rigid_fit(points: impl Iterator<Item = (Vec3, Vec3, f64)> + Clone) -> (Vec3, Vec3, Vec3) {
    let mut m_tot = 0.0;
    let mut xc = Vec3::ZERO;
    let mut vc = Vec3::ZERO;
    for (x, v, m) in points.clone() {
        m_tot += m;
        xc += x * m;
        vc += v * m;
    }
    if m_tot <= 0.0 {
        return (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
    }
    xc /= m_tot;
    vc /= m_tot;
    let mut l = Vec3::ZERO;
    let mut inertia = Mat3::ZERO;
    for (x, v, m) in points {
        let r = x - xc;
        l += r.cross(v - vc) * m;
        inertia +=
            (Mat3::IDENTITY * r.length_squared() - Mat3::from_cols(r * r.x, r * r.y, r * r.z)) * m;
    }
    let tr = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
    inertia += Mat3::IDENTITY * (1e-9 * tr + 1e-300);
    let omega = if inertia.determinant().abs() > 0.0 {
        inertia.inverse() * l
    } else {
        Vec3::ZERO
    };
    (vc, omega, xc)
}

impl SelfCollider {
    pub(super) fn merge(&mut self, st: &Stencil) {
        for k in 1..st.len {
            union(&mut self.parent, st.idx[0], st.idx[k]);
        }
    }

    /// Rigid impact zones: merge the vertices of still-colliding pairs and move each zone with
    /// the affine-rigid velocity `v_cm + w x r` from x0 (an invertible affine motion cannot
    /// create an intersection inside the zone). Returns the pairs still colliding at the end.
    pub(super) fn impact_zones(
        &mut self,
        zone_iterations: usize,
        x0: &[Vec3],
        x1: &mut [Vec3],
        v1: &mut [Vec3],
        th: &[f64],
        h: f64,
    ) -> usize {
        let n = x0.len().min(x1.len());
        self.parent.clear();
        self.parent.extend(0..n as u32);
        for _ in 0..zone_iterations.max(1) {
            if self.ccd_pass(x0, x1, v1, th, false) == 0 {
                return 0;
            }
            self.rigidify(x0, x1, v1, h);
        }
        // Last resort: vertices of zones stop at x0 (always intersection-free if x0 was).
        if self.ccd_pass(x0, x1, v1, th, false) == 0 {
            return 0;
        }
        self.mark_zones(n);
        for i in 0..n {
            if self.in_zone[i] && self.w[i] > 0.0 {
                x1[i] = x0[i];
                v1[i] = Vec3::ZERO;
            }
        }
        let stuck = self.ccd_pass(x0, x1, v1, th, false);
        if stuck > 0 {
            log::warn!("self-collision fail-safe left {stuck} colliding pairs");
        }
        stuck
    }

    /// `in_zone[i]`: vertex i shares a zone with another vertex.
    fn mark_zones(&mut self, n: usize) {
        self.in_zone.clear();
        self.in_zone.resize(n, false);
        for i in 0..n as u32 {
            let r = find(&mut self.parent, i);
            if r != i {
                self.in_zone[i as usize] = true;
                self.in_zone[r as usize] = true;
            }
        }
    }

    fn rigidify(&mut self, x0: &[Vec3], x1: &mut [Vec3], v1: &mut [Vec3], h: f64) {
        let n = x0.len().min(x1.len());
        for z in &mut self.zone_members {
            z.clear();
        }
        self.mark_zones(n);
        let mut roots: Vec<u32> = Vec::new();
        // Group members by root.
        let mut slot = vec![u32::MAX; 0];
        slot.resize(n, u32::MAX);
        for i in 0..n as u32 {
            if !self.in_zone[i as usize] {
                continue;
            }
            let r = find(&mut self.parent, i) as usize;
            if slot[r] == u32::MAX {
                slot[r] = roots.len() as u32;
                roots.push(r as u32);
                if self.zone_members.len() < roots.len() {
                    self.zone_members.push(Vec::new());
                }
            }
            self.zone_members[slot[r] as usize].push(i);
        }
        self.report.zones = self.report.zones.max(roots.len());
        let largest = self.zone_members[..roots.len()].iter().map(Vec::len).max();
        self.report.largest_zone = self.report.largest_zone.max(largest.unwrap_or(0));
        let inv_h = if h > 0.0 { 1.0 / h } else { 0.0 };
        for z in 0..roots.len() {
            let members = &self.zone_members[z];
            let vel = |i: usize| (x1[i] - x0[i]) * inv_h;
            let kinematic: Vec<usize> = members
                .iter()
                .map(|&i| i as usize)
                .filter(|&i| self.w[i] <= 0.0)
                .collect();
            if !kinematic.is_empty() {
                // Kinematic members have infinite mass: the zone moves rigidly with them, by the
                // rigid motion that best fits their velocities (exact when they share one link or
                // pin). Translating it with their mean velocity would ignore the link's rotation
                // and stretch the edges into the zone (robot_cape, where the shoulder's attached
                // corner meets the torso's).
                let (vc, omega, xc) = rigid_fit(kinematic.iter().map(|&i| (x0[i], vel(i), 1.0)));
                for &i in members {
                    let i = i as usize;
                    if self.w[i] > 0.0 {
                        let v = vc + omega.cross(x0[i] - xc);
                        v1[i] = v;
                        x1[i] = x0[i] + v * h;
                    }
                }
                continue;
            }
            let fit = members.iter().map(|&i| {
                let i = i as usize;
                (x0[i], vel(i), 1.0 / self.w[i])
            });
            let (vc, omega, xc) = rigid_fit(fit);
            for &i in members {
                let i = i as usize;
                let v = vc + omega.cross(x0[i] - xc);
                v1[i] = v;
                x1[i] = x0[i] + v * h;
            }
        }
    }
}
