//! Material keys in the units a textile lab reports (`areal_density` in g/m^2, bending lengths
//! in cm, `tensile` stiffness per unit width in N/m), beside the spring constants they stand in
//! for. Both forms of one property in one material is an error naming the key; the lab's
//! values are range-checked here, then converted ([`crate::cloth::Material::resolve_textile`])
//! before the scene's validation sees the internal constants.

use super::problem::{
    Invalid, Problem, MAX_BENDING_LENGTH, MAX_DENSITY, MAX_STIFFNESS, MAX_STRAIN_LIMIT,
};
use super::Scene;
use crate::cloth::Material;
use serde_yaml_ng::Value;

/// Each textile key and the key it stands in for.
const PAIRS: [(&str, &str); 4] = [
    ("areal_density", "density"),
    ("bending_length_warp", "bend_warp"),
    ("bending_length_weft", "bend_weft"),
    ("tensile", "stretch"),
];

fn positive(key: String, v: f64, max: f64, unit: &'static str) -> Result<(), Invalid> {
    if !v.is_finite() {
        return Err((key, Problem::NotFinite { value: v }));
    }
    if v <= 0.0 {
        return Err((key, Problem::NotPositive { value: v }));
    }
    if v > max {
        return Err((
            key,
            Problem::TooLarge {
                value: v,
                max,
                unit,
            },
        ));
    }
    Ok(())
}

/// Range checks of one material's textile keys (`at`: `cloths[0]`); `grid`: whether its
/// cloth is a grid (a tensile stiffness needs one).
fn check_values(at: &str, m: &Material, grid: bool) -> Result<(), Invalid> {
    let key = |k: &str| format!("{at}.material.{k}");
    if let Some(v) = m.areal_density {
        positive(key("areal_density"), v, MAX_DENSITY * 1e3, " g/m^2")?;
    }
    if let Some(v) = m.bending_length_warp {
        positive(key("bending_length_warp"), v, MAX_BENDING_LENGTH, " cm")?;
    }
    if let Some(v) = m.bending_length_weft {
        positive(key("bending_length_weft"), v, MAX_BENDING_LENGTH, " cm")?;
    }
    if let Some(t) = m.tensile {
        if !grid {
            return Err((key("tensile"), Problem::NeedsGrid));
        }
        positive(key("tensile.warp"), t.warp, MAX_STIFFNESS, " N/m")?;
        positive(key("tensile.weft"), t.weft, MAX_STIFFNESS, " N/m")?;
        positive(key("tensile.strain"), t.strain, MAX_STRAIN_LIMIT, "")?;
    }
    Ok(())
}

