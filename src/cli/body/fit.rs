//! `fitroom body fit`: the MakeHuman sliders fitted to measurements.

use std::{collections::BTreeMap, fmt::Write as _, path::Path};

use anyhow::{Context, Result, bail};
use fitroom_body::{BodyModel, FitOptions, FitReport, FitRequest, Measure};

/// `--gender`: MakeHuman's gender slider at either end.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gender {
    #[value(aliases = ["f", "woman"])]
    Female,
    #[value(aliases = ["m", "man"])]
    Male,
}

impl Gender {
    /// MakeHuman's gender slider: 0 female, 1 male.
    pub fn slider(self) -> f32 {
        match self {
            Gender::Female => 0.0,
            Gender::Male => 1.0,
        }
    }
}

/// The measurement flags of `fitroom body fit` (cm).
#[derive(Debug, Default, Clone, clap::Args)]
pub struct MeasurementArgs {
    #[arg(long)]
    pub stature: Option<f32>,
    /// Crotch height.
    #[arg(long)]
    pub inside_leg: Option<f32>,
    #[arg(long)]
    pub arm_length: Option<f32>,
    /// Biacromial breadth.
    #[arg(long)]
    pub shoulder_width: Option<f32>,
    /// Neck base girth.
    #[arg(long)]
    pub neck: Option<f32>,
    /// Bust (or chest) girth.
    #[arg(long, alias = "chest")]
    pub bust: Option<f32>,
    #[arg(long)]
    pub underbust: Option<f32>,
    /// Natural waist girth (EN 13402, the narrowest).
    #[arg(long)]
    pub waist: Option<f32>,
    /// Waist girth at the navel (ANSUR II's waist).
    #[arg(long)]
    pub navel_waist: Option<f32>,
    #[arg(long, alias = "hips")]
    pub hip: Option<f32>,
    #[arg(long)]
    pub thigh: Option<f32>,
    #[arg(long)]
    pub calf: Option<f32>,
}

impl MeasurementArgs {
    pub fn targets(&self) -> BTreeMap<Measure, f32> {
        [
            (Measure::Stature, self.stature),
            (Measure::InsideLeg, self.inside_leg),
            (Measure::ArmLength, self.arm_length),
            (Measure::ShoulderWidth, self.shoulder_width),
            (Measure::Neck, self.neck),
            (Measure::Bust, self.bust),
            (Measure::Underbust, self.underbust),
            (Measure::Waist, self.waist),
            (Measure::NavelWaist, self.navel_waist),
            (Measure::Hip, self.hip),
            (Measure::Thigh, self.thigh),
            (Measure::Calf, self.calf),
        ]
        .into_iter()
        .filter_map(|(m, v)| v.map(|v| (m, v)))
        .collect()
    }
}

/// `fitroom body fit`: fits, optionally saves the shape, and returns the report.
pub fn fit(
    model: &BodyModel,
    gender: f32,
    age_years: Option<f32>,
    measurements: &MeasurementArgs,
    out: Option<&Path>,
) -> Result<FitReport> {
    let request = FitRequest {
        gender,
        age_years,
        targets: measurements.targets(),
    };
    if request.targets.is_empty() {
        bail!(
            "give at least one measurement to fit, in cm: --stature, --inside-leg, --arm-length, \
             --shoulder-width, --neck, --bust, --underbust, --waist, --navel-waist, --hip, \
             --thigh, --calf"
        );
    }
    let report = fitroom_body::fit(model, &request, &FitOptions::default())?;
    if let Some(out) = out {
        let text = ron::ser::to_string_pretty(&report.shape, ron::ser::PrettyConfig::default())
            .context("cannot write the shape as RON")?;
        std::fs::write(out, text + "\n")
            .with_context(|| format!("cannot write the shape file '{}'", out.display()))?;
    }
    Ok(report)
}

/// A fit report as a table for people.
pub fn fit_table(r: &FitReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<16}{:>10}{:>10}{:>10}",
        "measure", "target", "achieved", "error"
    );
    for (m, t) in &r.targets {
        let a = m.of(&r.achieved);
        let flag = if (a - t).abs() > r.tolerance_cm {
            "  out of reach"
        } else {
            ""
        };
        let _ = writeln!(
            s,
            "{:<16}{:>10.1}{:>10.1}{:>+10.2}{flag}",
            m.name(),
            t,
            a,
            a - t
        );
    }
    let _ = writeln!(
        s,
        "{} in {:.0} ms ({} full measurements, {} steps, {} trial bodies)",
        if r.reachable {
            format!("reached within {} cm", r.tolerance_cm)
        } else {
            "NOT reachable by the model: the closest body is shown".to_owned()
        },
        r.time_ms,
        r.outer_iterations,
        r.iterations,
        r.evaluations
    );
    if !r.at_bounds.is_empty() {
        let _ = writeln!(s, "sliders at their limits: {}", r.at_bounds.join(", "));
    }
    s
}
