//! `memstab group NAME [--json]`: a point group's elements, irreps and characters.

use super::CliError;
use clap::Args;
use serde::Serialize;
use symmetry::Group;

#[derive(Debug, Args)]
pub(crate) struct GroupArgs {
    /// Group name: C<n>, C<n>v (n >= 1), I or Ih.
    name: String,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct ElementJson {
    matrix: [[f64; 3]; 3],
}

#[derive(Serialize)]
struct IrrepJson<'a> {
    name: &'a str,
    dim: usize,
    kind: &'static str,
    characters: Vec<f64>,
}

#[derive(Serialize)]
struct GroupJson<'a> {
    name: &'a str,
    order: usize,
    elements: Vec<ElementJson>,
    classes: &'a [Vec<usize>],
    irreps: Vec<IrrepJson<'a>>,
}

/// Rounds away the last bits of noise so that exact values print exactly (e.g. 0, −1, 0.5).
fn clean(x: f64) -> f64 {
    let r = (x * 1e12).round() / 1e12;
    if r == 0.0 {
        0.0
    } else if (r - x).abs() < 1e-13 {
        r
    } else {
        x
    }
}

pub(crate) fn run(args: &GroupArgs) -> Result<(), CliError> {
    memstab::limits::Limits::from_env()
        .and_then(|l| l.check_group(&args.name))
        .map_err(|e| CliError::Input(e.to_string()))?;
    let g = Group::by_name(&args.name).map_err(|e| CliError::Input(e.to_string()))?;
    if args.json {
        let json = GroupJson {
            name: g.name(),
            order: g.order(),
            elements: g
                .elements()
                .iter()
                .map(|m| ElementJson {
                    matrix: [0, 1, 2].map(|i| [0, 1, 2].map(|j| clean(m[(i, j)]))),
                })
                .collect(),
            classes: g.classes(),
            irreps: g
                .irreps()
                .iter()
                .map(|r| IrrepJson {
                    name: r.name(),
                    dim: r.dim(),
                    kind: match r.kind() {
                        symmetry::IrrepKind::Real => "real",
                        symmetry::IrrepKind::Complex => "complex",
                    },
                    characters: r.characters().into_iter().map(clean).collect(),
                })
                .collect(),
        };
        let text = serde_json::to_string(&json).map_err(|e| CliError::Failure(e.to_string()))?;
        out!("{text}");
        return Ok(());
    }
    out!(
        "{}: order {}, {} classes, {} real irreps",
        g.name(),
        g.order(),
        g.classes().len(),
        g.irreps().len()
    );
    out!("character table (one column per class; size x representative):");
    print!("{:>6}", "");
    for c in g.classes() {
        print!(" {:>9}", format!("{}x{}", c.len(), c[0]));
    }
    out!();
    for r in g.irreps() {
        print!("{:>6}", r.name());
        for c in g.classes() {
            print!(" {:>9.4}", clean(r.character(c[0])));
        }
        out!();
    }
    Ok(())
}
