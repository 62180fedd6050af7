//! Fuzzing the `.af` reader with proptest: mutated scene files never panic; they either
//! build a valid scene or give one positioned error. Failing cases proptest finds are
//! kept in `proptest-regressions/` and replayed first; crashes found while writing the
//! reader are pinned as named tests below.

mod common;

use common::mutation::Mutation;
use proptest::prelude::*;
use ragdoll_sim::scene::af::{AfOptions, parse};
use ragdoll_sim::scene::{MassSpec, validate};
use std::path::{Path, PathBuf};

fn sources() -> Vec<(String, String)> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut out = Vec::new();
    for dir in ["assets/scenes", "assets/figures"] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "af") {
                out.push((
                    p.display().to_string(),
                    std::fs::read_to_string(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

/// Tokens a mutation may insert: punctuation, keywords, bad numbers, vector forms.
const TOKENS: &[&str] = &[
    "{",
    "}",
    "(",
    ")",
    ",",
    "\"",
    "/*",
    "//",
    "\n",
    "-",
    "0",
    "-1",
    "1e39",
    "nan",
    "inf",
    "1e-40",
    "body",
    "hinge",
    "variant 2 \"v\" {",
    "settings",
    "world",
    "\"world\"",
    "joint( \"x\" )",
    "bonedir( \"a\", \"a\" )",
    "( 0, 0, 0 )",
    "( 1, 2 )",
    "box(",
    "model",
    "origin",
    "count 100",
    "replicate { count 3 }",
    "totalMass -1",
    "conelimit",
    "limit 0, -5, 0",
    "range 5, -5",
    "units \"cm\"",
    "up \"z\"",
    "fixed 1",
    "mass 0",
    "density 0",
    "particles",
    "é",
    "\u{0}",
];

/// A mutation over this reader's tokens.
fn mutation() -> impl Strategy<Value = Mutation> {
    common::mutation::strategy(TOKENS.len())
}

/// Applies mutations on char boundaries.
fn mutate(text: &str, muts: &[Mutation]) -> String {
    common::mutation::apply(text, muts, TOKENS)
}

/// The reader's contract on any text.
fn check(file: &str, text: &str, variant: u32) {
    let opts = AfOptions {
        variant,
        ..Default::default()
    };
    match parse(text, Path::new(file), &opts) {
        Ok(scene) => {
            validate(&scene.desc).expect("a scene the reader returns is valid");
            assert!(
                scene
                    .desc
                    .bodies
                    .iter()
                    .all(|b| matches!(b.mass, MassSpec::Mass(m) if m > 0.0 && m.is_finite()))
            );
        }
        Err(e) => {
            let lines = text.lines().count() as u32 + 1;
            assert!(e.line >= 1 && e.line <= lines.max(1), "{e}");
            assert!(e.col >= 1, "{e}");
            let shown = e.to_string();
            assert!(
                shown.starts_with(&format!("{file}:{}:{}: error: ", e.line, e.col)),
                "{shown}"
            );
            assert!(
                !e.message.is_empty() && !e.message.contains('\n'),
                "{shown}"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn mutated_scene_files_never_panic(
        which in any::<usize>(),
        muts in prop::collection::vec(mutation(), 1..4),
        variant in 1u32..4,
    ) {
        let srcs = sources();
        let (file, text) = &srcs[which % srcs.len()];
        check(file, &mutate(text, &muts), variant);
    }

    #[test]
    fn arbitrary_text_never_panics(text in "[ -~\n\t]{0,200}") {
        check("fuzz.af", &text, 1);
    }
}

#[test]
fn regression_deep_parentheses_do_not_overflow_the_stack() {
    check(
        "deep.af",
        &format!("settings {{ gravity {} }}", "(".repeat(100_000)),
        1,
    );
    check("deep.af", &"variant 2 \"x\" { ".repeat(10_000), 2);
}

#[test]
fn regression_huge_grid_does_not_overflow() {
    // columns × rows × layers overflowed u32 before the grid used u64 arithmetic.
    let text = "settings { units \"m\" up \"y\" }\nreplicate { count 3 columns 10000 rows 10000 layers 10000 }\nbody \"a\" { model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin ( 0, 2, 0 ) }\n";
    check("grid.af", text, 1);
}

#[test]
fn regression_every_token_in_every_place_of_a_small_file() {
    // Exhaustive over one small file: every token inserted before every character.
    let base = "settings { units \"m\" up \"y\" }\nbody \"a\" { model box( ( -1, -1, -1 ), ( 1, 1, 1 ) ) origin ( 0, 2, 0 ) }\nbody \"b\" { model bone( ( 0, 3, 0 ), ( 0, 4, 0 ), 0.5 ) }\nhinge \"h\" { body1 \"b\" body2 \"a\" anchor ( 0, 3, 0 ) axis ( 1, 0, 0 ) limit 0, 90, 0 }\n";
    for at in 0..=base.chars().count() {
        for t in 0..TOKENS.len() {
            check("small.af", &mutate(base, &[Mutation::Insert(at, t)]), 1);
        }
    }
}
