//! Test 10 (paper section 5.2.2, table 2): t_real/t_sim of three bones, one hinge and
//! one ball joint, for timesteps 0.001 … 0.1 s.
//!
//! The paper ran each scene for 10 s of wall-clock time and read the simulated time;
//! we simulate a fixed [`SECONDS`] and read the wall-clock time, which is the same ratio
//! without making a slow method simulate less of the scene than a fast one.

use super::table::{Table, pct};
use super::{Flavor, Report, RowFilter, Size, pct_cell, progress, scenes, time_flavors};
use crate::AppError;
use serde_json::{Value, json};

/// Simulated seconds per measurement (the figure falls, lands and settles).
pub const SECONDS: f64 = 10.0;

/// The paper's table 2: timestep, particle t_sim, particle %, constraint t_sim,
/// constraint %, all for t_real = 10 s. The percentages are printed as the paper has
/// them (its last particle row says 6 % where 10/317.2 is 3 %).
pub const PAPER: [(f32, f64, f64, f64, f64); 5] = [
    (0.001, 3.3, 303.0, 2.6, 385.0),
    (0.005, 17.5, 57.0, 12.9, 78.0),
    (0.01, 33.0, 30.0, 26.5, 38.0),
    (0.05, 166.2, 6.0, 132.3, 8.0),
    (0.1, 317.2, 6.0, 267.7, 4.0),
];

/// Runs test 10.
pub fn run(size: Size, only: &RowFilter) -> Result<Report, AppError> {
    let (rows_wanted, seconds): (&[_], f64) = match size {
        Size::Full => (&PAPER, SECONDS),
        Size::Quick => (&PAPER[2..3], 0.05),
    };
    let mut table = Table::new(
        format!(
            "Test 10 (table 2): 100% * t_real/t_sim, three bones, one hinge, one ball joint, \
             {seconds} s simulated per run (below 100% is faster than real time; t_real is the \
             stepping thread's CPU time)"
        ),
        &[
            "Timestep",
            "paper particle",
            "particle(paper)",
            "particle(rigid-frames)",
            "paper constraint",
            "multibody",
        ],
    );
    let mut rows = Vec::new();
    for &(dt, _, paper_particle, _, paper_constraint) in rows_wanted {
        if !only.keeps(dt as f64) {
            continue;
        }
        progress(&format!("timestep: dt = {dt}"));
        let scene = scenes::three_bones(dt);
        let runs = time_flavors(&scene, seconds, &Flavor::ALL)?;
        table.row(vec![
            format!("{dt}"),
            pct(paper_particle),
            pct_cell(&runs[0].1),
            pct_cell(&runs[1].1),
            pct(paper_constraint),
            pct_cell(&runs[2].1),
        ]);
        let mut row = serde_json::Map::new();
        row.insert("timestep".into(), json!(dt));
        row.insert("paper_particle_percent".into(), json!(paper_particle));
        row.insert("paper_constraint_percent".into(), json!(paper_constraint));
        for (flavor, t) in &runs {
            row.insert(flavor.key().into(), t.to_json());
        }
        rows.push(Value::Object(row));
    }
    Ok(Report {
        json: json!({"bench": "timestep", "seconds": seconds, "rows": rows}),
        text: table.render(),
    })
}
