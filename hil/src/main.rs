//! The `rigtwin` command. Parsing and dispatch live in [`cli`]; this file only turns
//! an error into a message on stderr and a non-zero exit status.

mod cli;

use std::process::ExitCode;

use clap::Parser as _;

/// A reader that goes away (`rigtwin diagnose ... | head`) makes `println!` fail with a
/// broken pipe, which it reports as a panic. Nothing is wrong then: whatever the command
/// records is already on disk, and there is nobody left to tell. Exit quietly, as a
/// filter killed by SIGPIPE would, instead of printing a panic.
fn exit_quietly_on_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info.payload_as_str().unwrap_or("");
        if message.contains("failed printing to stdout") && message.contains("Broken pipe") {
            std::process::exit(0);
        }
        default(info);
    }));
}

fn main() -> ExitCode {
    exit_quietly_on_broken_pipe();
    let args = cli::Cli::parse();
    match cli::run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // `{:#}` prints the context chain on one line: "reading session X: file:line: ...".
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
