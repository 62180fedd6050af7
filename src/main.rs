//! `ragdoll-lab`: particle and multibody ragdolls side by side.
//!
//! The command line is the contract with tests and users (`docs/cli.md`);
//! each subcommand lives in its own module.

use clap::Parser;
use ragdoll_lab::cli::{Cli, Command};
use std::process::ExitCode;

/// Counts live heap bytes for `bench memory` (test 9); two relaxed atomics per
/// allocation, otherwise the system allocator.
#[global_allocator]
static ALLOCATOR: ragdoll_lab::bench::memory::CountingAlloc =
    ragdoll_lab::bench::memory::CountingAlloc;

fn main() -> ExitCode {
    // egui-wgpu warns on every sRGB target; on GL (llvmpipe) that view is the only one we
    // can give it, and the colours are right, so keep its warnings out of every capture.
    env_logger::Builder::from_env(
        env_logger::Env::default().default_filter_or("warn,egui_wgpu::renderer=error"),
    )
    .init();
    let cli = Cli::parse();
    let result = match cli.command.unwrap_or(Command::View(cli.view)) {
        Command::View(args) => ragdoll_lab::view::run(args),
        Command::Capture(args) => ragdoll_lab::capture::run(args),
        Command::Stats(args) => ragdoll_lab::stats::run(args),
        Command::Check(args) => ragdoll_lab::check::run(args),
        Command::Bench(args) => ragdoll_lab::bench::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}
