//! Flags shared by several commands, one name per concept (issue 13 item 9): plots as
//! `--plot-dir DIR` + `--plot-format`, the case file as `--config FILE`, and choices parsed
//! through clap's [`clap::ValueEnum`] with messages that name the flag as the user typed it.
//!
//! Renamed flags keep their old spelling for one release as a hidden alias (or, where the
//! message must name the old spelling, a hidden deprecated option): `--tooth0-deg`,
//! `--plot`, `--plots`, `--model`, `--offset-um`, `--offset-se-um`, `--flutes` (README, CHANGELOG).

use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use std::path::{Path, PathBuf};

/// A plot file type.
#[derive(ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PlotFormat {
    #[default]
    Svg,
    Png,
}

impl PlotFormat {
    /// `svg` or `png` (the file extension).
    pub fn ext(self) -> &'static str {
        match self {
            PlotFormat::Svg => "svg",
            PlotFormat::Png => "png",
        }
    }
}

/// `--plot-dir DIR` and `--plot-format` of a command writing plots, with the deprecated
/// single-file `--plot FILE` (hidden, kept for one release).
#[derive(clap::Args, Debug, Default, Clone)]
pub struct PlotFlags {
    /// Write the plots into this folder (created if missing), as `<name>.<plot-format>`.
    #[arg(long, value_name = "DIR", allow_hyphen_values = true)]
    pub plot_dir: Option<PathBuf>,
    /// Plot file type (svg or png; no unit).
    #[arg(long, value_enum, default_value_t = PlotFormat::Svg)]
    pub plot_format: PlotFormat,
    /// Deprecated, use --plot-dir: the plot as one file (.svg or .png, by its extension).
    #[arg(long, hide = true, value_name = "FILE", allow_hyphen_values = true)]
    pub plot: Option<PathBuf>,
}

impl PlotFlags {
    /// Where the plot `name` goes: `--plot FILE` if given, else `DIR/name.<format>`, else nowhere.
    pub fn file(&self, name: &str) -> Option<PathBuf> {
        self.plot.clone().or_else(|| self.in_dir(name))
    }

    /// `DIR/name.<format>` when --plot-dir was given (ignoring --plot).
    pub fn in_dir(&self, name: &str) -> Option<PathBuf> {
        self.plot_dir
            .as_ref()
            .map(|d| d.join(format!("{name}.{}", self.plot_format.ext())))
    }

    /// Create the plot folder, if one was given.
    pub fn create_dir(&self) -> Result<()> {
        if let Some(d) = &self.plot_dir {
            std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
        }
        Ok(())
    }
}

/// `--time-var NAME`: the time base of a recording from a channel / variable of the file (issue 16),
/// for every command that reads recordings (identify, displacement signal, shank force / calibrate).
#[derive(clap::Args, Debug, Default, Clone)]
pub struct TimeFlags {
    /// Channel / variable holding the sample times (s; a text column's unit from its name or
    /// unit row), or in a .mat/HDF5/TDMS/Parquet file a scalar sample rate (Hz). The times must be
    /// evenly spaced (every sample within ½ sample period of the grid; ¼ for displacement
    /// signal); with --sample-rate-hz both must agree. Missing: the error lists what the file holds.
    #[arg(long, value_name = "NAME", allow_hyphen_values = true)]
    pub time_var: Option<String>,
}

/// The cutter: one set of flags for every command that takes one (issue 13 item 7), the keys
/// of a case file (`teeth`, `diameter_mm`, …), resolved by one resolver
/// ([`runout_io::config::simulate::resolve_cutter`]). Values may carry a unit suffix.
#[derive(clap::Args, Debug, Default, Clone)]
pub struct CutterFlags {
    /// Number of teeth K (count).
    #[arg(long, allow_hyphen_values = true)]
    pub teeth: Option<String>,
    /// Cutter diameter D (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub diameter_mm: Option<String>,
    /// Helix angle (deg); 0 for straight flutes.
    #[arg(long, allow_hyphen_values = true)]
    pub helix_deg: Option<String>,
    /// Variable pitch angles (deg), K comma-separated values summing to 360.
    #[arg(long, allow_hyphen_values = true)]
    pub pitch_deg: Option<String>,
    /// Flute length (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub flute_length_mm: Option<String>,
    /// End profile: flat | ball | bull_nose | tapered (default flat).
    #[arg(long, allow_hyphen_values = true)]
    pub profile: Option<String>,
    /// Corner radius r_c of a bull_nose cutter (mm), 0 < r_c <= D/2.
    #[arg(long, allow_hyphen_values = true)]
    pub corner_radius_mm: Option<String>,
    /// Taper (half-cone) angle of a tapered cutter (deg), 0 < α < 45; D is the tip diameter.
    #[arg(long, allow_hyphen_values = true)]
    pub taper_deg: Option<String>,
    /// Flute winding on a ball, bull-nose or taper: constant_lead | constant_helix (default constant_lead).
    #[arg(long, allow_hyphen_values = true)]
    pub flute_lead: Option<String>,
}

