//! Body measurements (ISO 8559-1 names, metres) read from RON, with defaults derived from
//! stature for the ones not given.
//!
//! The default size is a man of stature 1.76 m with chest 1.00 m, waist 0.88 m, hip 1.00 m
//! (close to EN 13402-3 size 50, but the proportions are chosen, not taken from a survey).
//! The girths not given default to these ratios of stature (chosen to match the default
//! size): upper arm 0.18, wrist 0.10, thigh 0.33, knee 0.21, calf 0.21, ankle 0.125; the
//! biacromial breadth 0.23. Segment lengths and joint heights follow Drillis & Contini's
//! ratios of stature as tabulated by Winter, *Biomechanics and Motor Control of Human
//! Movement* (4th ed., 2009), Fig. 4.1 (shoulder 0.818 H, knee 0.285 H, upper arm : forearm
//! 0.186 : 0.146, hand 0.108 H, foot 0.152 H, foot breadth 0.055 H).

use serde::{Deserialize, Serialize};

use crate::input::{Locator, SceneError};

/// Body measurements as written in a measurements file. Lengths in metres, written as plain
/// numbers. Only `stature` is required; the others default to ratios of stature (module doc).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Measurements {
    /// Stature: floor to the top of the head (vertex), standing.
    pub stature: f64,
    /// Chest girth, horizontal, at the chest level (0.72 H).
    #[serde(default)]
    pub chest_girth: Option<f64>,
    /// Waist girth, horizontal, at the natural waist (0.605 H).
    #[serde(default)]
    pub waist_girth: Option<f64>,
    /// Hip girth, horizontal, at the greatest buttock prominence (0.04 H above the crotch).
    #[serde(default)]
    pub hip_girth: Option<f64>,
    /// Neck girth, perpendicular to the neck axis, at mid-neck (0.86 H).
    #[serde(default)]
    pub neck_girth: Option<f64>,
    /// Head girth, the horizontal maximum above the brows (0.945 H).
    #[serde(default)]
    pub head_girth: Option<f64>,
    /// Arm length: shoulder joint centre to wrist joint centre along the straight arm
    /// (ISO 8559-1 arm length with the shoulder point taken at the joint centre).
    #[serde(default)]
    pub arm_length: Option<f64>,
    /// Inseam (ISO 8559-1 crotch height / inside leg length): floor to the crotch point, the
    /// lowest point of the pelvis segment, standing.
    #[serde(default)]
    pub inseam: Option<f64>,
    /// Biacromial (shoulder) breadth between the shoulder points.
    #[serde(default)]
    pub biacromial_breadth: Option<f64>,
    /// Upper-arm girth at mid upper arm.
    #[serde(default)]
    pub upper_arm_girth: Option<f64>,
    /// Wrist girth at the wrist joint level of the forearm.
    #[serde(default)]
    pub wrist_girth: Option<f64>,
    /// Thigh girth just below the crotch (0.01 H below it).
    #[serde(default)]
    pub thigh_girth: Option<f64>,
    /// Knee girth at the knee joint centre (end of the thigh).
    #[serde(default)]
    pub knee_girth: Option<f64>,
    /// Calf girth at 0.07 H below the knee joint.
    #[serde(default)]
    pub calf_girth: Option<f64>,
    /// Ankle girth (minimum leg girth) at 0.02 H above the ankle joint.
    #[serde(default)]
    pub ankle_girth: Option<f64>,
    /// Mesh refinement: 1 (default) gives 16 vertices round a limb and 24 round the trunk;
    /// `r` multiplies both and the rings of the caps.
    #[serde(default = "one")]
    pub resolution: u32,
}

fn one() -> u32 {
    1
}

/// All measurements with the defaults filled in (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    pub stature: f64,
    pub chest_girth: f64,
    pub waist_girth: f64,
    pub hip_girth: f64,
    pub neck_girth: f64,
    pub head_girth: f64,
    pub arm_length: f64,
    pub inseam: f64,
    pub biacromial_breadth: f64,
    pub upper_arm_girth: f64,
    pub wrist_girth: f64,
    pub thigh_girth: f64,
    pub knee_girth: f64,
    pub calf_girth: f64,
    pub ankle_girth: f64,
    pub resolution: u32,
}

/// Each measurement: its field name, ratio of stature as default, and the range of ratios
/// of stature accepted (a body generated outside it would not be a human shape).
const RATIOS: [(&str, f64, f64, f64); 14] = [
    ("chest_girth", 0.57, 0.35, 1.0),
    ("waist_girth", 0.50, 0.30, 1.0),
    ("hip_girth", 0.57, 0.35, 1.0),
    ("neck_girth", 0.22, 0.12, 0.35),
    ("head_girth", 0.325, 0.22, 0.45),
    ("arm_length", 0.335, 0.26, 0.42),
    ("inseam", 0.46, 0.38, 0.50),
    ("biacromial_breadth", 0.23, 0.17, 0.30),
    ("upper_arm_girth", 0.18, 0.10, 0.35),
    ("wrist_girth", 0.10, 0.06, 0.16),
    ("thigh_girth", 0.33, 0.18, 0.55),
    ("knee_girth", 0.21, 0.13, 0.35),
    ("calf_girth", 0.21, 0.12, 0.35),
    ("ankle_girth", 0.125, 0.08, 0.20),
];

