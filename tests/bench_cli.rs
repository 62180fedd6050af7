//! `ragdoll-lab bench ... --quick --json`: every bench runs end to end on tiny sizes and
//! prints the JSON shape the CLI contract promises. No timing is asserted (the machine is
//! shared and noisy); only that the figures exist, are positive and finite.

use serde_json::Value;
use std::process::Command;

fn bench(kind: &str) -> Value {
    bench_with(kind, &[])
}

fn bench_with(kind: &str, extra: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_ragdoll-lab"))
        .args(["bench", kind, "--quick", "--json"])
        .args(extra)
        .output()
        .expect("ragdoll-lab runs");
    assert!(
        out.status.success(),
        "bench {kind} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "bench {kind} printed no JSON ({e}): {}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

fn rows(v: &Value) -> &Vec<Value> {
    let rows = v["rows"].as_array().expect("\"rows\" is an array");
    assert!(!rows.is_empty());
    rows
}

fn positive(v: &Value, what: &str) -> f64 {
    let x = v
        .as_f64()
        .unwrap_or_else(|| panic!("{what} is not a number: {v}"));
    assert!(x.is_finite() && x > 0.0, "{what} = {x}");
    x
}

const FLAVORS: [&str; 3] = ["particle_paper", "particle_rigid_frames", "multibody"];
/// The memory bench measures the XPBD solver too.
const MEMORY_FLAVORS: [&str; 4] = [
    "particle_paper",
    "particle_rigid_frames",
    "particle_xpbd",
    "multibody",
];

/// The busy-phase figures every timed run reports (`bench::busy`): the frames, the
/// first seconds (null where the run is shorter than the second), the cost per awake
/// body, returned with the mean number of bodies awake.
fn check_busy(b: &Value, bodies: f64) -> f64 {
    let p95 = positive(&b["p95_frame_ms"], "p95 frame");
    let max = positive(&b["max_frame_ms"], "slowest frame");
    assert!(p95 <= max, "p95 {p95} above the slowest frame {max}");
    let seconds = b["first_seconds_ms"].as_array().expect("first seconds");
    assert_eq!(seconds.len(), 3);
    for s in seconds {
        assert!(s.is_null() || s.as_f64().is_some_and(|x| x > 0.0), "{s}");
    }
    let awake = positive(&b["mean_awake_bodies"], "mean awake bodies");
    assert!(awake <= bodies, "{awake} awake of {bodies}");
    let peak = b["peak_awake_bodies"].as_f64().expect("peak awake");
    assert!(awake <= peak && peak <= bodies);
    positive(&b["us_per_awake_body_step"], "us per awake body step");
    awake
}

/// The realtime benches (tests 10-12) share one per-method shape.
fn check_timings(row: &Value, bodies: f64) {
    for f in FLAVORS {
        let t = &row[f];
        positive(&t["t_sim"], "t_sim");
        positive(&t["t_real"], "t_real");
        positive(&t["percent_of_realtime"], "percent_of_realtime");
        assert!(t["steps"].as_u64().unwrap() >= 1);
        assert!(t["finite"].is_boolean());
        // These scenes never sleep (bench::scenes): every body is awake in every step.
        let awake = check_busy(&t["busy"], bodies);
        assert_eq!(awake, bodies, "{f}");
    }
}

#[test]
fn every_bench_prints_its_json_shape() {
    let m = bench("memory");
    for row in rows(&m) {
        let bones = row["bones"].as_u64().unwrap() as f64;
        positive(&row["paper_particle_bytes"], "paper bytes");
        for f in MEMORY_FLAVORS {
            // A method that simulates boxes holds at least a few bytes per box.
            let bytes = positive(&row[f]["bytes"], "bytes");
            let per_bone = positive(&row[f]["bytes_per_bone"], "bytes per bone");
            assert!((bytes / bones - per_bone).abs() < 1e-6);
            assert!(row[f]["peak_bytes"].as_f64().unwrap() >= bytes);
        }
    }

    // The pile of humans, joints included.
    let piles = m["pile_rows"].as_array().expect("pile rows");
    assert!(!piles.is_empty());
    for row in piles {
        let bones = row["bones"].as_u64().unwrap() as f64;
        assert_eq!(bones, 16.0 * row["humans"].as_u64().unwrap() as f64);
        for f in MEMORY_FLAVORS {
            let bytes = positive(&row[f]["bytes"], "pile bytes");
            let per_bone = positive(&row[f]["bytes_per_bone"], "pile bytes per bone");
            assert!((bytes / bones - per_bone).abs() < 1e-6);
            // The bytes by owner account for every byte held, each once.
            let owners = row[f]["owners"].as_object().expect("owners");
            let sum: f64 = owners.values().map(|b| b.as_f64().unwrap()).sum();
            assert_eq!(sum, bytes, "{f}: owners {owners:?}");
        }
        // The multibody names its owners: a landed human holds joints and contacts.
        let owners = &row["multibody"]["owners"];
        for owner in ["body states", "joints", "contact points", "contact pairs"] {
            positive(&owners[owner], owner);
        }
    }

    let t = bench("timestep");
    for row in rows(&t) {
        positive(&row["timestep"], "timestep");
        check_timings(row, 3.0);
    }

    let b = bench("bones");
    for row in rows(&b) {
        let bones = row["bones"].as_u64().unwrap();
        assert_eq!(bones % 3, 0);
        assert_eq!(row["joints"].as_u64().unwrap(), 2 * bones / 3);
        check_timings(row, bones as f64);
    }

    let i = bench("iterations");
    for row in rows(&i) {
        assert!(row["iterations"].as_u64().unwrap() >= 1);
        check_timings(row, 9.0);
    }

    check_scale(&bench("scale"), true);
}

/// The scale table's rows; with sleeping off, every body is awake in every step.
fn check_scale(s: &Value, sleep: bool) {
    assert_eq!(s["sleep"].as_bool(), Some(sleep));
    let mut single = 0;
    for row in rows(s) {
        let humans = row["humans"].as_u64().unwrap();
        let bones = row["bones"].as_u64().unwrap();
        assert_eq!(bones, 16 * humans, "16 bones per human");
        let threads = row["threads"].as_u64().unwrap();
        assert!(threads >= 1);
        for method in ["particle", "multibody"] {
            let key = format!("{method}_ms_per_frame");
            // A method that does not step on several threads has no many-thread figure.
            if threads == 1 || !row[&key].is_null() {
                positive(&row[&key], &key);
                let awake = check_busy(&row[format!("{method}_busy")], bones as f64);
                if !sleep {
                    assert_eq!(awake, bones as f64, "{method}: a body slept");
                }
            }
        }
        single += usize::from(threads == 1);
    }
    assert_eq!(single, 2, "one single-threaded row per pile size");
}

/// `--no-sleep` reaches the table (a quick run is too short for anything to fall asleep
/// either way; that sleeping off keeps bodies awake is `ragdoll-sim/tests/sleep_off.rs`).
#[test]
fn the_scale_table_takes_sleeping_off() {
    check_scale(&bench_with("scale", &["--no-sleep"]), false);
}

/// The rain (`bench rain`): every row's cost per moving body, with the airborne bodies
/// (always awake) among the moving ones and the landed ones fewer, so that charging the
/// frames to the landed ones alone costs more per body.
#[test]
fn the_rain_reports_its_cost_per_moving_body() {
    let r = bench("rain");
    assert_eq!(r["sleep"].as_bool(), Some(true));
    let bodies = positive(&r["bodies"], "bodies");
    let humans = r["humans"].as_u64().unwrap();
    assert_eq!(bodies as u64, 16 * humans);
    assert_eq!(humans, 3 * r["groups"].as_u64().unwrap());
    let mut single = 0;
    for row in rows(&r) {
        assert!(row["method"].is_string());
        assert_eq!(row["finite"].as_bool(), Some(true));
        positive(&row["mean_ms_per_frame"], "mean ms");
        let moving = check_busy(&row["busy"], bodies);
        assert_eq!(row["mean_moving_bodies"].as_f64(), Some(moving));
        let airborne = row["mean_airborne_bodies"].as_f64().unwrap();
        assert!(
            airborne > 0.0 && airborne <= moving,
            "{airborne} of {moving}"
        );
        let all = positive(&row["us_per_moving_body_step"], "us per moving body");
        let landed = positive(
            &row["us_per_landed_moving_body_step"],
            "us per landed moving body",
        );
        assert!(landed >= all, "{landed} < {all}");
        single += usize::from(row["threads"].as_u64() == Some(1));
    }
    assert_eq!(single, 2, "both methods on one thread");
}
