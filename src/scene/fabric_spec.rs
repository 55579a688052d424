//! Scene fabric spec → fabric sheet properties (preset plus explicit overrides).

use super::spec::FabricSpec;
use crate::material::{twist_default, FabricProperties, FABRIC_PRESETS};

/// Resolves `spec` into validated properties; on error returns the field and the message.
pub fn fabric_properties(spec: &FabricSpec) -> Result<FabricProperties, (&'static str, String)> {
    let mut p = match &spec.preset {
        Some(name) => FabricProperties::preset(name)
            .ok_or_else(|| ("preset", format!("unknown fabric preset \"{name}\"; presets: {}", FABRIC_PRESETS.join(", "))))?,
        None => {
            let need = |v: Option<f64>, name: &'static str| v.ok_or((name, format!("{name} is required when no preset is given")));
            let (b1, b2) = (need(spec.warp_bending, "warp_bending")?, need(spec.weft_bending, "weft_bending")?);
            let (e1, e2) = (need(spec.warp_tensile, "warp_tensile")?, need(spec.weft_tensile, "weft_tensile")?);
            FabricProperties {
                warp_tensile: e1,
                weft_tensile: e2,
                shear: need(spec.shear, "shear")?,
                poisson: spec.poisson.unwrap_or(0.0),
                warp_bending: b1,
                weft_bending: b2,
                twist_bending: twist_default(b1, b2, need(spec.shear, "shear")?, need(spec.thickness, "thickness")?),
                transverse_shear: e1.max(e2),
                areal_density: need(spec.areal_density, "areal_density")?,
                thickness: need(spec.thickness, "thickness")?,
                tension_table: Vec::new(),
                compression_table: Vec::new(),
            }
        }
    };
    let set = |dst: &mut f64, v: Option<f64>| {
        if let Some(v) = v {
            *dst = v;
        }
    };
    set(&mut p.warp_tensile, spec.warp_tensile);
    set(&mut p.weft_tensile, spec.weft_tensile);
    set(&mut p.shear, spec.shear);
    set(&mut p.poisson, spec.poisson);
    set(&mut p.warp_bending, spec.warp_bending);
    set(&mut p.weft_bending, spec.weft_bending);
    if spec.twist_bending.is_none() {
        p.twist_bending = twist_default(p.warp_bending, p.weft_bending, p.shear, p.thickness);
    }
    set(&mut p.twist_bending, spec.twist_bending);
    if spec.transverse_shear.is_none() && (spec.warp_tensile.is_some() || spec.weft_tensile.is_some()) {
        p.transverse_shear = p.warp_tensile.max(p.weft_tensile);
    }
    set(&mut p.transverse_shear, spec.transverse_shear);
    set(&mut p.areal_density, spec.areal_density);
    set(&mut p.thickness, spec.thickness);
    if let Some(t) = &spec.tension_table {
        p.tension_table = t.clone();
    }
    if let Some(t) = &spec.compression_table {
        p.compression_table = t.clone();
    }
    p.validate()?;
    Ok(p)
}
