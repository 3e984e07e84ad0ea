//! The figure options of a reproduction, as `sepg reproduce` takes them: each optional, with
//! the defaults of [`Style`] and of the experiment, checked before any run starts.

#[cfg(feature = "clap")]
use clap::Args;

use crate::error::{Error, Result};
use crate::figure::{BandKind, Style};
use crate::report::{FigureOptions, XAxis};
use crate::reproduce::Experiment;

/// The options of the figures of a reproduction; `None` takes the default.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[cfg_attr(feature = "clap", derive(Args))]
pub struct FigureFlags {
    /// Band around each curve of the figures: 95% interval, one standard error, or none
    /// (warned about below 3 seeds) [default: ci95]. σ is banded on log σ, the budget by a
    /// percentile bootstrap, so that no band leaves its quantity's domain.
    #[cfg_attr(feature = "clap", arg(long, value_enum))]
    pub band: Option<BandKind>,
    /// Abscissa of the figures: iteration, trajectories or environment steps (trajectories ×
    /// horizon) [default: trajectories for fig-5.3, iteration otherwise].
    #[cfg_attr(feature = "clap", arg(long = "x-axis", value_enum))]
    pub x_axis: Option<XAxis>,
    /// Size of the figures' tick labels in points; other text scales with it (4 to 72).
    #[cfg_attr(
        feature = "clap",
        arg(long = "font-size", allow_negative_numbers = true)
    )]
    pub font_size: Option<f64>,
    /// Resolution of the figures in dots per inch (50 to 1200) [default: 100].
    #[cfg_attr(feature = "clap", arg(long, allow_negative_numbers = true))]
    pub dpi: Option<u32>,
}

impl FigureFlags {
    /// The figure options of the experiment `what`: the given flags over the defaults.
    ///
    /// # Errors
    /// [`Error::Invalid`] when a flag is given for Table 5.1, which has no figure, or when
    /// the font size or resolution is out of range ([`Style::validate`]).
    pub fn options(&self, what: Experiment) -> Result<FigureOptions> {
        if what == Experiment::Table51
            && let Some(flag) = [
                (self.band.is_some(), "--band"),
                (self.x_axis.is_some(), "--x-axis"),
                (self.font_size.is_some(), "--font-size"),
                (self.dpi.is_some(), "--dpi"),
            ]
            .iter()
            .find_map(|&(given, flag)| given.then_some(flag))
        {
            return Err(Error::invalid(format!(
                "{flag} applies to the figures; table-5.1 has none"
            )));
        }
        let defaults = Style::default();
        let options = FigureOptions {
            band: self.band.unwrap_or_default(),
            style: Style {
                font_size: self.font_size.unwrap_or(defaults.font_size),
                dpi: self.dpi.unwrap_or(defaults.dpi),
            },
            x_axis: self.x_axis,
        };
        options.style.validate()?;
        Ok(options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_5_1_takes_no_figure_flag() {
        let flags = FigureFlags {
            dpi: Some(100),
            ..FigureFlags::default()
        };
        let e = flags.options(Experiment::Table51).unwrap_err();
        assert_eq!(
            e.to_string(),
            "--dpi applies to the figures; table-5.1 has none"
        );
        assert!(flags.options(Experiment::Fig51).is_ok());
    }

    #[test]
    fn unset_flags_take_the_style_defaults_and_bad_ones_are_invalid() {
        let o = FigureFlags::default().options(Experiment::Fig52).unwrap();
        assert_eq!(o.style.font_size, Style::default().font_size);
        assert_eq!(o.style.dpi, Style::default().dpi);
        let big = FigureFlags {
            font_size: Some(1000.0),
            ..FigureFlags::default()
        };
        assert!(
            big.options(Experiment::Fig51)
                .unwrap_err()
                .is_invalid_input()
        );
    }
}
