//! The multibody method solves islands on all cores (`rigid::parallel`): the result must
//! be bit for bit the same on any number of threads as on one.

use ragdoll_sim::Method;
use ragdoll_sim::method::BodyState;
use ragdoll_sim::rigid::MultibodyWorld;
use ragdoll_sim::scene::af::{AfOptions, load};
use std::path::PathBuf;

/// Steps a pile of 80 humans for 3 s on a pool of `threads` threads (`None`: rayon's
/// global pool) and returns every body's state. The pile starts as 80 separate figures,
/// so the solve is shared out over many islands, several to a batch (`rigid::parallel`
/// deals 16 batches per thread); they fall onto each other and merge into fewer, larger
/// ones, which the run also covers.
fn pile_on(threads: Option<usize>) -> Vec<BodyState> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/pile.af");
    let desc = load(
        &path,
        &AfOptions {
            count: Some(80),
            ..Default::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .desc;
    let run = || {
        let mut w = MultibodyWorld::new(&desc).unwrap();
        for _ in 0..180 {
            w.step();
        }
        let mut out = Vec::new();
        w.body_states(&mut out);
        out
    };
    match threads {
        None => run(),
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
            .install(run),
    }
}

fn bits(s: &[BodyState]) -> Vec<u32> {
    s.iter()
        .flat_map(|b| {
            [
                b.com.to_array(),
                b.linear_velocity.to_array(),
                b.angular_velocity.to_array(),
            ]
            .into_iter()
            .flatten()
            .chain(b.orientation.to_array())
        })
        .map(f32::to_bits)
        .collect()
}

#[test]
fn islands_on_any_number_of_threads_give_the_same_bits() {
    let one = pile_on(Some(1));
    assert!(
        one.iter().all(|b| b.com.is_finite()),
        "the pile must stay finite"
    );
    let reference = bits(&one);
    for threads in [Some(2), Some(3), None] {
        assert!(
            bits(&pile_on(threads)) == reference,
            "{threads:?} threads differ from one thread"
        );
    }
}