impl Measurements {
    /// The default size (module doc): stature 1.76 m, chest 1.00 m, waist 0.88 m, hip
    /// 1.00 m, neck 0.39 m, head 0.57 m, arm length 0.59 m, inseam 0.81 m.
    pub fn default_size() -> Self {
        Self {
            stature: 1.76,
            chest_girth: Some(1.00),
            waist_girth: Some(0.88),
            hip_girth: Some(1.00),
            neck_girth: Some(0.39),
            head_girth: Some(0.57),
            arm_length: Some(0.59),
            inseam: Some(0.81),
            resolution: 1,
            ..Default::default()
        }
    }

    fn given(&self, name: &str) -> Option<f64> {
        match name {
            "chest_girth" => self.chest_girth,
            "waist_girth" => self.waist_girth,
            "hip_girth" => self.hip_girth,
            "neck_girth" => self.neck_girth,
            "head_girth" => self.head_girth,
            "arm_length" => self.arm_length,
            "inseam" => self.inseam,
            "biacromial_breadth" => self.biacromial_breadth,
            "upper_arm_girth" => self.upper_arm_girth,
            "wrist_girth" => self.wrist_girth,
            "thigh_girth" => self.thigh_girth,
            "knee_girth" => self.knee_girth,
            "calf_girth" => self.calf_girth,
            "ankle_girth" => self.ankle_girth,
            _ => None,
        }
    }

    /// Fills the defaults and checks every value: finite, positive, and its ratio to stature
    /// within the accepted range; the stature within 0.5–2.5 m; resolution 1–8. Errors are
    /// located by `loc` at the offending field.
    pub fn resolve(&self, loc: &Locator) -> Result<Resolved, SceneError> {
        let h = self.stature;
        if !(h.is_finite() && (0.5..=2.5).contains(&h)) {
            return Err(loc.at(None, Some("stature"), "stature", format!("must be between 0.5 and 2.5 m, found {h}")));
        }
        if !(1..=8).contains(&self.resolution) {
            return Err(loc.at(None, Some("resolution"), "resolution", format!("must be 1 to 8, found {}", self.resolution)));
        }
        for &(name, _, lo, hi) in &RATIOS {
            if let Some(x) = self.given(name) {
                if !(x.is_finite() && x >= lo * h && x <= hi * h) {
                    return Err(loc.at(
                        None,
                        Some(name),
                        name,
                        format!("{x} m is outside {:.3}–{:.3} m ({lo}–{hi} × stature {h} m)", lo * h, hi * h),
                    ));
                }
            }
        }
        Ok(self.fill())
    }

    /// The measurements with the defaults filled in, unchecked.
    pub fn fill(&self) -> Resolved {
        let h = self.stature;
        let v: Vec<f64> = RATIOS.iter().map(|&(name, ratio, ..)| self.given(name).unwrap_or(ratio * h)).collect();
        Resolved {
            stature: h,
            chest_girth: v[0],
            waist_girth: v[1],
            hip_girth: v[2],
            neck_girth: v[3],
            head_girth: v[4],
            arm_length: v[5],
            inseam: v[6],
            biacromial_breadth: v[7],
            upper_arm_girth: v[8],
            wrist_girth: v[9],
            thigh_girth: v[10],
            knee_girth: v[11],
            calf_girth: v[12],
            ankle_girth: v[13],
            resolution: self.resolution,
        }
    }
}

/// Parses a measurements file (RON); `file` names it in errors. Returns the measurements
/// with defaults filled in.
pub fn parse_measurements(file: &str, text: &str) -> Result<Resolved, SceneError> {
    let text = crate::input::strip_bom(text);
    let loc = Locator::new(file, text);
    // Optional measurements are written as plain numbers (`chest_girth: 1.0`, no `Some`).
    let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let m: Measurements = options.from_str(text).map_err(|e| loc.from_ron(&e))?;
    m.resolve(&loc)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_from_stature_and_located_errors() {
        let r = parse_measurements("m.ron", "(stature: 1.6)").expect("valid");
        assert!((r.chest_girth - 0.57 * 1.6).abs() < 1e-15 && (r.inseam - 0.46 * 1.6).abs() < 1e-15);
        let e = parse_measurements("m.ron", "(\n  stature: 1.76,\n  waist_girth: 3.0,\n)").expect_err("too large");
        assert_eq!((e.line, e.column, e.field.as_str()), (3, 3, "waist_girth"));
        let d = Measurements::default_size();
        assert_eq!(d.resolve(&Locator::new("d", "")).expect("the default size is accepted"), d.fill());
        let e = parse_measurements("m.ron", "(stature: 1.76, chest: 1.0)").expect_err("unknown field");
        assert_eq!(e.line, 1);
        assert!(e.to_string().contains("chest"), "{e}");
    }
}
