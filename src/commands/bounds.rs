//! `sepg bounds`: every closed-form quantity that the given task constants, σ and gradients
//! determine (Theorems 3.11, 3.13, 3.14, 4.2, 4.3, 4.5, Lemma A.1, Corollary 4.4); the report
//! is [`sepg_runs::bounds_report`], this file parses and prints.

use clap::Args;
use sepg_runs::bounds_report::{self, BoundsQuery, BoundsReport, CertifiedReport, RowValue};

use crate::cli::CliError;
use crate::output::to_json_line;

/// Arguments of `sepg bounds`.
#[derive(Debug, Args)]
pub struct BoundsArgs {
    #[command(flatten)]
    query: BoundsQuery,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    json: bool,
    /// Also print, under `certified`, an outward-rounded enclosure [lo, hi] of ψ, c, d, C_max,
    /// λ and every safe-interval end point, and the certified largest steps with the
    /// enclosure of their bound (docs/THEOREMS.md, Certified steps).
    #[arg(long)]
    certified: bool,
}

fn render_table(r: &BoundsReport) -> String {
    let mut out = String::new();
    for row in r.rows() {
        let value = match row.value {
            RowValue::Real(x) => format!("{x:.6e}"),
            RowValue::Constant(x) => format!("{x:.10}"),
            RowValue::Exact(x) => format!("{x}"),
            RowValue::Count(n) => n.to_string(),
            RowValue::Flag(b) => b.to_string(),
            RowValue::Name(s) => s,
        };
        out.push_str(&format!("{:<22} {value:>16}   {}\n", row.name, row.cite));
    }
    if let Some(c) = &r.certified {
        render_certified(c, &mut out);
    }
    out
}

/// The `certified` part of the table: the enclosures, then the certified steps.
fn render_certified(c: &CertifiedReport, out: &mut String) {
    out.push_str("certified enclosures [lo, hi] (outward-rounded):\n");
    for (name, [lo, hi]) in &c.enclosures {
        out.push_str(&format!("  {name:<20} [{lo:e}, {hi:e}]\n"));
    }
    out.push_str("certified steps:\n");
    for (name, s) in &c.steps {
        let step = s.step.map_or_else(|| "-".to_string(), |x| format!("{x:e}"));
        let bound = s
            .bound
            .map_or_else(|| "-".to_string(), |[lo, hi]| format!("[{lo:e}, {hi:e}]"));
        out.push_str(&format!(
            "  {name:<20} {:<14} step {step}, bound {bound}\n",
            s.outcome.label()
        ));
    }
}

/// Runs `sepg bounds`.
pub fn run(args: &BoundsArgs) -> Result<(), CliError> {
    let report = bounds_report::report(&args.query, args.certified)?;
    let text = if args.json {
        to_json_line(&report)?
    } else {
        render_table(&report)
    };
    print!("{text}");
    Ok(())
}
