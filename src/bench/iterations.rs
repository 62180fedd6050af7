//! Test 12 (paper section 5.2.4, table 4): t_real/t_sim of nine boxes at dt = 0.01 s
//! against the iterations, 1 … 40.
//!
//! The paper measured only its particle method ("changing the iterations for the time
//! stepper did not have any impact" on its constraint-based one). `iterations` is the
//! paper's N in the particle method's paper mode and the velocity iterations per substep
//! of the multibody method; the improved particle solver spends its budget in substeps,
//! so its row shows what the setting costs it (each method's own label says what it did).

use super::table::{Table, pct};
use super::{Flavor, Report, RowFilter, Size, pct_cell, progress, scenes, time_flavors};
use crate::AppError;
use serde_json::{Value, json};

/// The paper's table 4: iterations, particle % (t_real = 10 s).
pub const PAPER: [(u32, f64); 6] = [
    (1, 33.0),
    (2, 33.0),
    (5, 39.0),
    (10, 57.0),
    (20, 94.0),
    (40, 169.0),
];

/// Simulated seconds per measurement.
pub const SECONDS: f64 = 10.0;

/// Runs test 12.
pub fn run(size: Size, only: &RowFilter) -> Result<Report, AppError> {
    let (rows_wanted, seconds): (&[_], f64) = match size {
        Size::Full => (&PAPER, SECONDS),
        Size::Quick => (&PAPER[..2], 0.05),
    };
    let mut table = Table::new(
        format!(
            "Test 12 (table 4): 100% * t_real/t_sim against iterations, nine boxes, \
             dt = 0.01 s, {seconds} s simulated per run (t_real: the stepping thread's CPU time)"
        ),
        &[
            "Iterations",
            "paper particle",
            "particle(paper)",
            "particle(rigid-frames)",
            "multibody",
        ],
    );
    let mut rows = Vec::new();
    let mut labels = serde_json::Map::new();
    for &(iterations, paper_particle) in rows_wanted {
        if !only.keeps(iterations as f64) {
            continue;
        }
        progress(&format!("iterations: {iterations}"));
        let scene = scenes::nine_boxes(iterations);
        let runs = time_flavors(&scene, seconds, &Flavor::ALL)?;
        table.row(vec![
            iterations.to_string(),
            pct(paper_particle),
            pct_cell(&runs[0].1),
            pct_cell(&runs[1].1),
            pct_cell(&runs[2].1),
        ]);
        let mut row = serde_json::Map::new();
        row.insert("iterations".into(), json!(iterations));
        row.insert("paper_particle_percent".into(), json!(paper_particle));
        for (flavor, t) in &runs {
            row.insert(flavor.key().into(), t.to_json());
        }
        rows.push(Value::Object(row));
        if labels.is_empty() {
            for flavor in Flavor::ALL {
                labels.insert(
                    flavor.key().into(),
                    json!(flavor.build(&scene)?.solver_label()),
                );
            }
        }
    }
    for (k, v) in &labels {
        table.note(format!(
            "{k} at its first row: {}",
            v.as_str().unwrap_or_default()
        ));
    }
    Ok(Report {
        json: json!({"bench": "iterations", "timestep": 0.01, "rows": rows, "solvers": labels}),
        text: table.render(),
    })
}
