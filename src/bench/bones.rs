//! Test 11 (paper section 5.2.3, table 3): t_real/t_sim against the number of bones,
//! dt = 0.01 s, 5 iterations, two joints per three bones; the paper's 3 … 120 bones and
//! then 480, 1920 and 7680 to show how the cost grows.
//!
//! The paper's particle method tested every pair of boxes in every projection
//! iteration and collapsed past 30 bones; a method with a broad phase should cost about
//! the same per bone at every size. The table prints microseconds per bone per step
//! and the log-log slope of the cost (1 = linear, 2 = every pair).

use super::table::{Table, opt, pct};
use super::{Flavor, Report, RowFilter, RunTiming, Size, pct_cell, progress, scenes, time_flavors};
use crate::AppError;
use serde_json::{Value, json};

/// The paper's table 3: bones, particle %, constraint % (t_real = 10 s).
pub const PAPER: [(usize, f64, f64); 6] = [
    (3, 30.0, 40.0),
    (6, 31.0, 40.0),
    (15, 71.0, 40.0),
    (30, 222.0, 40.0),
    (60, 769.0, 43.0),
    (120, 3333.0, 60.0),
];

/// Bones past the paper's table.
pub const EXTRA: [usize; 3] = [480, 1920, 7680];

/// Timestep and iterations of the test.
pub const TIMESTEP: f32 = 0.01;
/// Iterations (the paper's N; the multibody method's velocity iterations).
pub const ITERATIONS: u32 = 5;

/// Simulated seconds for a row: the paper's 10 s for its own sizes, less for the large
/// ones so the whole table stays within minutes (still past the landing at ~0.3 s).
fn seconds_for(bones: usize) -> f64 {
    match bones {
        0..=120 => 10.0,
        121..=480 => 3.0,
        _ => 1.0,
    }
}

fn us_per_bone_step(t: &RunTiming, bones: usize) -> f64 {
    1e6 * t.t_real / (t.steps as f64 * bones as f64)
}

/// Log-log slope of cost against bones between two rows: 1 is linear, 2 quadratic.
pub fn growth_exponent(n1: usize, t1: f64, n2: usize, t2: f64) -> f64 {
    (t2 / t1).ln() / (n2 as f64 / n1 as f64).ln()
}

/// Runs test 11.
pub fn run(size: Size, only: &RowFilter) -> Result<Report, AppError> {
    let wanted: Vec<(usize, Option<(f64, f64)>)> = match size {
        Size::Full => PAPER
            .iter()
            .map(|&(n, p, c)| (n, Some((p, c))))
            .chain(EXTRA.iter().map(|&n| (n, None)))
            .collect(),
        Size::Quick => vec![
            (3, Some((PAPER[0].1, PAPER[0].2))),
            (6, Some((PAPER[1].1, PAPER[1].2))),
        ],
    };
    let mut table = Table::new(
        format!(
            "Test 11 (table 3): 100% * t_real/t_sim against bones, dt = {TIMESTEP} s, \
             {ITERATIONS} iterations, two joints per three bones; us = CPU microseconds per bone per step"
        ),
        &[
            "Bones",
            "paper particle",
            "particle(paper)",
            "us",
            "particle(rigid-frames)",
            "us",
            "paper constraint",
            "multibody",
            "us",
        ],
    );
    let mut rows = Vec::new();
    // (bones, t_real per step) per flavor, for the growth slope.
    let mut cost: Vec<Vec<(usize, f64)>> = vec![Vec::new(); Flavor::ALL.len()];
    for &(bones, paper) in &wanted {
        if !only.keeps(bones as f64) {
            continue;
        }
        progress(&format!("bones: {bones}"));
        let scene = scenes::figures(bones / 3, TIMESTEP, ITERATIONS);
        let seconds = match size {
            Size::Full => seconds_for(bones),
            Size::Quick => 0.05,
        };
        let runs = time_flavors(&scene, seconds, &Flavor::ALL)?;
        let us = |i: usize| format!("{:.2}", us_per_bone_step(&runs[i].1, bones));
        table.row(vec![
            bones.to_string(),
            opt(paper.map(|p| p.0), pct),
            pct_cell(&runs[0].1),
            us(0),
            pct_cell(&runs[1].1),
            us(1),
            opt(paper.map(|p| p.1), pct),
            pct_cell(&runs[2].1),
            us(2),
        ]);
        let mut row = serde_json::Map::new();
        row.insert("bones".into(), json!(bones));
        row.insert("joints".into(), json!(scene.constraints.len()));
        row.insert("paper_particle_percent".into(), json!(paper.map(|p| p.0)));
        row.insert("paper_constraint_percent".into(), json!(paper.map(|p| p.1)));
        for (i, (flavor, t)) in runs.iter().enumerate() {
            let mut j = t.to_json();
            j["us_per_bone_step"] = json!(us_per_bone_step(t, bones));
            row.insert(flavor.key().into(), j);
            cost[i].push((bones, t.t_real / t.steps as f64));
        }
        rows.push(Value::Object(row));
    }
    let mut growth = serde_json::Map::new();
    for (flavor, c) in Flavor::ALL.iter().zip(&cost) {
        // From the paper's 30 bones (where its particle method broke down) to the largest.
        let first = c.iter().find(|(n, _)| *n >= 30).or(c.first());
        if let (Some(&(n1, t1)), Some(&(n2, t2))) = (first, c.last())
            && n2 > n1
        {
            let e = growth_exponent(n1, t1, n2, t2);
            table.note(format!(
                "{}: cost grows as bones^{e:.2} from {n1} to {n2} bones",
                flavor.key()
            ));
            growth.insert(flavor.key().into(), json!(e));
        }
    }
    Ok(Report {
        json: json!({
            "bench": "bones",
            "timestep": TIMESTEP,
            "iterations": ITERATIONS,
            "rows": rows,
            "growth_exponent": growth,
        }),
        text: table.render(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn growth_exponent_of_linear_and_quadratic_costs() {
        assert!((growth_exponent(10, 1.0, 100, 10.0) - 1.0).abs() < 1e-12);
        assert!((growth_exponent(10, 1.0, 100, 100.0) - 2.0).abs() < 1e-12);
    }
}