impl CutterFlags {
    /// The flags as (case-file key, value given).
    pub fn pairs(&self) -> [(&'static str, &Option<String>); 9] {
        [
            ("teeth", &self.teeth),
            ("diameter_mm", &self.diameter_mm),
            ("helix_deg", &self.helix_deg),
            ("pitch_deg", &self.pitch_deg),
            ("flute_length_mm", &self.flute_length_mm),
            ("profile", &self.profile),
            ("corner_radius_mm", &self.corner_radius_mm),
            ("taper_deg", &self.taper_deg),
            ("flute_lead", &self.flute_lead),
        ]
    }

    /// The cutter, when --teeth and --diameter-mm are given (`None` when neither is).
    pub fn cutter(&self) -> Result<Option<runout_core::Cutter>> {
        match (&self.teeth, &self.diameter_mm) {
            (Some(_), Some(_)) => {}
            (None, None) => return Ok(None),
            _ => bail!("--teeth and --diameter-mm go together"),
        }
        let s = runout::case::settings(None, runout::case::flag_layer(self.pairs()), &[])?;
        Ok(Some(runout_io::config::simulate::resolve_cutter(&s)?))
    }
}

/// The case file: the positional argument or `--config FILE` (one of them).
pub fn config_file(
    positional: &Option<PathBuf>,
    flag: &Option<PathBuf>,
) -> Result<Option<PathBuf>> {
    match (positional, flag) {
        (Some(a), Some(b)) if a != b => bail!(
            "two case files: {} and --config {}; give one",
            a.display(),
            b.display()
        ),
        (Some(a), _) => Ok(Some(a.clone())),
        (None, b) => Ok(b.clone()),
    }
}

/// A choice flag's text as the enum `T` (case-insensitive, surrounding spaces ignored); the
/// message names `flag` as given and lists the accepted values.
pub fn choice<T: ValueEnum>(flag: &str, text: &str) -> Result<T> {
    T::from_str(text.trim(), true).map_err(|_| {
        let names: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value().map(|p| p.get_name().to_string()))
            .collect();
        anyhow::anyhow!(
            "{flag}: expected {}, got `{}`",
            names.join(" | "),
            text.trim()
        )
    })
}

/// The value of a renamed flag: the canonical one, or the old spelling (hidden, deprecated),
/// with the name that was used (for messages). Giving both is refused by clap
/// (`conflicts_with`).
pub fn renamed<'a, T>(
    canonical: (&'static str, &'a Option<T>),
    old: (&'static str, &'a Option<T>),
) -> (&'static str, &'a Option<T>) {
    if old.1.is_some() {
        old
    } else {
        canonical
    }
}

/// Refuse outputs that overwrite one of `inputs`.
pub fn check_outputs<'a>(
    outputs: impl IntoIterator<Item = &'a Option<PathBuf>>,
    inputs: &[&Path],
) -> Result<()> {
    for out in outputs.into_iter().flatten() {
        crate::output::check_not_input(out, inputs)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choices_name_the_flag_and_the_values() {
        assert_eq!(
            choice::<PlotFormat>("--plot-format", " PNG ").unwrap(),
            PlotFormat::Png
        );
        let e = choice::<PlotFormat>("--plot-format", "pdf")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "--plot-format: expected svg | png, got `pdf`");
    }

    #[test]
    fn plot_files_and_config() {
        let p = PlotFlags {
            plot_dir: Some("out".into()),
            plot_format: PlotFormat::Png,
            plot: None,
        };
        assert_eq!(p.file("forces"), Some(PathBuf::from("out/forces.png")));
        let old = PlotFlags {
            plot: Some("f.svg".into()),
            ..PlotFlags::default()
        };
        assert_eq!(old.file("forces"), Some(PathBuf::from("f.svg")));
        assert_eq!(PlotFlags::default().file("x"), None);
        let (a, b) = (Some(PathBuf::from("a.toml")), Some(PathBuf::from("b.toml")));
        assert_eq!(config_file(&a, &None).unwrap(), a);
        assert_eq!(config_file(&None, &b).unwrap(), b);
        assert!(config_file(&a, &b).is_err());
        let (x, y) = (Some(1), None);
        assert_eq!(renamed(("--new", &y), ("--old", &x)), ("--old", &x));
    }
}