impl Scene {
    /// Refuses a material of the scene's text that gives a textile key and the key it replaces.
    /// Serde has already read the text (with its defaults), so this looks at the keys written.
    pub(super) fn check_textile_keys(text: &str) -> Result<(), Invalid> {
        let Ok(value) = serde_yaml_ng::from_str::<Value>(text) else {
            return Ok(());
        };
        for list in ["cloths", "garments"] {
            let Some(items) = value.get(list).and_then(Value::as_sequence) else {
                continue;
            };
            for (i, item) in items.iter().enumerate() {
                let Some(m) = item.get("material").and_then(Value::as_mapping) else {
                    continue;
                };
                for (textile, spring) in PAIRS {
                    if m.contains_key(textile) && m.contains_key(spring) {
                        return Err((
                            format!("{list}[{i}].material.{textile}"),
                            Problem::BothKeys { other: spring },
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// Checks every material's textile keys and converts them to the internal constants.
    pub(super) fn resolve_textile(&mut self) -> Result<(), Invalid> {
        for (i, c) in self.cloths.iter_mut().enumerate() {
            check_values(&format!("cloths[{i}]"), &c.material, true)?;
            c.material.resolve_textile();
            // The springs take `tensile` by their widths; what reads one constant per cloth
            // (stretch bounds, wave speeds) reads the inner springs' of the softer direction.
            let [nu, nv] = c.grid.resolution;
            if let (Some(t), true) = (c.material.tensile, nu >= 2 && nv >= 2) {
                let du = c.grid.size[0] / (nu - 1) as f64;
                let dv = c.grid.size[1] / (nv - 1) as f64;
                let k = (t.warp * dv / du).min(t.weft * du / dv);
                if k.is_finite() && k > 0.0 {
                    c.material.stretch = k;
                }
            }
        }
        for (i, g) in self.garments.iter_mut().enumerate() {
            check_values(&format!("garments[{i}]"), &g.material, false)?;
            g.material.resolve_textile();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::{Problem, Scene, SceneError};

    fn scene(material: &str) -> String {
        format!(
            "effects: [gravity, stretch, bending]
cloths:
  - name: sheet
    grid: {{ size: [1.0, 0.5], resolution: [11, 6] }}
    material: {{ {material} }}
"
        )
    }

    fn refused(material: &str) -> (String, Problem) {
        match Scene::from_yaml(&scene(material), "cloth.yaml") {
            Err(SceneError::Value {
                origin,
                key,
                problem,
            }) => {
                assert_eq!(origin, "cloth.yaml");
                (key, *problem)
            }
            other => panic!("{material}: {other:?}"),
        }
    }

    #[test]
    fn lab_units_become_the_internal_constants() {
        let s = Scene::from_yaml(
            &scene("areal_density: 150, bending_length_warp: 2.5, bending_length_weft: 2.0"),
            "cloth.yaml",
        )
        .expect("valid");
        let m = &s.cloths[0].material;
        assert!((m.density - 0.150).abs() < 1e-15);
        let w = 0.150 * 9.80665;
        assert!((m.bend_warp / (w * 0.025f64.powi(3)) - 1.0).abs() < 1e-12);
        assert!((m.bend_weft / (w * 0.020f64.powi(3)) - 1.0).abs() < 1e-12);
        assert_eq!(m.areal_density, None, "converted, not kept twice");
        // The rendered text reads back the same material.
        let again = Scene::from_yaml(
            &serde_yaml_ng::to_string(&s).expect("serializes"),
            "again.yaml",
        )
        .expect("valid");
        assert_eq!(again.cloths[0].material, *m);
    }

    #[test]
    fn a_tensile_stiffness_sets_the_inner_springs_constant() {
        // 1.0 x 0.5 m on 11 x 6 vertices: du = dv = 0.1 m.
        let s = Scene::from_yaml(
            &scene("tensile: { warp: 800, weft: 600, strain: 0.02 }"),
            "cloth.yaml",
        )
        .expect("valid");
        assert!((s.cloths[0].material.stretch - 600.0).abs() < 1e-9);
    }

    #[test]
    fn a_lab_key_beside_the_key_it_replaces_is_refused() {
        for (both, key, other) in [
            (
                "bend_warp: 1.0e-4, bending_length_warp: 2.0",
                "bending_length_warp",
                "bend_warp",
            ),
            (
                "density: 0.2, areal_density: 200",
                "areal_density",
                "density",
            ),
            (
                "stretch: 1000, tensile: { warp: 800, weft: 800, strain: 0.02 }",
                "tensile",
                "stretch",
            ),
        ] {
            let (k, p) = refused(both);
            assert_eq!(k, format!("cloths[0].material.{key}"));
            assert_eq!(p, Problem::BothKeys { other });
            assert!(p.to_string().contains(other));
        }
    }

    #[test]
    fn lab_values_out_of_range_are_refused_by_key() {
        let (k, _) = refused("bending_length_weft: -1");
        assert_eq!(k, "cloths[0].material.bending_length_weft");
        let (k, _) = refused("tensile: { warp: 800, weft: 0, strain: 0.02 }");
        assert_eq!(k, "cloths[0].material.tensile.weft");
        let (k, _) = refused("areal_density: .nan");
        assert_eq!(k, "cloths[0].material.areal_density");
    }
}
