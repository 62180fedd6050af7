//! `ragdoll-lab bench ... --quick --json`: every bench runs end to end on tiny sizes and
//! prints the JSON shape the CLI contract promises. No timing is asserted (the machine is
//! shared and noisy); only that the figures exist, are positive and finite.

use serde_json::Value;
use std::process::Command;

fn bench(kind: &str) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_ragdoll-lab"))
        .args(["bench", kind, "--quick", "--json"])
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

/// The realtime benches (tests 10-12) share one per-method shape.
fn check_timings(row: &Value) {
    for f in FLAVORS {
        let t = &row[f];
        positive(&t["t_sim"], "t_sim");
        positive(&t["t_real"], "t_real");
        positive(&t["percent_of_realtime"], "percent_of_realtime");
        assert!(t["steps"].as_u64().unwrap() >= 1);
        assert!(t["finite"].is_boolean());
    }
}

#[test]
fn every_bench_prints_its_json_shape() {
    let m = bench("memory");
    for row in rows(&m) {
        let bones = row["bones"].as_u64().unwrap() as f64;
        positive(&row["paper_particle_bytes"], "paper bytes");
        for f in FLAVORS {
            // A method that simulates boxes holds at least a few bytes per box.
            let bytes = positive(&row[f]["bytes"], "bytes");
            let per_bone = positive(&row[f]["bytes_per_bone"], "bytes per bone");
            assert!((bytes / bones - per_bone).abs() < 1e-6);
            assert!(row[f]["peak_bytes"].as_f64().unwrap() >= bytes);
        }
    }

    let t = bench("timestep");
    for row in rows(&t) {
        positive(&row["timestep"], "timestep");
        check_timings(row);
    }

    let b = bench("bones");
    for row in rows(&b) {
        let bones = row["bones"].as_u64().unwrap();
        assert_eq!(bones % 3, 0);
        assert_eq!(row["joints"].as_u64().unwrap(), 2 * bones / 3);
        check_timings(row);
    }

    let i = bench("iterations");
    for row in rows(&i) {
        assert!(row["iterations"].as_u64().unwrap() >= 1);
        check_timings(row);
    }

    let s = bench("scale");
    let mut single = 0;
    for row in rows(&s) {
        let humans = row["humans"].as_u64().unwrap();
        let bones = row["bones"].as_u64().unwrap();
        assert_eq!(bones, 16 * humans, "16 bones per human");
        let threads = row["threads"].as_u64().unwrap();
        assert!(threads >= 1);
        for key in ["particle_ms_per_frame", "multibody_ms_per_frame"] {
            // A method that does not step on several threads has no many-thread figure.
            if threads == 1 || !row[key].is_null() {
                positive(&row[key], key);
            }
        }
        single += usize::from(threads == 1);
    }
    assert_eq!(single, 2, "one single-threaded row per pile size");
}
